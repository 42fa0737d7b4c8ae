#pragma once
/// @file baseline_test_util.h
/// Test meshes and shading points shared by the baseline tests (the soundness set of the
/// edge forest: spot, torus, bunny, a subdivided cube; points uniform around the mesh, near
/// the surface and on triangle planes: tests/soundness_set.h).

#include "qsil/edgetree/edge_forest.h"
#include "qsil/scene.h"
#include "soundness_set.h"
#include "test_data.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace qsil::baselines_test {

using test::make_cube;
using test::shading_points;

/// A test mesh by file name (test_data.h: a missing file fails the test with its path).
inline TriangleMesh test_mesh(const std::string& name) { return load_obj(test::mesh_file(name)); }

/// A camera-like Hough origin: 2 diagonals from the mesh centre along a fixed oblique direction.
inline Vec3 camera_like_origin(const TriangleMesh& m) {
  const Box3 b = m.bounds();
  return b.center() + 2.0 * b.diagonal() * Vec3(0.36, 0.48, 0.8);
}

/// The edge forest over `meshes`, mesh i as shape i (the meshes must outlive it).
inline edgetree::EdgeForest forest_over(const std::vector<TriangleMesh>& meshes) {
  std::vector<edgetree::ForestShapeInput> in;
  for (size_t i = 0; i < meshes.size(); ++i) in.push_back({&meshes[i], int(i)});
  return edgetree::EdgeForest::build(in);
}

}  // namespace qsil::baselines_test
