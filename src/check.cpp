/// @file check.cpp
/// The failure path of QSIL_CHECK / QSIL_DCHECK; see qsil/check.h.

#include "qsil/check.h"

#include <cstdio>
#include <cstdlib>

namespace qsil::detail {

void check_failed(const char* file, int line, const char* condition, const std::string& message) {
  if (message.empty())
    std::fprintf(stderr, "%s:%d: check failed: %s\n", file, line, condition);
  else
    std::fprintf(stderr, "%s:%d: check failed: %s (%s)\n", file, line, condition, message.c_str());
  std::fflush(stderr);
  std::abort();
}

}  // namespace qsil::detail
