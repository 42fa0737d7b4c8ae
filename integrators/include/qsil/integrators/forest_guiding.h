#pragma once
/// @file forest_guiding.h
/// The guiding parameters of the quadric methods' edge choice (guided quadric silhouette sampling,
/// [QSS] §5.2's future work; the guide: qsil/edgetree/forest_guide.h), apart from the estimator
/// so that configurations (EstimatorConfig, the command line, comparisons) need not include it.

#include "qsil/edgetree/forest_guide.h"

namespace qsil {

/// How the forest guide is trained (EstimatorConfig::forest_guiding). At set-up, `rounds` passes
/// of `training` samples per pixel each trace the gradient's paths with the boundary term from a
/// fixed stream (the guide depends on the scene alone, not on the run's seed) and record every
/// contributing edge point that went through a guided slot; each pass after the first already
/// uses the guide learnt from the passes before it, and the guide learns from all of them. The
/// training passes' images are discarded; their time is set-up time (charged in equal-time
/// comparisons). training = 0: no guide (the default).
struct ForestGuiding {
  int training = 0;                    ///< samples per pixel of each training pass, in [0, 1024]
  int rounds = 2;                      ///< training passes, in [1, 16]
  edgetree::ForestGuideOptions guide;  ///< resolution, depth, defensive share
};

/// Throws qsil::Error ("forest guide: training spp N out of range [0, 1024]", likewise for
/// rounds, [1, 16], and the guide's options) unless the parameters are valid (with training 0
/// the others are not read). The estimator also refuses a guide for a method without an edge
/// forest ("forest guide: method M has no edge forest to guide (quadric, quadric-box)").
void check_forest_guiding(const ForestGuiding& guiding);

}  // namespace qsil
