/// @file cmd_render.cpp
/// `qsil render SCENE.xml [-o out.exr] [--spp N] [--seed S] [--threads T] [-D k=v]... [--preview out.png]`:
/// the primal image. Under an MPI launcher every rank renders its part and rank 0 writes the image
/// (qsil/integrators/distributed.h).

#include "cli_common.h"
#include "commands.h"
#include "qsil/preview.h"

#include <cstdio>
#include <optional>

namespace qsil::cli {
namespace {

const CommandRegistrar registrar{
    {"render", "Render the primal image of a scene to OpenEXR", [](CLI::App& app) -> std::function<int()> {
       auto flags = std::make_shared<CommonFlags>();
       add_common_flags(app, *flags, "render.exr");
       return [flags]() {
         const ProcessGroup& group = process_group();
         std::optional<Scene> scene;
         std::optional<Estimator> estimator;
         group.all_or_none([&] {
           scene.emplace(load_scene_with_flags(flags->scene, flags->defines));
           estimator.emplace(*scene, EstimatorConfig::primal());
         });
         const RenderResult r = group.run(*estimator, flags->render);
         const uint64_t invalid_rays = group_invalid_rays();
         on_root([&] {
           Image img = r.film.to_image();
           add_render_attributes(img, *flags, r);
           write_exr(flags->output, img);
           if (!flags->preview.empty()) write_preview_png(flags->preview, img, flags->exposure);
           report_nonfinite(r, invalid_rays);
           std::printf("render: %s %dx%d, %d spp%s, %.3f s, %.2f Mrays/s -> %s\n", flags->scene.c_str(), img.width,
                       img.height, r.spp, processes_note().c_str(), r.seconds, mrays_per_second(r),
                       flags->output.c_str());
         });
         return 0;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
