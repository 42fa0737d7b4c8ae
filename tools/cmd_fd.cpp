/// @file cmd_fd.cpp
/// `qsil fd SCENE.xml --param SPEC... [--h H] [--spp N]`: central finite differences with common
/// random numbers, in the same EXR layout as `qsil grad`; the reference for every gradient test.
/// Under an MPI launcher every rank renders its part and rank 0 writes the image.

#include "cli_common.h"
#include "commands.h"

#include <cstdio>
#include <optional>

namespace qsil::cli {
namespace {

const CommandRegistrar registrar{
    {"fd", "Finite-difference derivatives (central, common random numbers)", [](CLI::App& app) -> std::function<int()> {
       struct Flags : CommonFlags {
         std::vector<std::string> params;
         std::vector<double> h;
         std::string preview_dir;
         double reg_width = 0;
       };
       auto flags = std::make_shared<Flags>();
       add_common_flags(app, *flags, "fd.exr");
       add_param_option(app, flags->params);
       add_fd_step_option(app, flags->h);
       app.add_option("--preview-dir", flags->preview_dir, "Write primal.png and one diverging PNG per parameter here");
       add_regularization_options(app, flags->reg_width,
                                  "(given: the differences of the regularised image, the oracle of grad --boundary "
                                  "regularized; default: none)");
       return [flags]() {
         const ProcessGroup& group = process_group();
         SceneEstimator set_up;
         set_up_estimator(*flags, flags->params, [&](const Scene& scene, const std::vector<ParameterSpec>& params) {
           EstimatorConfig config = EstimatorConfig::finite_differences(params, fd_steps(scene, params, flags->h));
           if (flags->reg_width > 0)
             config.regularization = Regularization::for_scene(scene, flags->reg_width);
           return config;
         }, set_up);
         const std::vector<ParameterSpec>& params = set_up.params;
         const std::optional<Estimator>& estimator = set_up.estimator;
         const RenderResult r = group.run(*estimator, flags->render);
         const uint64_t invalid_rays = group_invalid_rays();
         on_root([&] {
           report_nonfinite(r, invalid_rays);
           std::printf("fd: %s %dx%d, %d spp%s, %zu parameter(s), %.3f s (set-up %.3f s) -> %s\n", flags->scene.c_str(),
                       r.film.width(), r.film.height(), r.spp, processes_note().c_str(), params.size(),
                       estimator->setup().seconds + r.seconds, estimator->setup().seconds, flags->output.c_str());
           for (size_t k = 0; k < params.size(); ++k) std::printf("  h%zu = %.6g\n", k, estimator->fd_steps()[k]);
           write_gradient_outputs(*flags, params, r, flags->preview_dir, "fd", "fd");
         });
         return 0;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
