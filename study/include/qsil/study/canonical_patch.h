#pragma once
/// @file canonical_patch.h
/// The single-node experiment of [QSS] Sec. 5.1, Fig. 7: a patch of edges (one node), and for a
/// shading point p the verdict of four rejection tests next to the brute-force ground truth.
/// - Canonical patches (`qsil slices --patch sphere|torus`): a spherical cap (unit sphere, polar
///   angle <= 50 deg, 12 rings x 16 sectors, 368 triangles) and a toroidal patch (R = 1, r = 0.4,
///   a quarter turn about the axis u in [0, pi/2] and the upper tube v in [30, 150] deg, 16 x 12
///   quads, 384 triangles; positive and negative Gaussian curvature). Open meshes, world = their
///   own frame, +z up, counter-clockwise outward.
/// - PatchTests: the node over a patch's two-face edges (concave ones kept: the torus patch's
///   saddle side), fitted once with fit_node() (quadric and quadric-box, [QSS] 3.4) and bounded in
///   Hough space for a Hough origin o (vsphere and vsphere-solid, [QSS] App. F).
///
/// Units: scene units; frames: the mesh's.

#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/node_fit.h"
#include "qsil/edgetree/vsphere_tree.h"
#include "qsil/math.h"
#include "qsil/integrators/method.h"
#include "qsil/scene.h"

#include <array>

#include <string>
#include <vector>

namespace qsil::study {

using edgetree::EdgeForest;
using edgetree::NodeBound;
using edgetree::Wedge;

/// The two canonical patches.
enum class PatchKind { Sphere, Torus };

/// Parses "sphere" | "torus"; throws qsil::Error otherwise.
PatchKind parse_patch_kind(const std::string& name);

/// The patch mesh (see the file comment).
TriangleMesh make_canonical_patch(PatchKind kind);

/// Ground truth and the verdicts of the four rejection tests of Fig. 7 (kRejectionMethods:
/// quadric, quadric-box, vsphere, vsphere-solid) at one point.
struct SliceVerdict {
  bool truth = false;                                   ///< some edge of the patch is a silhouette for p
  std::array<bool, kRejectionMethods.size()> accept{};  ///< in kRejectionMethods order
  /// The verdict of `method` (one of kRejectionMethods).
  bool accepts(Method method) const;
};

/// One node (a set of wedges) and its four tests.
class PatchTests {
 public:
  /// The node over every two-face edge of `mesh` that is not flat (convex and concave), fitted
  /// as a root (no parent quadric). `o` is the Hough origin.
  static PatchTests from_mesh(const TriangleMesh& mesh, const Vec3& o);

  /// Inner node `node` of a forest: quadric tests are the forest's own (may_have_silhouette);
  /// the Hough box is built over the node's edges for the origin `o`.
  static PatchTests from_forest_node(const EdgeForest& forest, int node, const Vec3& o);

  /// A default Hough origin for a patch: 3 diagonals from the centre of its box along the
  /// area-weighted mean normal of the faces (a camera looking at it).
  static Vec3 default_origin(const TriangleMesh& mesh);

  /// Ground truth (brute force over the wedges, edge_is_silhouette's predicate) and verdicts.
  SliceVerdict evaluate(const Vec3& p) const;

  int num_edges() const { return int(wedges_.size()); }
  /// Edges that are silhouettes from o: they would sit in Li's plain tree, so whenever there is
  /// one the v-sphere methods accept every point (reported; 0 for the canonical defaults).
  int origin_silhouettes() const { return origin_sil_; }
  const Box3& hough_box() const { return bh_; }
  std::uint16_t flags() const { return flags_; }  ///< NodeFlags of the fit (unrejectable, box-only)

 private:
  std::vector<Wedge> wedges_;
  Box3 bp_, bh_;
  Vec3 o_ = Vec3::Zero();
  int origin_sil_ = 0;
  std::uint16_t flags_ = 0;
  NodeBound bound_;
  const EdgeForest* forest_ = nullptr;  ///< set by from_forest_node
  int node_ = -1;
};

}  // namespace qsil::study
