#pragma once
/// @file primary_boundary.h
/// The primary boundary term: pixel coverage changes where silhouettes and outlines of moving
/// shapes cross the image (docs/architecture.md §6). The camera centre o is one fixed point, so its
/// discontinuity edges are found once per render: forest edges of moving shapes that are
/// silhouettes from o (exact per-edge test) and their always-candidate (boundary) edges, each
/// clipped against the near plane and the four frustum planes and projected to the image.
///
/// Estimator: a pixel's value is the integral of L over the pixel (box filter, pixel units), and
/// dx = W(w) dw with W(w) = f_x f_y / cos^3(theta) (pinhole; f the focal lengths in pixels, theta
/// the angle to the optical axis), so [QSS Eq. 3] applies with W in place of f_s cos:
///   dI_pixel/dtheta = sum_e integral s (L_bg - L_fg) W(w(t)) det(w0, w1, v_t)/|w_t|^3 dt
/// over the t whose image point lies in the pixel: a piece of an edge with probability ∝ its
/// weight (PrimaryEdges), a point uniformly along its projected part (so the density in t carries
/// the perspective Jacobian ds/dt), splatted into the pixel it lands in.

#include "qsil/edgetree/edge_set.h"
#include "qsil/film.h"
#include "qsil/integrators/attached_camera.h"
#include "qsil/integrators/edge_point.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/parameters.h"

#include <functional>

namespace qsil {

/// One primary discontinuity edge: its visible parameter range and its projected segment.
struct PrimaryEdge {
  const edgetree::Edge* edge = nullptr;
  double ta = 0, tb = 1;                    ///< the part in front of the near plane and inside the frustum
  Vec2 a = Vec2::Zero(), b = Vec2::Zero();  ///< film positions (pixels) of ta and tb
  double za = 1, zb = 1;                    ///< camera-space depths of ta and tb
  double length = 0;                        ///< |b - a| in pixels
  /// Sampling weight (pixels): length for silhouettes and boundary edges, length * angle / pi
  /// for a crease, whose jump grows with its bend angle (always_edge_weight's scale): a smooth
  /// mesh's many shallow concave creases do not crowd out its silhouettes.
  double weight = 0;
  int first_piece = 0, piece_count = 0;  ///< its pieces in PrimaryEdges::pieces

