#pragma once
/// @file boundary_context.h
/// What the secondary boundary term needs at a path vertex besides the path context: the edge
/// sampler, the contour index, eligibility, the sample rate and the importance inputs.

#include "qsil/edgetree/contour_set.h"
#include "qsil/edgetree/edge_sampler.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/integrators/attached_camera.h"
#include "qsil/parameters.h"

#include <array>
#include <vector>

namespace qsil {

/// What the boundary term needs besides the path context.
struct BoundaryContext {
  const edgetree::EdgeSampler* sampler = nullptr;  ///< the --boundary method's secondary edge sampler
  /// The mesh adjacency for contour sets at glossy vertices and under small area lights
  /// (contour_probe; the quadric method in a scene with a glossy BSDF or an area light), or null
  /// for none.
  const edgetree::ContourIndex* contours = nullptr;
  const SceneVelocities* velocities = nullptr;
  std::vector<bool> moving;  ///< shapes with non-zero velocity (eligible at a static p)
  std::vector<bool> all;     ///< every shape (eligible at a moving p)
  /// Secondary boundary-term traversals per path vertex, on average over a pixel's samples
  /// (EstimatorConfig::sppi; positive and finite): boundary_traversals() of them at every
  /// vertex of a sample's path, each weighted 1 / sppi.
  double sppi = 1.0;
  /// Splitting at fast shading points (boundary_split): a vertex whose shading point moves at
  /// speed s makes ceil(s / split_speed) traversals, at most kMaxBoundarySplit, for each one
  /// boundary_traversals schedules. 0: no splitting. Set from default_split_speed(method).
  double split_speed = 0;
  std::vector<edgetree::LightPolygon> lights;  ///< quad area lights for I_light [QSS 3.6]
  /// The other area lights (mesh emitters) for I_light, by their bounding spheres
  /// (edgetree::LightSphere: a quad facing each shading point outside the sphere).
  std::vector<edgetree::LightSphere> light_spheres;
  double env_weight = 1.0;                     ///< environment intensity (luminance of its mean)
  std::vector<double> emission;                ///< per shape: luminance of its emission (0: none)
  /// Per parameter: 1 / the largest |dx/dtheta_k| over all vertices (0: unused parameter), so that
  /// the leaves' normal-velocity factor weighs parameters of different units alike.
  std::array<double, kMaxParameters> velocity_scale{};
  /// Attached camera hits (attached_camera.h): the primary edges include static shapes' outlines
  /// (find_primary_edges' `attached`). Set before set_up_boundary_term.
  CameraHits camera_hits = CameraHits::Detached;
  /// The forest guide of the quadric methods (edgetree::ForestGuide; SilhouetteQuery::guide), or
  /// null: unguided.
  const edgetree::ForestGuide* guide = nullptr;
};

}  // namespace qsil
