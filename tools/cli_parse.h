#pragma once
/// @file cli_parse.h
/// The command-line parse shared by every program of tools/ (`qsil`, `qsil-check_gradients`,
/// `qsil-fit_ltc`, the benchmark): CLI11 parses argv; --help prints and ends with exit code 0, a
/// bad argument prints CLI11's message and ends with exit code 2 (docs/architecture.md §8).

#include <CLI/CLI.hpp>

#include <optional>
#include <sstream>

namespace qsil::cli {

/// Parses argv with `app`. Returns std::nullopt when the program should go on, else the exit code.
/// `silent`: print neither help nor errors (ranks other than 0 of an MPI job: rank 0 prints).
inline std::optional<int> parse_arguments(CLI::App& app, int argc, char** argv, bool silent = false) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::ostringstream sink;
    const int code = silent ? app.exit(e, sink, sink) : app.exit(e);
    return code == 0 ? 0 : 2;
  }
  return std::nullopt;
}

}  // namespace qsil::cli
