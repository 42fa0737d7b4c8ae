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

#include "qsil/integrators/gradient_check.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

using namespace qsil;

int main(int argc, char** argv) {
  std::vector<std::string> names;
  int res = 32, spp = 1024, fd_spp = 4096, threads = 0;
  double h = 0;
  std::string csv, root = ".";
  gradcheck::Case custom;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--case") names.push_back(next());
    else if (a == "--res") res = std::atoi(next().c_str());
    else if (a == "--spp") spp = std::atoi(next().c_str());
    else if (a == "--fd-spp") fd_spp = std::atoi(next().c_str());
    else if (a == "--h") h = std::atof(next().c_str());
    else if (a == "--threads") threads = std::atoi(next().c_str());
    else if (a == "--csv") csv = next();
    else if (a == "--root") root = next();
    else if (a == "--scene") custom.file = next();
    else if (a == "--param") custom.param = next();
    else if (a == "-D") {
      const std::string kv = next();
      const auto eq = kv.find('=');
      if (eq == std::string::npos) {
        std::fprintf(stderr, "-D expects name=value\n");
        return 2;
      }
      custom.defaults[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
    else if (a == "--help" || a == "-h") {
      std::printf("usage: qsil-check_gradients [--case NAME]... [--res N] [--spp N] [--fd-spp N] [--h H] "
                  "[--threads T] [--csv DIR] [--root REPOSITORY] [--scene FILE --param SPEC [-D k=v]...]\ncases "
                  "(scenes under --root):");
      for (const auto& c : gradcheck::cases()) std::printf(" %s", c.name.c_str());
      std::printf("\n");
      return 0;
    } else {
      std::fprintf(stderr, "unknown argument %s (see --help)\n", a.c_str());
      return 2;
    }
  }
  if (!custom.file.empty()) {
    custom.name = std::filesystem::path(custom.file).stem().string();
    custom.h = 1e-2;
  } else if (names.empty())
    for (const auto& c : gradcheck::cases()) names.push_back(c.name);
  bool ok = true;
  try {
    std::vector<gradcheck::Case> run_cases;
    for (const auto& name : names) run_cases.push_back(gradcheck::find_case(name).resolved(root));
    if (!custom.file.empty()) run_cases.push_back(custom);
    for (const gradcheck::Case& c : run_cases) {
      gradcheck::Films films;
      const gradcheck::Agreement a =
          gradcheck::run(c, res, spp, fd_spp, h > 0 ? h : c.h, true, threads, csv.empty() ? nullptr : &films);
      std::printf("%s", gradcheck::describe(c.name + " (" + c.param + ")", a).c_str());
      std::printf("  boundary: %llu traversals, %.1f%% zero\n", (unsigned long long)a.report.traversals,
                  a.report.traversals ? 100.0 * double(a.report.zero_traversals) / double(a.report.traversals) : 0.0);
      std::fflush(stdout);
      if (!csv.empty()) gradcheck::write_csv(csv + "/" + c.name + ".csv", films);
      ok = ok && a.sums_agree() && a.pixels_agree() && a.nonfinite == 0;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return ok ? 0 : 1;
}
