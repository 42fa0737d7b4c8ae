#pragma once
/// @file error.h
/// The one error type of qsil. Every user-facing failure (bad scene file, bad flag, missing file,
/// malformed mesh) throws qsil::Error with a one-line message that names the file, line or value,
/// formatted `file:line: message` where a location exists. The CLI prints it and exits with code 2
/// (docs/architecture.md §8).

#include <stdexcept>
#include <string>

namespace qsil {

/// A user-facing error: message is one line, ready to print. exit code 2 in the CLI.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace qsil
