#pragma once
/// @file spot_sheet_world.h
/// The world of the traversal tests that need loose always-candidate edges beside a mesh's tree
/// (split_sampling_test.cpp, forest_guide_test.cpp): spot and an emitting open square sheet
/// (radiance 40) above it, facing down, whose outline is four loose always-candidate edges.

#include "baselines/baseline_test_util.h"
#include "qsil/edgetree/edge_forest.h"

#include <memory>
#include <vector>

namespace qsil::edgetree::test {

struct SpotSheetWorld {
  std::vector<TriangleMesh> meshes;  ///< spot, the sheet
  EdgeForest forest;
  std::vector<double> emission{0.0, 40.0};
  std::vector<bool> eligible{true, true};
};

/// Spot with its creases as `spot_creases` says (CreaseSet::Concave: as the renderer builds a
/// one-sided smooth shape, its 2602 concave edges creases in an always-candidate tree) and the
/// sheet, of half side `half_side` in the plane y = `height` (scene units), centred on the y axis.
inline std::unique_ptr<SpotSheetWorld> make_spot_sheet_world(CreaseSet spot_creases, double half_side, double height) {
  auto w = std::make_unique<SpotSheetWorld>();
  w->meshes.push_back(baselines_test::test_mesh("spot.obj"));
  const double h = half_side;
  TriangleMesh sheet;
  sheet.positions = {{-h, height, -h}, {h, height, -h}, {h, height, h}, {-h, height, h}};
  sheet.triangles = {{0, 1, 2}, {0, 2, 3}};
  w->meshes.push_back(sheet);
  const std::vector<ForestShapeInput> in{{&w->meshes[0], 0, /*face_normals=*/false, spot_creases}, {&w->meshes[1], 1}};
  w->forest = EdgeForest::build(in);
  return w;
}

}  // namespace qsil::edgetree::test
