#pragma once
/// @file cli_parse.h
/// The command-line parse shared by every program of tools/ (`qsil`, `qsil-check_gradients`,
/// `qsil-fit_ltc`, the benchmark): CLI11 parses argv; --help prints and ends with exit code 0, a
/// bad argument prints one line and ends with exit code 2 (docs/architecture.md §8).

#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <optional>
#include <string>
#include <sstream>

namespace qsil::cli {

/// Parses argv with `app`. Returns std::nullopt when the program should go on, else the exit code.
/// `silent`: print neither help nor errors (ranks other than 0 of an MPI job: rank 0 prints).
/// A bad argument prints one line, CLI11's message naming the option (e.g. "--spp: must be a
/// positive number (got 0)"), on stderr.
inline std::optional<int> parse_arguments(CLI::App& app, int argc, char** argv, bool silent = false) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {  // --help, --help-all
      std::ostringstream sink;
      if (silent) app.exit(e, sink, sink);
      else app.exit(e);
      return 0;
    }
    if (!silent) std::cerr << e.what() << "\n";
    return 2;
  }
  return std::nullopt;
}

/// The numeric checks of every program's options: a value out of range fails the parse with a
/// one-line message (CLI11's own range validators print the whole double range).
inline CLI::Validator positive_number() {
  return CLI::Validator(
      [](std::string& in) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(in, v) || !(v > 0 && std::isfinite(v)))
          return "must be a positive number (got " + in + ")";
        return {};
      },
      "POSITIVE");
}

/// As positive_number, for values that may be 0.
inline CLI::Validator non_negative_number() {
  return CLI::Validator(
      [](std::string& in) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(in, v) || !(v >= 0 && std::isfinite(v)))
          return "must be a number >= 0 (got " + in + ")";
        return {};
      },
      "NONNEGATIVE");
}

}  // namespace qsil::cli
