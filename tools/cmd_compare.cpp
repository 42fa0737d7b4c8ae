/// @file cmd_compare.cpp
/// `qsil compare SCENE.xml --param SPEC --methods quadric,quadric-box,vsphere,uniform,fd
/// --budgets 1,2,4 [--reference REF.exr] [--spp-list 4,16] [--h H] --out DIR`: equal-time (or
/// equal-sample) comparison of gradient methods against a reference (run_compare,
/// qsil/study/compare.h). Writes DIR/results.csv, DIR/results.json, DIR/images/ and calls
/// tools/plot_compare.py DIR for error_vs_time.png and grid.png.

#include "cli_common.h"
#include "commands.h"
#include "qsil/error.h"
#include "qsil/study/compare.h"

#include <cstdio>
#include <iostream>

namespace qsil::cli {
namespace {

struct Flags {
  std::string scene;
  std::vector<std::string> defines;
  std::vector<std::string> params;
  std::vector<std::string> methods{"quadric", "quadric-box", "vsphere", "uniform", "fd"};
  std::vector<double> budgets;
  std::vector<int> spp_list;
  std::string reference;
  std::vector<double> h;
  double sppi = 0;
  double sppp = kDefaultSppp;
  double reg_width = 1e-3;
  WarpedAreaSampling warped_area;
  ProjectiveGuiding projective_guiding;
  ForestGuiding forest_guiding;
  std::string out;
  double reference_factor = 8;
  uint64_t seed = 0;
  int threads = 0;
  bool quiet = false;
  bool no_plot = false;
  std::string scripts_dir;
};

void add_options(CLI::App& app, Flags& f) {
  add_scene_options(app, f.scene, f.defines);
  app.add_option("--seed", f.seed, "Base random seed (each method, budget and the reference derive their own)")
      ->check(qsil::cli::non_negative_number());
  app.add_option("--threads", f.threads, "Worker threads (0 = all cores)")->check(qsil::cli::non_negative_number());
  app.add_flag("-q,--quiet", f.quiet, "No per-run progress lines");
  add_param_option(app, f.params);
  app.add_option("--methods", f.methods, "Comma-separated methods: " + method_list(kAllMethods))
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--budgets", f.budgets, "Comma-separated wall-clock budgets in seconds (equal-time mode)")
      ->delimiter(',')
      ->check(qsil::cli::positive_number());
  app.add_option("--spp-list", f.spp_list, "Comma-separated spp counts (equal-sample mode, instead of --budgets)")
      ->delimiter(',')
      ->check(qsil::cli::positive_number());
  app.add_option("--reference", f.reference,
                 "Reference EXR from `qsil reference` (same scene, -D and --param). Without it, a quadric "
                 "reference is rendered first for --reference-factor x the largest budget (or spp) and saved "
                 "as DIR/reference.exr");
  app.add_option("--reference-factor", f.reference_factor,
                 "Budget (or spp) of the automatic reference relative to the largest budget")
      ->capture_default_str()
      ->check(qsil::cli::positive_number());
  add_fd_step_option(app, f.h);
  add_sample_rate_options(app, f.sppi, f.sppp);
  add_regularization_options(app, f.reg_width, "for --methods regularized");
  add_warped_area_options(app, f.warped_area, "--methods was");
  add_projective_guiding_options(app, f.projective_guiding, "--methods projective");
  add_forest_guiding_options(app, f.forest_guiding, "--methods quadric, quadric-box");
  app.add_option("--out", f.out, "Output directory")->required();
  app.add_flag("--no-plot", f.no_plot, "Do not call plot_compare.py (the charts)");
  add_scripts_dir_option(app, f.scripts_dir);
}

CompareOptions compare_options(const Flags& f) {
  if (f.budgets.empty() == f.spp_list.empty()) throw Error("give exactly one of --budgets and --spp-list");
  CompareOptions o;
  o.scene = f.scene;
  o.defines = f.defines;
  for (const std::string& m : f.methods) o.methods.push_back(parse_method(m, "--methods", kAllMethods));
  o.equal_time = !f.budgets.empty();
  o.targets = o.equal_time ? f.budgets : std::vector<double>(f.spp_list.begin(), f.spp_list.end());
  o.reference = f.reference;
  o.reference_factor = f.reference_factor;
  o.h = f.h;
  o.sppi = f.sppi;
  o.sppp = f.sppp;
  o.reg_width = f.reg_width;
  o.warped_area = f.warped_area;
  o.projective_guiding = f.projective_guiding;
  o.forest_guiding = f.forest_guiding;
  o.out = f.out;
  o.seed = f.seed;
  o.threads = f.threads;
  return o;
}

/// The summary on stdout: relative MSE per method at the largest target.
void print_summary(const CompareReport& rep, const CompareOptions& o, const std::vector<ParameterSpec>& params) {
  const Reference& ref = rep.reference;
  std::printf("compare: %s, %s, %zu method(s) x %zu %s, reference %s (rel. noise floor %.3g) -> %s\n", o.scene.c_str(),
              params[0].text.c_str(), o.methods.size(), rep.targets.size(), o.equal_time ? "budget(s)" : "spp count(s)",
              rep.reference_description.c_str(), ref.noise_floor / ref.mean_sq, (o.out / "results.csv").c_str());
  for (const CompareSetup& s : rep.setups)
    std::printf("  %-14s set-up once: %s\n", std::string(method_name(s.method)).c_str(), s.report.describe().c_str());
  for (const CompareRow& r : rep.rows) {
    if (r.target != rep.targets.back()) continue;
    char target[64];
    std::snprintf(target, sizeof target, o.equal_time ? "budget %g s" : "%g spp", r.target);
    std::printf("  %-14s %s: %6d spp, %7.3f s, rel. MSE %.4g, image-sum error %.4g (se %.3g), %lld non-finite px\n",
                std::string(method_name(r.method)).c_str(), target, r.run.result.spp, r.run.wall_seconds, r.err.rel_mse,
                r.err.sum_error[0], r.err.sum_se[0], r.err.nonfinite_pixels);
  }
  std::fflush(stdout);
}

const CommandRegistrar registrar{
    {"compare", "Equal-time comparison of gradient methods against a reference",
     [](CLI::App& app) -> std::function<int()> {
       auto flags = std::make_shared<Flags>();
       add_options(app, *flags);
       return [flags]() {
         const CompareOptions options = compare_options(*flags);
         const Scene scene = load_scene_with_flags(flags->scene, flags->defines);
         const auto params = parse_parameters(flags->params, scene);
         const CompareReport report = run_compare(scene, params, options, flags->quiet ? nullptr : &std::cerr);
         print_summary(report, options, params);
         // ---- charts (matplotlib, Debian's python3 found on PATH)
         if (!flags->no_plot &&
             run_python_script("compare", "plot_compare.py", {options.out.string()}, flags->scripts_dir) != 0) {
           std::cerr << "warning: the charts were not drawn; results.csv and results.json are written\n";
           return 1;
         }
         return 0;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