  /// The fraction t' of the way from ta to tb whose image lies at a + s (b - a), s in [0, 1]:
  /// perspective-correct (s is linear in film position, t' in world position).
  double tp_at(double s) const { return s * za / (zb * (1 - s) + s * za); }
  /// The edge parameter t (of edge->p0 + t (p1 - p0)) whose image lies at a + s (b - a).
  double t_at(double s) const { return ta + tp_at(s) * (tb - ta); }
  /// The world point at projected parameter s.
  Vec3 point_at(double s) const { return edge->p0 + t_at(s) * (edge->p1 - edge->p0); }
};

/// A piece [s0, s1] of a primary edge's projected segment (s = 0 at `a`, 1 at `b`, linear in
/// film position) with its sampling weight: the edge's weight times (s1 - s0), times
/// kPrimaryHiddenShare when the piece was found hidden from the camera (find_primary_edges).
struct PrimaryPiece {
  int edge = 0;  ///< index into PrimaryEdges::edges
  double s0 = 0, s1 = 1;
  double weight = 0;
  bool visible = true;  ///< a test point (an end or the middle) is visible from the camera
};

/// Projected length (pixels) of the pieces a primary edge is cut into for the visibility test:
/// at most this long, at most kPrimaryMaxPieces per edge.
inline constexpr double kPrimaryPieceLength = 1.0;
inline constexpr int kPrimaryMaxPieces = 64;
/// The weight, relative to a visible piece of the same length, of a piece whose three test points
/// (its ends and its middle) are all hidden from the camera: small, never 0, so the estimator stays
/// unbiased where a piece the test called hidden is partly visible (variance, not bias).
inline constexpr double kPrimaryHiddenShare = 1.0 / 8.0;

/// The primary discontinuity edges of a render and the distribution the primary boundary term
/// samples from: a piece of an edge with probability weight / total, and s uniformly in the piece.
struct PrimaryEdges {
  std::vector<PrimaryEdge> edges;
  std::vector<PrimaryPiece> pieces;  ///< every edge's pieces, edge by edge, in order of s
  std::vector<double> cdf;           ///< cumulative piece weights (size pieces + 1, cdf[0] = 0)
  int hidden_pieces = 0;             ///< pieces found hidden (tests)
  /// Found for attached camera hits (attached_camera.h): the silhouettes and boundary edges of
  /// static shapes are among the edges (the flux of an attached shape seen past them), and every
  /// sample adds the attached form's flux (add_primary_boundary).
  bool attached = false;
  CameraAttachment attachment;  ///< the attachment of camera hits (attached only)
  int static_edges = 0;         ///< of the edges, those of static shapes (attached only)
  bool empty() const { return pieces.empty(); }
  /// The density of s on edge `edge` at `s` (per unit s): the weight of its piece that contains s
  /// (the larger one at an end two pieces share) over the piece's length, divided by the total
  /// weight of all pieces (0 for an edge index out of range).
  double density(int edge, double s) const;
};

/// The discontinuity edges of moving shapes seen from the camera centre, clipped and projected
/// (the edge set's tree and always-candidate edges; the edges point into `edges`), cut into pieces
/// of at most kPrimaryPieceLength pixels whose visibility from the camera is tested at their ends
/// and middle with `tracer` (the same test as the boundary term's: a ray to the edge point that
/// ignores the edge's own faces). A hidden piece keeps kPrimaryHiddenShare of its weight, so few
/// samples are spent on hidden contour edges (measured: docs/experiments/2026-11-25-sample-allocation.md
/// §6 "How many primary samples"). The camera is fixed, so this is done once per set-up.
/// `hidden_share` in (0, 1] replaces kPrimaryHiddenShare (tests; 1 weighs every piece by its length
/// alone).
/// `hits` (attached camera hits, attached_camera.h): the attachment (camera_attachment), and,
/// when some vertex is attached (else as for CameraHits::Detached), also the silhouettes and boundary edges of
/// static shapes (not their creases, which have nothing behind them), whose samples carry only the
/// flux of an attached shape seen just past them: a piece of such an edge keeps its full weight
/// when one of its three test points is visible and the ray through it, past the edge, meets a
/// moving shape, else `hidden_share` of it (small, never 0).
PrimaryEdges find_primary_edges(const Scene& scene, const edgetree::EdgeSet& edges, const std::vector<bool>& moving,
                                const RayTracer& tracer, double hidden_share = kPrimaryHiddenShare,
                                CameraHits hits = CameraHits::Detached);

/// Primary edge samples per sample index for a W x H image at `ratio` samples per pixel sample:
/// ratio W H rounded up to a whole chunk of 1024 (at least one chunk), so that runs over ranges
/// that partition [0, spp) draw exactly the samples of the run over [0, spp) for every image size
/// (so below 1024 / (W H) samples per pixel sample the ratio is that: 0.44 at 48 x 48 for 0.25).
/// Throws qsil::Error unless ratio is in (0, 1024].
long long primary_samples_per_index(int width, int height, double ratio);

/// Adds the primary boundary term of the sample range [first_sample, first_sample + spp) to the
/// derivative channels of `film` (a gradient film of velocities.num_params parameters): n =
/// primary_samples_per_index(W, H, ratio) edge samples per sample index. The samples are numbered
/// globally (sample index s owns numbers [s n, (s + 1) n)) and drawn in chunks of 1024 numbers,
/// chunk c from its stream (stream::kPrimary) whichever run draws it (n is a whole number of
/// chunks, so no chunk straddles two sample indices): the sample-range guarantees of estimator.h
/// hold. Deterministic for a seed whatever the thread count (chunks are merged in order). Counts
/// rays and zero contributions in `stats`.
/// Part `part` of `parts` (RenderOptions::parts) draws only the part-th of `parts` contiguous
/// shares of the range's chunks (each exactly as the whole run draws it); with `deferred` its
/// splats are appended there in the order the whole run adds them, instead of to `film`.
void add_primary_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                          const PrimaryEdges& edges, double ratio, int first_sample, int spp, uint64_t seed,
                          int threads, PathStats& stats, int part = 0, int parts = 1,
                          std::vector<FilmSplat>* deferred = nullptr);

