#pragma once
// Running a shell command from the repository root and capturing what it printed: the helper of
// the tests that drive the built `qsil` program (tests/cli_test.cpp, tests/mpi_cli_test.cpp).

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

namespace qsil::testing {

/// What a command did: exit code (-1 if it did not exit normally), stderr, stdout, wall time.
struct ShellRun {
  int code = -1;
  std::string err;  ///< stderr
  std::string out;  ///< stdout
  double seconds = 0;
};

/// The whole content of a file ("" if it cannot be opened).
inline std::string read_whole_file(const std::filesystem::path& p) {
  std::string s;
  if (FILE* f = std::fopen(p.c_str(), "r")) {
    std::array<char, 4096> buf;
    size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) s.append(buf.data(), n);
    std::fclose(f);
  }
  return s;
}

/// Runs the shell command `cmd` from the repository root (QSIL_SOURCE_DIR, whatever ctest's
/// working directory), capturing stdout and stderr in temporary files named after `tag` and the
/// process id (ctest runs tests of one file in parallel processes).
inline ShellRun run_shell(const std::string& cmd, const std::string& tag) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string id = std::to_string(::getpid());
  const auto err = dir / (tag + id + ".err"), out = dir / (tag + id + ".out");
  const std::string full =
      "cd '" + std::string(QSIL_SOURCE_DIR) + "' && " + cmd + " >" + out.string() + " 2>" + err.string();
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(full.c_str());
  ShellRun r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = read_whole_file(err);
  r.out = read_whole_file(out);
  std::filesystem::remove(err);
  std::filesystem::remove(out);
  return r;
}

}  // namespace qsil::testing
