/// @file edge_sampler_factory.cpp
/// See edge_sampler_factory.h.

#include "integrators/edge_sampler_factory.h"

#include "qsil/edgetree/uniform_sampler.h"
#include "qsil/edgetree/vsphere_sampler.h"

namespace qsil {

std::unique_ptr<edgetree::EdgeSampler> make_edge_sampler(BoundaryMethod method, const Scene& scene,
                                                         const edgetree::EdgeForest& forest) {
  switch (method) {
    case BoundaryMethod::None: return nullptr;
    case BoundaryMethod::Quadric:
      return std::make_unique<edgetree::QuadricEdgeSampler>(forest, edgetree::RejectionMode::Quadric);
    case BoundaryMethod::QuadricBox:
      return std::make_unique<edgetree::QuadricEdgeSampler>(forest, edgetree::RejectionMode::Box);
    // Li 2019: the Hough origin is the camera centre (docs/architecture.md §7).
    case BoundaryMethod::VSphere:
      return std::make_unique<edgetree::VSphereEdgeSampler>(forest, scene.camera.origin(), edgetree::VSphereTest::Hollow);
    case BoundaryMethod::VSphereSolid:
      return std::make_unique<edgetree::VSphereEdgeSampler>(forest, scene.camera.origin(), edgetree::VSphereTest::Solid);
    case BoundaryMethod::Uniform: return std::make_unique<edgetree::UniformEdgeSampler>(forest);
  }
  return nullptr;
}

}  // namespace qsil