/// One contributing primary edge sample (reverse mode): the pixel it lands in, the edge point
/// (edge, t), its weight s (L_bg - L_fg) W / pdf per sample index, and g = (w0 x w1) / |w_t|^3:
/// the pixel's derivative gains weight (g . v) for an edge-point velocity v. With attached camera
/// hits (PrimaryEdges::attached), also what the attached form's flux needs
/// (for_each_attached_side): the jump's two sides, the film position (pixels) and W per_sample /
/// pdf (`scale`, which multiplies the flux as it does the jump).
struct PrimarySample {
  int px = 0, py = 0;
  const edgetree::Edge* edge = nullptr;
  double t = 0;
  Color weight = Color::Zero();
  Vec3 g = Vec3::Zero();
  bool attached = false;  ///< sides, film and scale are set
  EdgeSides sides;
  Vec2 film = Vec2::Zero();
  double scale = 0;
  /// The edge point (world).
  Vec3 point() const { return edge->p0 + t * (edge->p1 - edge->p0); }
};

/// The sides of a primary sample's jump that carry the attached form's flux (attached_camera.h):
/// the flux at an edge point `xe` (world) at film position `film` (pixels) in pixel (px, py) is,
/// per parameter and colour, - sum over the sides of k (L_side - c) (g . v_side), where v_side is the
/// velocity of the material point the side's ray hits (side.hit: shape, triangle, barycentrics u,
/// v) and c the pixel's control variate (CameraAttachment::control).
/// `fn(side, k, L_side - c)` is called for each side whose hit has a non-zero attachment, with
/// k = sign w r_e / r_side: w = b(film) a(hit), the attachment weight of the side's sample
/// position; r_e / r_side, as a point at distance r_side from the camera that moves at v turns its
/// ray as a point at distance r_e (the edge point's) moving at v r_e / r_side.
template <class Fn>
void for_each_attached_side(const Scene& scene, const CameraAttachment& attachment, const EdgeSides& sides,
                            const Vec3& xe, const Vec2& film, int px, int py, Fn&& fn) {
  const double b = attached_bump_1d(film.x() - px) * attached_bump_1d(film.y() - py);
  if (!(b > 0)) return;
  const Vec3 o = scene.camera.origin();
  const Color c = attachment.control_at(px, py);
  for (int i = 0; i < sides.count; ++i) {
    const EdgeSides::Side& side = sides.side[i];
    if (!side.hit.valid()) continue;
    const double a = attachment.at(scene, side.hit.shape, side.hit.triangle, side.hit.u, side.hit.v);
    if (!(a > 0)) continue;
    const Vec3 y = scene.shapes[size_t(side.hit.shape)].mesh.point(side.hit.triangle, side.hit.u, side.hit.v);
    const double r = (y - o).norm();
    if (!(r > 0)) continue;
    fn(side, side.sign * a * b * (xe - o).norm() / r, Color(side.L - c));
  }
}
using PrimarySampleFn = std::function<void(const PrimarySample&)>;

/// The primary boundary term's samples of the range [first_sample, first_sample + spp), drawn
/// exactly as add_primary_boundary draws them (same streams, same chunks), but without velocities:
/// every sample whose edge point is visible and whose jump is non-zero is passed to `fn`, on the
/// calling thread, in chunk order (deterministic for a seed whatever the thread count). The edges
/// are those of the shapes whose vertices are differentiated. Counts rays and zero contributions.
void for_each_primary_sample(const PathContext& ctx, const PrimaryEdges& edges, double ratio, int first_sample, int spp,
                             uint64_t seed, int threads, PathStats& stats, const PrimarySampleFn& fn);

}  // namespace qsil
