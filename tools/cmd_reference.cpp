/// @file cmd_reference.cpp
/// `qsil reference SCENE.xml --param SPEC... --method quadric|fd|... --spp N [--h H] -o ref.exr`:
/// a high-spp gradient image for `qsil compare`, with each channel's per-pixel standard error
/// stored beside it (channel NAME.se), so that comparisons can state the reference's own noise.
/// Under an MPI launcher every rank renders its part and rank 0 writes the image (the sums and
/// squared sums behind the .se channels are those of one process, bit for bit).

#include "cli_common.h"
#include "commands.h"
#include "qsil/study/reference.h"
#include "qsil/preview.h"

#include <cstdio>
#include <optional>

namespace qsil::cli {
namespace {

struct Flags : CommonFlags {
  std::vector<std::string> params;
  BoundaryFlags boundary;  ///< method: --method (an edge sampler or fd)
  std::vector<double> h;
};

/// Writes the reference EXR (and preview) of run `r` and prints its summary (rank 0).
void write_reference(const Flags& flags, const std::vector<ParameterSpec>& params, const Estimator& estimator,
                     const RenderResult& r, uint64_t invalid_rays) {
  const int K = int(params.size());
  report_nonfinite(r, invalid_rays);
  Reference ref;
  ref.image = reference_image(r);
  ref.num_params = K;
  add_render_attributes(ref.image, flags, r);
  ref.image.attributes["qsil:method"] = "reference/" + flags.boundary.method;
  for (int k = 0; k < K; ++k) ref.image.attributes["qsil:param" + std::to_string(k)] = params[size_t(k)].text;
  for (size_t k = 0; k < estimator.fd_steps().size(); ++k)
    ref.image.attributes["qsil:h" + std::to_string(k)] = std::to_string(estimator.fd_steps()[k]);
  write_exr(flags.output, ref.image);
  if (!flags.preview.empty()) write_preview_png(flags.preview, ref.image, flags.exposure);
  summarize_reference(ref);
  std::printf(
      "reference: %s %dx%d, %d spp%s, %d parameter(s), method %s, %.3f s, %.2f Mrays/s, "
      "noise floor (mean se^2) %.4g = %.3g x mean(ref^2) -> %s\n",
      flags.scene.c_str(), r.film.width(), r.film.height(), r.spp, processes_note().c_str(), K, flags.boundary.method.c_str(),
      r.seconds + estimator.setup().seconds, mrays_per_second(r), ref.noise_floor,
      ref.mean_sq > 0 ? ref.noise_floor / ref.mean_sq : 0.0, flags.output.c_str());
  for (int k = 0; k < K; ++k) {
    const ImageSum s = r.film.derivative_sum(k);
    std::printf("  dtheta%d (%s): image sum %.6g +- %.3g (1 s.e.%s)\n", k, params[size_t(k)].text.c_str(),
                ref.sum[size_t(k)], ref.sum_se[size_t(k)], largest_share_note(s).c_str());
    // A reference judges other estimates: one carried by a pixel's few samples cannot.
    warn_if_dominant_pixel("reference", k, s, r.film, false);
  }
}

const CommandRegistrar registrar{
    {"reference", "Render a high-spp reference gradient with per-pixel standard errors",
     [](CLI::App& app) -> std::function<int()> {
       auto flags = std::make_shared<Flags>();
       add_common_flags(app, *flags, "reference.exr");
       add_param_option(app, flags->params);
       add_boundary_flags(app, flags->boundary, "--method",
                          "Unbiased estimator: quadric, quadric-box, vsphere, vsphere-solid, uniform (boundary term "
                          "of `qsil grad`), or fd (central finite differences; biased by O(h^2))",
                          false);
       add_fd_step_option(app, flags->h);
       return [flags]() {
         const ProcessGroup& group = process_group();
         SceneEstimator set_up;
         set_up_estimator(*flags, flags->params, [&](const Scene& scene, const std::vector<ParameterSpec>& params) {
           const Method method = parse_method(flags->boundary.method, "--method", kReferenceMethods);
           return method == Method::FiniteDifferences
                      ? EstimatorConfig::finite_differences(params, fd_steps(scene, params, flags->h))
                      : gradient_config(scene, params, method, flags->boundary);
         }, set_up);
         // One run with the progress bar (a reference is one long run, not passes).
         const RenderResult r = group.run(*set_up.estimator, flags->render);
         const uint64_t invalid_rays = group_invalid_rays();
         on_root([&] { write_reference(*flags, set_up.params, *set_up.estimator, r, invalid_rays); });
         return 0;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
