/// @file cmd_fd.cpp
/// `qsil fd SCENE.xml --param SPEC... [--h H] [--spp N]`: central finite differences with common
/// random numbers, in the same EXR layout as `qsil grad`; the reference for every gradient test.

#include "cli_common.h"
#include "commands.h"
#include "qsil/error.h"

#include <cstdio>

namespace qsil::cli {
namespace {

const CommandRegistrar registrar{{"fd", "Finite-difference derivatives (central, common random numbers)",
  [](CLI::App& app) -> std::function<int()> {
    struct Flags : CommonFlags {
      std::vector<std::string> params;
      std::vector<double> h;
      std::string preview_dir;
    };
    auto flags = std::make_shared<Flags>();
    add_common_flags(app, *flags, "fd.exr");
    app.add_option("--param", flags->params, "Parameter (repeatable, 1-8), as for `qsil grad`")->required()->allow_extra_args(false);
    app.add_option("--h", flags->h,
                   "Step per parameter (one value for all, or one per --param). Default: translate/vertex "
                   "1e-3 x scene bounding-box diagonal / |direction| (scene units of theta); rotate 1e-3 rad; "
                   "scale 1e-3 (relative)")
        ->allow_extra_args(false);
    app.add_option("--preview-dir", flags->preview_dir, "Write primal.png and one diverging PNG per parameter here");
    return [flags]() {
      const Scene scene = load_scene_with_flags(*flags);
      const auto params = parse_parameters(flags->params, scene);
      std::vector<double> steps;
      for (size_t k = 0; k < params.size(); ++k) {
        if (flags->h.empty()) steps.push_back(default_fd_step(scene, params[k]));
        else if (flags->h.size() == 1) steps.push_back(flags->h[0]);
        else if (flags->h.size() == params.size()) steps.push_back(flags->h[k]);
        else throw Error("--h: give one value or one per --param (" + std::to_string(params.size()) + ")");
      }
      const RenderResult r = render_finite_differences(scene, params, steps, flags->render);
      report_nonfinite(r);
      std::printf("fd: %s %dx%d, %d spp, %zu parameter(s), %.3f s -> %s\n", flags->scene.c_str(), r.film.width(),
                  r.film.height(), r.spp, params.size(), r.seconds, flags->output.c_str());
      for (size_t k = 0; k < steps.size(); ++k) std::printf("  h%zu = %.6g\n", k, steps[k]);
      write_gradient_outputs(*flags, params, r, flags->preview_dir, "fd");
      return 0;
    };
  }}};

}  // namespace
}  // namespace qsil::cli
