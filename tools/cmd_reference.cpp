/// @file cmd_reference.cpp
/// `qsil reference SCENE.xml --param SPEC... --method quadric|fd|... --spp N [--h H] -o ref.exr`:
/// a high-spp gradient image for `qsil compare`, with each channel's per-pixel standard error
/// stored beside it (channel NAME.se), so that comparisons can state the reference's own noise.

#include "cli_common.h"
#include "cli_compare.h"
#include "commands.h"
#include "qsil/error.h"

#include <cstdio>

namespace qsil::cli {
namespace {

const CommandRegistrar registrar{{"reference", "Render a high-spp reference gradient with per-pixel standard errors",
  [](CLI::App& app) -> std::function<int()> {
    struct Flags : CommonFlags {
      std::vector<std::string> params;
      std::string method = "quadric";
      std::vector<double> h;
      int boundary_spp = 1;
    };
    auto flags = std::make_shared<Flags>();
    add_common_flags(app, *flags, "reference.exr");
    app.add_option("--param", flags->params, "Parameter (repeatable, 1-8), as for `qsil grad`")
        ->required()
        ->allow_extra_args(false);
    app.add_option("--method", flags->method,
                   "Unbiased estimator: quadric, quadric-box, vsphere, vsphere-solid, uniform (boundary term "
                   "of `qsil grad`), or fd (central finite differences; biased by O(h^2))")
        ->capture_default_str();
    app.add_option("--h", flags->h, "FD step per parameter (one for all, or one per --param); default as `qsil fd`")
        ->allow_extra_args(false);
    app.add_option("--boundary-spp", flags->boundary_spp, "Discontinuity samples per shading point")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    return [flags]() {
      const GradientMethod method = parse_gradient_method(flags->method);
      if (!method.fd && method.boundary == BoundaryMethod::None)
        throw Error("--method none omits the boundary term: not a reference");
      const Scene scene = load_scene_with_flags(*flags);
      const auto params = parse_parameters(flags->params, scene);
      const std::vector<double> steps = fd_steps(scene, params, flags->h);
      auto totals = std::make_shared<PassTotals>();
      // One render with the progress bar (a reference is one long run, not passes).
      const RenderResult r = make_gradient_pass(scene, params, method, steps, flags->boundary_spp, totals)(flags->render);
      report_nonfinite(r);
      const int K = int(params.size());
      Image img = reference_image(r, K);
      add_render_attributes(img, *flags, r);
      img.attributes["qsil:method"] = "reference/" + flags->method;
      for (int k = 0; k < K; ++k) img.attributes["qsil:param" + std::to_string(k)] = params[k].text;
      if (method.fd)
        for (int k = 0; k < K; ++k) img.attributes["qsil:h" + std::to_string(k)] = std::to_string(steps[k]);
      write_exr(flags->output, img);
      if (!flags->preview.empty()) write_preview_png(flags->preview, img, flags->exposure);

      Reference ref;
      ref.image = img;
      ref.num_params = K;
      summarize_reference(ref);
      std::printf("reference: %s %dx%d, %d spp, %zu parameter(s), method %s, %.3f s, %.2f Mrays/s, "
                  "noise floor (mean se^2) %.4g = %.3g x mean(ref^2) -> %s\n",
                  flags->scene.c_str(), r.film.width(), r.film.height(), r.spp, params.size(), flags->method.c_str(),
                  r.seconds + totals->report.forest_seconds, r.seconds > 0 ? double(r.rays) / r.seconds * 1e-6 : 0.0,
                  ref.noise_floor, ref.mean_sq > 0 ? ref.noise_floor / ref.mean_sq : 0.0, flags->output.c_str());
      for (int k = 0; k < K; ++k)
        std::printf("  dtheta%d (%s): image sum %.6g +- %.3g (1 s.e.)\n", k, params[k].text.c_str(), ref.sum[k],
                    ref.sum_se[k]);
      return 0;
    };
  }}};

}  // namespace
}  // namespace qsil::cli
