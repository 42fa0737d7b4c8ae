#pragma once
/// @file cli_parse.h
/// The command-line parse shared by every program of tools/ (`qsil`, `qsil-check_gradients`,
/// `qsil-fit_ltc`, the benchmark): CLI11 parses argv; --help prints and ends with exit code 0, a
/// bad argument prints CLI11's message and ends with exit code 2 (docs/architecture.md §8).

#include <CLI/CLI.hpp>

#include <optional>

namespace qsil::cli {

/// Parses argv with `app`. Returns std::nullopt when the program should go on, else the exit code.
inline std::optional<int> parse_arguments(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  return std::nullopt;
}

}  // namespace qsil::cli
