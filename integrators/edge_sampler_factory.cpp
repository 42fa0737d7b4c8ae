/// @file edge_sampler_factory.cpp
/// See edge_sampler_factory.h.

#include "integrators/edge_sampler_factory.h"

namespace qsil {

std::unique_ptr<edgetree::EdgeSampler> make_edge_sampler(BoundaryMethod method, const Scene& scene,
                                                         const edgetree::EdgeForest& forest) {
  (void)scene;
  switch (method) {
    case BoundaryMethod::None: return nullptr;
    case BoundaryMethod::Quadric:
      return std::make_unique<edgetree::QuadricEdgeSampler>(forest, edgetree::RejectionMode::Quadric);
    case BoundaryMethod::QuadricBox:
      return std::make_unique<edgetree::QuadricEdgeSampler>(forest, edgetree::RejectionMode::Box);
  }
  return nullptr;
}

}  // namespace qsil
