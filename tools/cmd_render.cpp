/// @file cmd_render.cpp
/// `qsil render SCENE.xml [-o out.exr] [--spp N] [--seed S] [--threads T] [-D k=v]... [--preview out.png]`:
/// the primal image.

#include "cli_common.h"
#include "commands.h"
#include "qsil/preview.h"

#include <cstdio>

namespace qsil::cli {
namespace {

const CommandRegistrar registrar{
    {"render", "Render the primal image of a scene to OpenEXR", [](CLI::App& app) -> std::function<int()> {
       auto flags = std::make_shared<CommonFlags>();
       add_common_flags(app, *flags, "render.exr");
       return [flags]() {
         const Scene scene = load_scene_with_flags(flags->scene, flags->defines);
         const Estimator estimator(scene, EstimatorConfig::primal());
         const RenderResult r = estimator.run(flags->render);
         Image img = r.film.to_image();
         add_render_attributes(img, *flags, r);
         write_exr(flags->output, img);
         if (!flags->preview.empty()) write_preview_png(flags->preview, img, flags->exposure);
         report_nonfinite(r);
         std::printf("render: %s %dx%d, %d spp, %.3f s, %.2f Mrays/s -> %s\n", flags->scene.c_str(), img.width,
                     img.height, r.spp, r.seconds, mrays_per_second(r), flags->output.c_str());
         return 0;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
