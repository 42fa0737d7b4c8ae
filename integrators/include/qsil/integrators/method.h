#pragma once
/// @file method.h
/// The one method type of qsil: how a derivative image is estimated (docs/architecture.md §7).
/// Every command names methods the same way (`--boundary`, `--method`, `--methods`), and this
/// file is the only place that parses or prints them. Each command accepts a subset
/// (kBoundaryMethods for `grad --boundary`, kEdgeSamplingMethods for `candidates`, ...);
/// parse_method() names that subset when the value is not in it.
///
/// Which structure a method needs is decided here too (edge set, fitted forest, v-sphere tree),
/// so that an estimator builds only that (integrators/estimator.cpp).

#include <array>
#include <span>
#include <string>
#include <string_view>

namespace qsil {

namespace edgetree {
enum class NodeTest;     // node_rejection.h
enum class VSphereTest;  // vsphere_tree.h
}  // namespace edgetree

/// A derivative estimator: the boundary-term sampler of `qsil grad`, the interior term alone, or
/// finite differences. The first four are also the four rejection tests of `qsil slices`.
enum class Method {
  Quadric,       ///< `quadric`: edge forest, dual box + bounding quadric pair test [QSS] (default)
  QuadricBox,    ///< `quadric-box`: the same forest with the dual box test only (ablation)
  VSphere,       ///< `vsphere`: Li 2019's Hough-space tree, hollow v-sphere test ([QSS] App. F)
  VSphereSolid,  ///< `vsphere-solid`: redner's original solid v-sphere test
  Uniform,       ///< `uniform`: no rejection, edges by length x dihedral angle (a floor)
  None,          ///< `none`: the interior term only (misses silhouettes, shadows, outlines)
  /// `regularized`: Quinn 2021's blurred visibility, differentiated by the interior term alone
  /// (qsil/integrators/regularized_visibility.h); biased, its bias set by the blur width
  Regularized,
  /// `was`: Bangaru et al. 2020's warped-area sampling: every sampled direction, the camera's too,
  /// warped (qsil/integrators/warp_field.h); biased for a fixed number of auxiliary rays
  WarpedArea,
  /// `projective`: Zhang, Roussel, Jakob 2023's projective sampling without guiding (Mitsuba 3's
  /// `prb_projective` with guiding "none"): the secondary boundary term from boundary segments
  /// sampled over every edge and direction and connected to the camera
  /// (integrators/projective_boundary.h); the primary term as the edge samplers'
  Projective,
  FiniteDifferences,  ///< `fd`: central finite differences with common random numbers
};

/// Every method, in the order above.
inline constexpr std::array<Method, 10> kAllMethods = {
    Method::Quadric, Method::QuadricBox,  Method::VSphere,    Method::VSphereSolid, Method::Uniform,
    Method::None,    Method::Regularized, Method::WarpedArea, Method::Projective,   Method::FiniteDifferences};
/// The methods that sample edges (`qsil candidates`).
inline constexpr std::array<Method, 5> kEdgeSamplingMethods = {Method::Quadric, Method::QuadricBox, Method::VSphere,
                                                               Method::VSphereSolid, Method::Uniform};
/// The methods with a rejection test ([QSS] Fig. 7, `qsil slices`), in display order.
inline constexpr std::array<Method, 4> kRejectionMethods = {Method::Quadric, Method::QuadricBox, Method::VSphere,
                                                            Method::VSphereSolid};
/// The values of `qsil grad --boundary`: every edge sampler, none, regularized, was and projective.
inline constexpr std::array<Method, 9> kBoundaryMethods = {
    Method::Quadric, Method::QuadricBox,  Method::VSphere,    Method::VSphereSolid, Method::Uniform,
    Method::None,    Method::Regularized, Method::WarpedArea, Method::Projective};
/// Unbiased gradient methods (`qsil reference --method`): every edge sampler, and fd.
inline constexpr std::array<Method, 6> kReferenceMethods = {Method::Quadric, Method::QuadricBox,
                                                            Method::VSphere, Method::VSphereSolid,
                                                            Method::Uniform, Method::FiniteDifferences};

/// The method's name on the command line and in outputs: "quadric", "quadric-box", "vsphere",
/// "vsphere-solid", "uniform", "none", "regularized", "was", "projective", "fd".
std::string_view method_name(Method method);

/// The method named `name` among `allowed`. Throws qsil::Error
/// "OPTION 'NAME': unsupported (supported: a, b, ...)" listing `allowed` otherwise.
Method parse_method(std::string_view name, std::string_view option, std::span<const Method> allowed);

/// `allowed` as "a, b, c" (for help texts).
std::string method_list(std::span<const Method> allowed);

/// True for the five edge samplers (a boundary term with a secondary edge sampler).
bool samples_edges(Method method);
/// True for the methods whose boundary term reads the scene's edge set: the five edge samplers
/// and projective (its boundary sample space and the primary edges).
bool uses_edge_set(Method method);
/// True for quadric and quadric-box: sampling traverses the fitted edge forest.
bool uses_edge_forest(Method method);
/// True for quadric only: the forest's nodes carry fitted dual quadrics (the others need none).
bool uses_quadrics(Method method);
/// The secondary boundary-term traversals per path vertex a method uses by default
/// (EstimatorConfig::sppi = 0): 0.5 for quadric and quadric-box, one traversal every other pixel
/// sample (their boundary term is cheap in variance and dear in time against the interior term;
/// measured: docs/experiments/2026-11-25-sample-allocation.md §5 "How many traversals"); 1 for
/// the baselines, whose boundary term holds most of their variance. For projective it is not per
/// vertex: boundary segments per pixel sample (1), as Mitsuba 3's sppi is per pixel.
double default_sppi(Method method);

/// The shading-point speed per extra secondary traversal a method uses (BoundaryContext::
/// split_speed, boundary_split): 4 for quadric and quadric-box, whose rate above is tuned for
/// points moving no faster than the mesh (a point a camera ray meets at a grazing angle slides
/// along the ray at about 1/cos that speed, and its boundary term's variance grows with it;
/// docs/architecture.md §5 "Splitting at fast shading points"); 0 (no splitting) for the
/// baselines, which keep one traversal per vertex as published.
double default_split_speed(Method method);

/// The forest node test of `method` (Quadric or QuadricBox; QSIL_CHECK otherwise).
edgetree::NodeTest node_test(Method method);

/// The v-sphere test of `method` (VSphere or VSphereSolid; QSIL_CHECK otherwise).
edgetree::VSphereTest vsphere_test(Method method);

}  // namespace qsil
