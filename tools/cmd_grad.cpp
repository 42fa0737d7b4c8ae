/// @file cmd_grad.cpp
/// `qsil grad SCENE.xml --param SPEC... [--spp N] [--seed S] [--boundary METHOD] [-o grad.exr]
/// [--preview-dir DIR]`: the primal image and its derivatives with respect to geometry parameters
/// (interior term in forward mode + boundary term), from the same paths. Under an MPI launcher
/// every rank renders its part and rank 0 writes the image (qsil/integrators/distributed.h).

#include "cli_common.h"
#include "commands.h"
#include "largest_samples.h"

#include <cstdio>
#include <optional>

namespace qsil::cli {
namespace {

const CommandRegistrar registrar{
    {"grad", "Render an image and its derivatives with respect to geometry parameters",
     [](CLI::App& app) -> std::function<int()> {
       struct Flags : CommonFlags {
         std::vector<std::string> params;
         BoundaryFlags boundary;
         std::string preview_dir;
         std::string largest_csv;
       };
       auto flags = std::make_shared<Flags>();
       add_common_flags(app, *flags, "grad.exr");
       add_param_option(app, flags->params);
       add_boundary_flags(app, flags->boundary, "--boundary",
                          "Boundary-term estimator: quadric (edge forest, dual box + bounding quadrics [QSS]), "
                          "quadric-box (dual box only), vsphere (Li 2019's Hough-space tree, hollow v-sphere test), "
                          "vsphere-solid (redner's original solid v-sphere test), uniform (no rejection, length x "
                          "dihedral angle), none (interior term only: misses silhouettes, shadows, outlines), "
                          "regularized (Quinn 2021's blurred visibility, interior term only; biased: --reg-width), "
                          "was (Bangaru 2020's warped-area sampling: every direction warped, no edges; biased "
                          "for a fixed --was-rays, unbiased with --was-unbiased)",
                          true);
       app.add_option("--preview-dir", flags->preview_dir, "Write primal.png and one diverging PNG per parameter here");
       app.add_option("--largest-samples", flags->render.largest_samples,
                      "Report the K samples of largest |derivative| and their paths, vertex by vertex (term, "
                      "cosines, slide dt/dtheta, what each vertex adds): where a heavy tail comes from")
           ->check(CLI::NonNegativeNumber);
       app.add_option("--largest-samples-csv", flags->largest_csv,
                      "Also write that report as CSV (one row per path vertex) to this file");
       return [flags]() {
         const ProcessGroup& group = process_group();
         if (flags->render.largest_samples > 0 && group.size() > 1)
           throw Error("--largest-samples: not under an MPI launcher (each rank sees only its own pixels)");
         if (!flags->largest_csv.empty() && flags->render.largest_samples == 0)
           throw Error("--largest-samples-csv needs --largest-samples K with K > 0");
         SceneEstimator set_up;
         set_up_estimator(*flags, flags->params, [&](const Scene& scene, const std::vector<ParameterSpec>& params) {
           return gradient_config(scene, params, parse_method(flags->boundary.method, "--boundary", kBoundaryMethods),
                                  flags->boundary);
         }, set_up);
         const std::optional<Estimator>& estimator = set_up.estimator;
         const RenderResult r = group.run(*estimator, flags->render);
         const uint64_t invalid_rays = group_invalid_rays();
         on_root([&] {
           report_nonfinite(r, invalid_rays);
           const SetupReport& setup = estimator->setup();
           std::printf(
               "grad: %s %dx%d, %d spp%s, %zu parameter(s), boundary %s, %.3f s (set-up %.3f s, interior %.3f s, "
               "boundary %.3f s), %.2f Mrays/s, %llu traversals, %.1f%% zero-contribution -> %s\n",
               flags->scene.c_str(), r.film.width(), r.film.height(), r.spp, processes_note().c_str(),
               estimator->config().params.size(), flags->boundary.method.c_str(), setup.seconds + r.seconds, setup.seconds,
               r.seconds - r.boundary_seconds, r.boundary_seconds, mrays_per_second(r),
               (unsigned long long)r.traversals,
               r.traversals ? 100.0 * double(r.zero_traversals) / double(r.traversals) : 0.0, flags->output.c_str());
           std::printf("  set-up: %s\n", setup.describe().c_str());
           write_gradient_outputs(*flags, estimator->config().params, r, flags->preview_dir, "grad",
                                  "grad/" + flags->boundary.method);
           if (flags->render.largest_samples > 0) {
             print_largest_samples(*set_up.scene, estimator->config().params, r.largest);
             if (!flags->largest_csv.empty()) write_largest_samples_csv(flags->largest_csv, *set_up.scene, r.largest);
           }
         });
         return 0;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
