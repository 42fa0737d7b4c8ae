/// @file tool_fit_ltc.cpp
/// `qsil-fit_ltc` (CMake names tools/tool_X.cpp qsil-X): fits the table of linearly transformed
/// cosines to qsil's own GGX (fit_ltc_table, qsil/edgetree/ltc_fit.h, which documents the method)
/// and prints it as the C++ initializer of edgetree/ltc_ggx_table.inc. Regenerate with
///   build/qsil-fit_ltc > edgetree/ltc_ggx_table.inc
/// (about two minutes on one core). Progress and a fit summary go to stderr.

#include "cli_parse.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/edgetree/ltc_fit.h"

#include <algorithm>
#include <cstdio>
#include <utility>
#include <vector>

using namespace qsil::edgetree;

namespace {

constexpr int NA = kLTCAlphaCount, NC = kLTCCosCount;

/// Prints the fit's accuracy on stderr; returns the mean and worst relative L1 error.
std::pair<double, double> report_fit(const std::vector<LTCFitNode>& table) {
  double worst = 0, mean = 0, worst_below = 0;
  int wi = 0, wj = 0;
  for (int i = 0; i < NA; ++i)
    for (int j = 0; j < NC; ++j) {
      const LTCFitNode& e = table[size_t(i * NC + j)];
      mean += e.l1;
      if (e.l1 > worst) {
        worst = e.l1;
        wi = i;
        wj = j;
      }
      worst_below = std::max(worst_below, e.mass_below);
    }
  mean /= NA * NC;
  std::fprintf(stderr, "relative L1 error: mean %.4f, worst %.4f at alpha %.3e cos %.4f; max mass below horizon %.3f\n",
               mean, worst, ltc_table_alpha(wi), ltc_table_cos(wj), worst_below);
  for (int i = 0; i < NA; i += 9) {
    std::fprintf(stderr, "alpha %.2e L1 by cos node:", ltc_table_alpha(i));
    for (int j = 0; j < NC; j += 9) std::fprintf(stderr, " %.3f", table[size_t(i * NC + j)].l1);
    std::fprintf(stderr, "\n");
  }
  return {mean, worst};
}

/// Prints the table as the initializer of edgetree/ltc_ggx_table.inc.
void print_table(const std::vector<LTCFitNode>& table, double mean, double worst) {
  std::printf("// edgetree/ltc_ggx_table.inc -- GENERATED, do not edit.\n");
  std::printf(
      "// LTC fit of qsil's GGX (ggx_eval_cos: separable Smith G, Fresnel 1); layout in qsil/edgetree/ltc.h.\n");
  std::printf("// Regenerate: build/qsil-fit_ltc > edgetree/ltc_ggx_table.inc  (tools/tool_fit_ltc.cpp)\n");
  std::printf("// [alpha node %d][cos node %d] = {M_inv(0,0), M_inv(0,2), M_inv(2,0), M_inv(2,2), albedo}\n", NA, NC);
  std::printf("// Fit: mean relative L1 error %.4f, worst %.4f.\n", mean, worst);
  for (int i = 0; i < NA; ++i) {
    std::printf("{ // alpha = %.6e\n", ltc_table_alpha(i));
    for (int j = 0; j < NC; ++j) {
      const LTCFitNode& e = table[size_t(i * NC + j)];
      std::printf("{%.7g,%.7g,%.7g,%.7g,%.7g},", e.m[0], e.m[1], e.m[2], e.m[3], e.m[4]);
      if (j % 4 == 3) std::printf("\n");
    }
    std::printf("},\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "qsil-fit_ltc: fits the LTC table of qsil's GGX and prints it as edgetree/ltc_ggx_table.inc "
      "(about two minutes on one core; a fit summary goes to stderr)"};
  if (const auto code = qsil::cli::parse_arguments(app, argc, argv)) return *code;
  const std::vector<LTCFitNode> table =
      fit_ltc_table([](double alpha) { std::fprintf(stderr, "alpha %.3e done\n", alpha); });
  const auto [mean, worst] = report_fit(table);
  print_table(table, mean, worst);
  return 0;
}
