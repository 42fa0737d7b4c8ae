#pragma once
/// @file candidates.h
/// The candidate-edge study of `qsil candidates` ([QSS] Sec. 5.1, Fig. 8): for one shading point,
/// every edge each edge-sampling method can sample (non-zero probability), found by exhaustive
/// traversal of its hierarchy, with statistics and pictures.
///
/// Shading point: the first hit of the ray through the centre of a pixel (normal: the hit
/// triangle's geometric normal, turned toward the camera for twosided BSDFs; wo toward the
/// camera), or a given point and normal (wo toward the camera centre; a diffuse BSDF). Eligible
/// shapes: every shape (as for a moving shading point, docs/architecture.md §2) or a list. Per
/// method (quadric and quadric-box: the edge forest, every accepted child down to the leaves,
/// whose edges are tested exactly; vsphere, vsphere-solid: Li's tree with the Hough origin at the
/// camera centre, every accepted child down to the one-edge leaves; uniform: every edge):
/// - candidates: edges with probability > 0; silhouettes among them; silhouettes with a point
///   above the shading point's tangent plane ("upper hemisphere");
/// - non-silhouette mass: the total probability of candidates that are not silhouettes;
/// - dead-end mass: 1 - total candidate probability (traversals that end with every child
///   rejected); both are zero-contribution samples.
/// Probabilities are those of one traversal without splitting (sample_silhouette): the renderer
/// additionally splits bright loose edges off (silhouette_sampler.h), which the query here (no
/// lights, no emission) rarely triggers; a split edge is covered with probability 1.
/// Outputs (write_candidates): DIR/<method>-camera.png (scene camera) and <method>-overview.png
/// (overview_camera): the meshes' wireframe in grey, non-silhouette candidates green, silhouette
/// candidates red, the shading point black with its normal; DIR/<method>-edges.obj (the
/// candidate line sets and the point for external viewers); DIR/summary.json and summary.csv.

#include "qsil/edgetree/edge_sampler.h"
#include "qsil/integrators/method.h"
#include "qsil/scene.h"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace qsil {

/// Where the shading point is and which methods and shapes to study.
struct CandidatesOptions {
  std::vector<int> pixel;             ///< X,Y: the first hit through this pixel's centre (or empty)
  std::vector<double> point, normal;  ///< X,Y,Z each: a free shading point (when pixel is empty)
  std::vector<Method> methods{kEdgeSamplingMethods.begin(), kEdgeSamplingMethods.end()};
  std::vector<std::string> shapes;  ///< eligible shape ids (empty: every shape)
};

/// One method's candidates and statistics.
struct MethodCandidates {
  Method method = Method::Quadric;
  std::vector<edgetree::EdgeProbability> edges;  ///< every edge with probability > 0
  long long candidates = 0, silhouettes = 0, upper = 0;
  long long leaf_edges = -1;  ///< leaf edges tested exactly (quadric methods), -1 otherwise
  double non_silhouette_mass = 0, dead_end_mass = 0, upper_mass = 0;
};

/// The result of find_candidates (see the file comment).
struct CandidatesReport {
  Vec3 p = Vec3::Zero(), n = Vec3::UnitZ();        ///< shading point and normal (world)
  int shape = -1;                                  ///< the hit shape (-1 for a free point)
  std::string where;                               ///< "pixel X,Y" or "point"
  long long true_silhouettes = 0, true_upper = 0;  ///< ground truth over the eligible shapes
  std::vector<MethodCandidates> methods;
  std::shared_ptr<const void> keep_alive;  ///< owns the edge structures the edge pointers point into
};

/// Finds the shading point and every method's candidates. Throws qsil::Error for a pixel
/// outside the image or whose ray hits nothing, a missing or zero point/normal, or an unknown
/// shape id.
CandidatesReport find_candidates(const Scene& scene, const CandidatesOptions& options);

/// Writes the pictures (`size` pixels on the larger side), OBJ line sets, summary.json and
/// summary.csv of a report to `dir` (created). `scene_path` is recorded (portable_path).
void write_candidates(const Scene& scene, const CandidatesReport& report, const std::string& scene_path,
                      const std::filesystem::path& dir, int size);

}  // namespace qsil
