#pragma once
/// @file slice_study.h
/// The single-node study of `qsil slices` ([QSS] Sec. 5.1, Fig. 7): the verdicts of the four
/// rejection tests (kRejectionMethods) for one node on two parallel planes, next to the
/// brute-force ground truth (canonical_patch.h).
///
/// Every point x of the plane {x : n.x = h} within the square of side E around the projection of
/// the centre gets ground truth (does a patch edge have (q0.x)(q1.x) <= 0) and the verdict of
/// quadric, quadric-box, vsphere and vsphere-solid. Outputs (write_slice_study) in DIR:
/// <method>-plane<k>.png (grey: no silhouette, rejected; blue: silhouette, accepted; orange: false
/// accept; magenta: false reject, a soundness bug), summary.json and summary.csv (per test and
/// plane: points, points without silhouette, false accepts, false-accept rate = false accepts /
/// points without silhouette, false rejects).

#include "qsil/study/canonical_patch.h"
#include "qsil/math.h"

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace qsil::study {

/// The node and the planes. Either `patch` ("sphere" or "torus", a canonical patch) or `mesh`
/// (an OBJ file) with `node` (an inner node of its edge forest). Empty vectors and zeros take the
/// defaults of each case.
struct SliceStudyOptions {
  std::string mesh;
  int node = -1;
  std::string patch;
  std::vector<double> origin;   ///< Hough origin X,Y,Z (default PatchTests::default_origin)
  std::vector<double> normal;   ///< plane normal X,Y,Z (default 0,0,1)
  std::vector<double> heights;  ///< H1,H2: the planes n.x = H
  std::vector<double> center;   ///< X,Y,Z: centre of the squares (projected onto each plane)
  double extent = 0;            ///< side of the squares (scene units)
  int resolution = 256;         ///< points per side (2..4096)
};

/// Counts of one plane.
struct PlaneStats {
  double height = 0;
  long long points = 0, no_silhouette = 0;
  std::array<long long, kRejectionMethods.size()> false_accepts{}, false_rejects{}, accepts{};
  /// The slice picture of each test (resolution^2 RGB bytes, top row first).
  std::array<std::vector<unsigned char>, kRejectionMethods.size()> images;
};

/// A finished study.
struct SliceStudy {
  std::string label;  ///< the patch name, or MESH-node<ID>
  int edges = 0;
  int origin_silhouettes = 0;  ///< edges that are silhouettes from the Hough origin
  Vec3 origin = Vec3::Zero(), normal = Vec3::UnitZ();
  double extent = 0;
  int resolution = 0;
  std::array<PlaneStats, 2> planes;
  /// Total false rejects over both planes and every test (0 unless a test is unsound).
  long long false_rejects() const;
};

/// Builds the node and evaluates both planes (in parallel with oneTBB). Throws qsil::Error for
/// inconsistent options (both or neither of mesh and patch, no node, not an inner node, a zero
/// normal, malformed vectors, a resolution outside 2..4096).
SliceStudy run_slice_study(const SliceStudyOptions& options);

/// Writes the pictures, summary.json and summary.csv of a study to `dir` (created).
void write_slice_study(const SliceStudy& study, const std::filesystem::path& dir);

}  // namespace qsil::study
