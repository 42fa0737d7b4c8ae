#pragma once
/// @file check.h
/// Invariant checks, in the manner of pbrt-v4's util/check.h. A failed check is a bug in qsil,
/// never bad input (bad input throws qsil::Error, error.h): it prints one line
/// `file:line: check failed: CONDITION [(message)]` to stderr and aborts.
/// - QSIL_CHECK(cond), QSIL_CHECK_MSG(cond, message): always on. For invariants whose test is
///   cheap next to the work it guards (once per render, per structure, per film).
/// - QSIL_DCHECK(cond), QSIL_DCHECK_MSG(cond, message): on when the build defines QSIL_DCHECKS
///   (the CMake option of the same name: on for Debug builds and for `tools/run-tests.sh`, off in
///   Release); otherwise the condition is compiled but never evaluated, so they cost nothing. For
///   invariants on hot paths (per sample, per ray).
/// `message` is anything `std::ostream <<` accepts, e.g. `"pdf " << pdf`.

#include <sstream>
#include <string>

namespace qsil::detail {

/// Prints `file:line: check failed: condition (message)` to stderr and aborts.
[[noreturn]] void check_failed(const char* file, int line, const char* condition, const std::string& message);

}  // namespace qsil::detail

#define QSIL_CHECK(cond) \
  ((cond) ? static_cast<void>(0) : ::qsil::detail::check_failed(__FILE__, __LINE__, #cond, std::string()))

#define QSIL_CHECK_MSG(cond, message)                                                            \
  ((cond) ? static_cast<void>(0) : ::qsil::detail::check_failed(__FILE__, __LINE__, #cond, [&] { \
    std::ostringstream qsil_check_stream_;                                                       \
    qsil_check_stream_ << message;                                                               \
    return qsil_check_stream_.str();                                                             \
  }()))

#ifdef QSIL_DCHECKS
#define QSIL_DCHECK(cond) QSIL_CHECK(cond)
#define QSIL_DCHECK_MSG(cond, message) QSIL_CHECK_MSG(cond, message)
#else
// Compiled (names stay used, no warnings) but not evaluated: sizeof's operand is unevaluated.
#define QSIL_DCHECK(cond) static_cast<void>(sizeof(!(cond)))
#define QSIL_DCHECK_MSG(cond, message) static_cast<void>(sizeof(!(cond)))
#endif
