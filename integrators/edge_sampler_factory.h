#pragma once
/// @file edge_sampler_factory.h
/// The secondary edge sampler of a `--boundary` method (docs/architecture.md §7).

#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/edge_sampler.h"
#include "qsil/integrators/render.h"

#include <memory>

namespace qsil {

/// Builds the sampler of `method` over the scene's shapes. `forest` is the quadric edge forest
/// of the scene (always built: its edge lists also feed the primary term). Returns nullptr for
/// BoundaryMethod::None.
std::unique_ptr<edgetree::EdgeSampler> make_edge_sampler(BoundaryMethod method, const Scene& scene,
                                                         const edgetree::EdgeForest& forest);

}  // namespace qsil
