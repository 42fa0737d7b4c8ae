#pragma once
/// @file geometry_view.h
/// How the integrators read vertex positions and shading normals: as doubles (PrimalView, for
/// `render` and finite differences) or as dual numbers carrying dx/dtheta (DualView<N>, for the
/// interior term in forward mode, docs/architecture.md §4). Integrator code is written once over a view.

#include "qsil/dual.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

namespace qsil {

/// Plain double geometry: no derivatives.
struct PrimalView {
  using Real = double;
  const Scene* scene;
  Vec3 position(int shape, int v) const { return scene->shapes[shape].mesh.positions[v]; }
  Vec3 normal(int shape, int v) const { return scene->shapes[shape].mesh.normals[v]; }
  bool moving(int) const { return false; }
};

/// Geometry with forward-mode derivatives of N parameters (N >= velocities->num_params).
template <int N>
struct DualView {
  using Real = Dual<N>;
  const Scene* scene;
  const SceneVelocities* velocities;
  Vec3T<Real> position(int shape, int v) const {
    return lift<N>(scene->shapes[shape].mesh.positions[v],
                   velocities->position[shape][v].template leftCols<N>().eval());
  }
  Vec3T<Real> normal(int shape, int v) const {
    return lift<N>(scene->shapes[shape].mesh.normals[v], velocities->normal[shape][v].template leftCols<N>().eval());
  }
  bool moving(int shape) const { return velocities->moving[shape]; }
  /// Whether a ray from origin `o` that hits shape `shape` has a hit with zero derivatives: the
  /// shape does not move and o's derivatives are all zero (make_interaction then works in doubles).
  /// Parameters move geometry only; parameters of materials or the camera would have to count here.
  bool constant_hit(int shape, const Vec3T<Real>& o) const {
    if (moving(shape)) return false;
    for (int i = 0; i < 3; ++i)
      if (!(o[i].derivatives().array() == 0).all()) return false;
    return true;
  }
};

}  // namespace qsil
