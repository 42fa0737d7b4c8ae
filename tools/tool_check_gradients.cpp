/// @file tool_check_gradients.cpp
/// `qsil-check_gradients` (CMake names tools/tool_X.cpp qsil-X): the long form of
/// tests/integrators/gradient_vs_fd_test.cpp. For every gradient scene (or those named with
/// --case) it renders `qsil grad` (quadric boundary term), the interior term alone and central
/// finite differences with common random numbers, and prints the same statistics as the tests
/// (image sums +- standard errors, the fraction of pixel-channels within 4 combined standard
/// errors, the worst pixel-channels); docs/gradient-checks.md records its output. The cases'
/// scenes are files of the repository, found under --root (default: the working directory):
///   build/qsil-check_gradients [--case NAME]... [--res 32] [--spp 1024] [--fd-spp 4096] [--h H]
///                              [--threads T] [--csv DIR] [--root REPOSITORY]
///   build/qsil-check_gradients --scene FILE.xml --param SPEC [-D k=v]... (any scene, same statistics)
/// --csv writes DIR/NAME.csv with every pixel-channel (x,y,c,primal,grad,grad_se,fd,fd_se,interior).
/// Exit code 1 when a criterion fails (sums within 3 SE, >= 98% of pixel-channels within 4 SE).

#include "cli_parse.h"
#include "qsil/study/gradient_check.h"
#include "qsil/scene.h"

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

using namespace qsil;

namespace {

struct Flags {
  std::vector<std::string> names;
  int res = 32, spp = 1024, fd_spp = 4096, threads = 0;
  double h = 0;
  std::string csv, root = ".";
  std::string scene, param;
  std::vector<std::string> defines;
};

/// The cases to run: --case names (or every case), plus the --scene case.
std::vector<gradcheck::Case> selected_cases(const Flags& f) {
  std::vector<gradcheck::Case> out;
  std::vector<std::string> names = f.names;
  if (f.scene.empty() && names.empty())
    for (const auto& c : gradcheck::cases()) names.push_back(c.name);
  for (const auto& name : names) out.push_back(gradcheck::find_case(name).resolved(f.root));
  if (!f.scene.empty()) {
    gradcheck::Case custom;
    custom.file = f.scene;
    custom.param = f.param;
    custom.defaults = parse_defines(f.defines);
    custom.name = std::filesystem::path(f.scene).stem().string();
    custom.h = 1e-2;
    out.push_back(custom);
  }
  return out;
}

/// Runs and prints every case; true when all pass.
bool run_cases(const Flags& f) {
  bool ok = true;
  for (const gradcheck::Case& c : selected_cases(f)) {
    gradcheck::Films films;
    const gradcheck::Agreement a = gradcheck::run(c, f.res, f.spp, f.fd_spp, f.h > 0 ? f.h : c.h, true, f.threads,
                                                  f.csv.empty() ? nullptr : &films);
    std::printf("%s", gradcheck::describe(c.name + " (" + c.param + ")", a).c_str());
    std::printf("  boundary: %llu traversals, %.1f%% zero\n", (unsigned long long)a.traversals,
                a.traversals ? 100.0 * double(a.zero_traversals) / double(a.traversals) : 0.0);
    std::fflush(stdout);
    if (!f.csv.empty()) gradcheck::write_csv(f.csv + "/" + c.name + ".csv", films);
    ok = ok && a.sums_agree() && a.pixels_agree() && a.nonfinite == 0;
  }
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  Flags f;
  std::string case_list;
  for (const auto& c : gradcheck::cases()) case_list += " " + c.name;
  CLI::App app{
      "qsil-check_gradients: image-level gradient checks (grad vs finite differences). Cases (scenes "
      "under --root):" +
      case_list};
  app.add_option("--case", f.names, "A gradient case (repeatable; default: every case)")->allow_extra_args(false);
  app.add_option("--res", f.res, "Image side in pixels")->capture_default_str()->check(qsil::cli::positive_number());
  app.add_option("--spp", f.spp, "Samples per pixel of grad")->capture_default_str()->check(qsil::cli::positive_number());
  app.add_option("--fd-spp", f.fd_spp, "Samples per pixel of FD")->capture_default_str()->check(qsil::cli::positive_number());
  app.add_option("--h", f.h, "FD step (default: the case's)")->check(qsil::cli::non_negative_number());
  app.add_option("--threads", f.threads, "Worker threads (0 = all cores)")->check(qsil::cli::non_negative_number());
  app.add_option("--csv", f.csv, "Write DIR/NAME.csv with every pixel-channel");
  app.add_option("--root", f.root, "The repository whose scenes the cases use")->capture_default_str();
  app.add_option("--scene", f.scene, "Any scene instead of the cases (with --param)");
  app.add_option("--param", f.param, "The parameter of --scene");
  app.add_option("-D", f.defines, "Override a <default> of --scene: -D name=value (repeatable)")
      ->allow_extra_args(false);
  if (const auto code = qsil::cli::parse_arguments(app, argc, argv)) return *code;
  try {
    return run_cases(f) ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "qsil-check_gradients: %s\n", e.what());
    return 2;
  }
}
