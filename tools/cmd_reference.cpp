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
  std::string method = "quadric";
  std::vector<double> h;
  double sppi = 0;
  double sppp = kDefaultSppp;
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
  ref.image.attributes["qsil:method"] = "reference/" + flags.method;
  for (int k = 0; k < K; ++k) ref.image.attributes["qsil:param" + std::to_string(k)] = params[size_t(k)].text;
  for (size_t k = 0; k < estimator.fd_steps().size(); ++k)
    ref.image.attributes["qsil:h" + std::to_string(k)] = std::to_string(estimator.fd_steps()[k]);
  write_exr(flags.output, ref.image);
  if (!flags.preview.empty()) write_preview_png(flags.preview, ref.image, flags.exposure);
  summarize_reference(ref);
  std::printf(
      "reference: %s %dx%d, %d spp%s, %d parameter(s), method %s, %.3f s, %.2f Mrays/s, "
      "noise floor (mean se^2) %.4g = %.3g x mean(ref^2) -> %s\n",
      flags.scene.c_str(), r.film.width(), r.film.height(), r.spp, processes_note().c_str(), K, flags.method.c_str(),
      r.seconds + estimator.setup().seconds, mrays_per_second(r), ref.noise_floor,
      ref.mean_sq > 0 ? ref.noise_floor / ref.mean_sq : 0.0, flags.output.c_str());
  for (int k = 0; k < K; ++k)
    std::printf("  dtheta%d (%s): image sum %.6g +- %.3g (1 s.e.)\n", k, params[size_t(k)].text.c_str(),
                ref.sum[size_t(k)], ref.sum_se[size_t(k)]);
}

const CommandRegistrar registrar{
    {"reference", "Render a high-spp reference gradient with per-pixel standard errors",
     [](CLI::App& app) -> std::function<int()> {
       auto flags = std::make_shared<Flags>();
       add_common_flags(app, *flags, "reference.exr");
       add_param_option(app, flags->params);
       app.add_option("--method", flags->method,
                      "Unbiased estimator: quadric, quadric-box, vsphere, vsphere-solid, uniform (boundary term "
                      "of `qsil grad`), or fd (central finite differences; biased by O(h^2))")
           ->capture_default_str();
       add_fd_step_option(app, flags->h);
       add_sppi_option(app, flags->sppi);
       add_sppp_option(app, flags->sppp);
       return [flags]() {
         const ProcessGroup& group = process_group();
         std::optional<Scene> scene;
         std::optional<Estimator> estimator;
         std::vector<ParameterSpec> params;
         group.all_or_none([&] {
           const Method method = parse_method(flags->method, "--method", kReferenceMethods);
           scene.emplace(load_scene_with_flags(flags->scene, flags->defines));
           params = parse_parameters(flags->params, *scene);
           estimator.emplace(
               *scene, method == Method::FiniteDifferences
                           ? EstimatorConfig::finite_differences(params, fd_steps(*scene, params, flags->h))
                           : EstimatorConfig::gradient(params, method, flags->sppi, flags->sppp));
         });
         // One run with the progress bar (a reference is one long run, not passes).
         const RenderResult r = group.run(*estimator, flags->render);
         const uint64_t invalid_rays = group_invalid_rays();
         on_root([&] { write_reference(*flags, params, *estimator, r, invalid_rays); });
         return 0;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
