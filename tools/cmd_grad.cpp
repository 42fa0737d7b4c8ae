/// @file cmd_grad.cpp
/// `qsil grad SCENE.xml --param SPEC... [--spp N] [--seed S] [--boundary none] [-o grad.exr]
/// [--preview-dir DIR]`: the primal image and its derivatives with respect to geometry parameters
/// (interior term in forward mode + boundary term), from the same paths.

#include "cli_common.h"
#include "commands.h"
#include "qsil/error.h"

#include <cstdio>

namespace qsil::cli {
namespace {

const CommandRegistrar registrar{{"grad", "Render an image and its derivatives with respect to geometry parameters",
  [](CLI::App& app) -> std::function<int()> {
    struct Flags : CommonFlags {
      std::vector<std::string> params;
      std::string boundary = "quadric";
      int boundary_spp = 1;
      std::string preview_dir;
    };
    auto flags = std::make_shared<Flags>();
    add_common_flags(app, *flags, "grad.exr");
    app.add_option("--param", flags->params,
                   "Parameter (repeatable, 1-8): ID:translate:X,Y,Z | ID:rotate:X,Y,Z[@CX,CY,CZ] (radians) | "
                   "ID:scale[@CX,CY,CZ] (relative) | ID:vertex:INDEX:X,Y,Z; ID is the shape's XML id")
        ->required()
        ->allow_extra_args(false);
    app.add_option("--boundary", flags->boundary,
                   "Boundary-term estimator: quadric (edge forest, dual box + bounding quadrics [QSS]), "
                   "quadric-box (dual box only), vsphere (Li 2019's Hough-space tree, hollow v-sphere test), "
                   "vsphere-solid (redner's original solid v-sphere test), uniform (no rejection, length x "
                   "dihedral angle), none (interior term only: misses silhouettes, shadows, outlines)")
        ->capture_default_str();
    app.add_option("--boundary-spp", flags->boundary_spp, "Discontinuity samples per shading point")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--preview-dir", flags->preview_dir, "Write primal.png and one diverging PNG per parameter here");
    return [flags]() {
      GradientOptions gopt;
      gopt.boundary = parse_boundary_method(flags->boundary);
      gopt.boundary_spp = flags->boundary_spp;
      const Scene scene = load_scene_with_flags(*flags);
      const auto params = parse_parameters(flags->params, scene);
      GradientReport rep;
      const RenderResult r = render_gradient(scene, params, flags->render, gopt, &rep);
      report_nonfinite(r);
      std::printf("grad: %s %dx%d, %d spp, %zu parameter(s), boundary %s, %.3f s (interior %.3f s, boundary %.3f s, "
                  "forest %.3f s), %.2f Mrays/s, %llu traversals, %.1f%% zero-contribution -> %s\n",
                  flags->scene.c_str(), r.film.width(), r.film.height(), r.spp, params.size(), flags->boundary.c_str(),
                  r.seconds + rep.forest_seconds, r.seconds - rep.boundary_seconds, rep.boundary_seconds,
                  rep.forest_seconds, r.seconds > 0 ? double(r.rays) / r.seconds * 1e-6 : 0.0,
                  (unsigned long long)rep.traversals,
                  rep.traversals ? 100.0 * double(rep.zero_traversals) / double(rep.traversals) : 0.0,
                  flags->output.c_str());
      write_gradient_outputs(*flags, params, r, flags->preview_dir, "grad/" + flags->boundary);
      return 0;
    };
  }}};

}  // namespace
}  // namespace qsil::cli
