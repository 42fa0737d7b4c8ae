/// @file forest_guiding.cpp
/// See qsil/integrators/forest_guiding.h.

#include "qsil/integrators/forest_guiding.h"

#include "qsil/error.h"

#include <string>

namespace qsil {

void check_forest_guiding(const ForestGuiding& guiding) {
  if (guiding.training < 0 || guiding.training > 1024)
    throw Error("forest guide: training spp " + std::to_string(guiding.training) + " out of range [0, 1024]");
  if (guiding.training == 0) return;
  if (guiding.rounds < 1 || guiding.rounds > 16)
    throw Error("forest guide: training rounds " + std::to_string(guiding.rounds) + " out of range [1, 16]");
  edgetree::check_forest_guide_options(guiding.guide);
}

}  // namespace qsil
