/// @file cmd_agree.cpp
/// `qsil agree A.exr B.exr [--block 8]`: whether two independent references (`qsil reference`
/// outputs, with NAME.se channels) of the same scene and parameters estimate the same images:
/// image-sum and block z-tests (qsil::agreement, qsil/study/reference.h). Exit 0 if they
/// agree, 1 if not, 2 on bad input (missing file, different sizes or parameters).

#include "cli_common.h"
#include "commands.h"
#include "qsil/error.h"
#include "qsil/film.h"
#include "qsil/study/reference.h"

#include <cstdio>

namespace qsil::cli {
namespace {

/// A reference EXR with as many parameters as it has dtheta<k>.R.se channels (at least one).
Reference read_any_reference(const std::string& path) {
  const Image probe = read_exr(path);
  int K = 0;
  while (K < 8 && probe.channel_index(FilmLayout::derivative_name(K, 0) + ".se") >= 0) ++K;
  if (K == 0) throw Error(path + ": no channel dtheta0.R.se (render references with `qsil reference`)");
  return read_reference(path, K, probe.width, probe.height);
}

std::string attribute(const Reference& r, const std::string& name) {
  const auto it = r.image.attributes.find(name);
  return it == r.image.attributes.end() ? "?" : it->second;
}

const CommandRegistrar registrar{
    {"agree", "Test whether two independent reference gradients agree (image-sum and block z-tests)",
     [](CLI::App& app) -> std::function<int()> {
       struct Flags {
         std::string a, b;
         int block = 8;
       };
       auto flags = std::make_shared<Flags>();
       app.add_option("A", flags->a, "First reference EXR (qsil reference)")->required();
       app.add_option("B", flags->b, "Second reference EXR, rendered independently (another seed or method)")
           ->required();
       app.add_option("--block", flags->block, "Block size in pixels of the block z-tests")
           ->capture_default_str()
           ->check(qsil::cli::positive_number());
       return [flags]() {
         const Reference a = read_any_reference(flags->a), b = read_any_reference(flags->b);
         for (int k = 0; k < std::min(a.num_params, b.num_params); ++k) {
           const std::string pa = attribute(a, "qsil:param" + std::to_string(k));
           const std::string pb = attribute(b, "qsil:param" + std::to_string(k));
           if (pa != pb)
             throw Error(flags->b + ": parameter " + std::to_string(k) + " is '" + pb + "', " + flags->a + " has '" +
                         pa + "'");
         }
         const Agreement g = agreement(a, b, flags->block);
         std::printf("agree: %s (%s, %s spp) vs %s (%s, %s spp), %dx%d\n", flags->a.c_str(),
                     attribute(a, "qsil:method").c_str(), attribute(a, "qsil:spp").c_str(), flags->b.c_str(),
                     attribute(b, "qsil:method").c_str(), attribute(b, "qsil:spp").c_str(), a.image.width,
                     a.image.height);
         for (int k = 0; k < a.num_params; ++k)
           std::printf("  dtheta%d image sum: %.6g +- %.3g vs %.6g +- %.3g, z %.2f\n", k, a.sum[size_t(k)],
                       a.sum_se[size_t(k)], b.sum[size_t(k)], b.sum_se[size_t(k)], g.sum_z[size_t(k)]);
         std::printf(
             "  %dx%d blocks: %lld tests, chi2/dof %.3f (limit %.3f), max |z| %.2f, %.2f%% with |z| > 3, %lld "
             "zero-variance blocks unequal, %lld tests of blocks one reference never sampled (chi2/dof %.3f without "
             "them, limit %.3f)\n",
             g.block, g.block, g.tests, g.chi2_per_dof, g.chi2_limit(), g.max_abs_z, 100 * g.frac_above_3,
             g.unequal_exact, g.unseen, g.chi2_per_dof_seen, g.chi2_limit_seen());
         std::printf(
             "  per-pixel squared difference beyond noise: %.4g +- %.2g x mean square (noise removed: %.4g)\n",
             g.excess_rel_mse, g.excess_se, g.noise_rel_mse);
         std::printf("agree: %s\n", g.agrees() ? "yes" : "NO");
         return g.agrees() ? 0 : 1;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
