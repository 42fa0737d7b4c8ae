#pragma once
/// @file sample_trace.h
/// The largest samples of a forward-mode gradient run, and where along their paths they came from
/// (`qsil grad --largest-samples K`): a mean that agrees with finite differences can hide a tail in
/// which one sample in a million is worth 1e5, and the first question about such a tail is which
/// term, which path vertex, and at what cosine. The estimator keeps, per thread, the K samples of
/// largest |derivative| (TopSamples), then traces each one's path again from its own sampler
/// stream with a recording hook (VertexRecorder) that adds no boundary term to the path: the
/// path's decisions do not depend on the boundary term (it draws from a stream of its own), so the
/// retrace is the same path, and its derivative is the sample's interior term exactly; the rest of
/// the sample is its secondary boundary term, whose edge points the hook evaluates again from
/// their own stream and records beside the path (BoundaryPointTrace). Primary boundary-term
/// samples (splats) are not samples of a pixel and are not among them. The recording hook is
/// integrators/vertex_recorder.h.

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace qsil {

/// One path vertex of a traced sample (derivatives with respect to the sample's parameter).
struct VertexTrace {
  int segments = 0;              ///< segments of the path before the vertex (1: the camera ray's hit)
  int shape = -1, triangle = -1;  ///< what the vertex lies on (scene indices)
  double cos_geometric = 0;      ///< |n_g . wo| (wo toward the previous vertex)
  double cos_shading = 0;        ///< n_s . wo, n_s the shading normal as the BSDF uses it (adapted)
  double dt = 0;                 ///< d(distance along the ray)/d(theta): the slide of the hit on its fixed ray
  double dp = 0;                 ///< |dp/dtheta| (world units per unit of theta)
  double dns = 0;                ///< |d(shading normal)/d(theta)| (per unit of theta)
  /// The derivative (channel mean) the path gains from this vertex on until the next vertex: its
  /// next-event estimate plus the emission found by the segment leaving it (or the environment
  /// it escapes to). Summed over the vertices, with the emission the camera ray finds first
  /// (SampleTrace::camera_emission), it is the sample's interior term.
  double added = 0;
  /// The part of the sample's interior term that arises at this vertex, wherever the path collects
  /// it: the derivative of what this vertex collects with its throughput held (its own shading,
  /// hit and light samples), plus, for every later vertex, what that vertex collects (value) times
  /// the log-derivative of the throughput factor this vertex adds toward the next (its BSDF weight
  /// as its frame and hit move), per colour channel, then the channel mean; the first vertex also
  /// takes the attached camera ray's Jacobian term (SampleTrace::camera_jacobian) and any
  /// derivative of the throughput it starts with. A diffuse hit whose normal turns fast and whose
  /// sampled direction finds a bright mirror shows its derivative here, not at the mirror that
  /// collects the light (`added`). Summed over the vertices, with the camera's emission, it is the
  /// interior term. A vertex's own part includes its hit's motion whatever moves it: where an
  /// earlier vertex's slide moves this hit along a fixed direction, that share is filed here.
  double arises = 0;
};

/// The edge point that adds the most to a sample's secondary boundary term (derivatives with
/// respect to the sample's parameter), and the count and sum of all its edge points: the retrace
/// evaluates the boundary term again from its own stream, so `total` equals the sample's
/// value - interior (a check of the retrace). Its contribution is
/// throughput * bsdf * jump / (pdf * rate) * jacobian (channel means of the colours).
struct BoundaryPointTrace {
  int points = 0;     ///< contributing edge points of the sample (0: none; the fields below unset)
  double total = 0;   ///< the sum of their contributions
  int segments = 0;   ///< segments of the path before the vertex at which the point was sampled
  int shape = -1;     ///< the edge's shape (scene index; for an intersection curve its crossing group, no shape)
  /// What the edge is: 0 a mesh edge that is a silhouette from the vertex, 1 a shading crease
  /// (Edge::crease, not smooth), 2 a smoothed crease (Edge::smooth_crease), 3 a segment of an
  /// intersection curve.
  int kind = 0;
  double pdf = 0;          ///< the point's pdf (per unit t of the edge)
  double rate = 0;         ///< edge points per unit of the estimate (sppi times the split)
  double jump = 0;         ///< |radiance jump| across the edge (channel mean)
  double bsdf = 0;         ///< f_s |cos| toward the point (channel mean)
  double throughput = 0;   ///< the path's throughput to the vertex (channel mean)
  double jacobian = 0;     ///< d(boundary measure)/d(theta) at the point: g . (v_edge - dp/dtheta)
  double distance = 0;     ///< from the vertex to the edge point (scene units)
  double edge_length = 0;  ///< the edge's length (scene units)
  /// |sin| of the angle between the edge and the direction toward the point: an edge seen
  /// end-on projects to a short arc, and the Jacobian of t grows as its inverse.
  double sin_view = 0;
  double added = 0;  ///< this point's contribution
};

/// One sample of a gradient run and its path.
struct SampleTrace {
  int x = 0, y = 0;   ///< pixel
  int sample = 0;     ///< sample index within the pixel (its sampler stream)
  int param = 0;      ///< the parameter whose derivative is largest in magnitude
  double value = 0;   ///< the sample's derivative (channel mean) for `param`: interior + secondary boundary
  double interior = 0;  ///< of which the interior term (the retraced path's derivative)
  double camera_emission = 0;  ///< the derivative of emission seen directly by the camera ray
  /// An attached camera ray's Jacobian term (AttachedCameraRay::apply_jacobian): part of the
  /// interior term, in no vertex's `added` (in the first vertex's `arises`); 0 for a fixed ray.
  double camera_jacobian = 0;
  std::vector<VertexTrace> vertices;  ///< in path order
  BoundaryPointTrace boundary;        ///< its secondary boundary term's largest edge point
};

/// Keeps the `capacity` samples of largest |value| offered to it (by (|value|, pixel, sample) so
/// that the choice does not depend on the order of offers: runs on any thread count keep the
/// same samples), each with whatever path it was offered with.
class TopSamples {
 public:
  explicit TopSamples(int capacity = 0) : capacity_(std::max(0, capacity)) {}
  /// Offers a sample without a path yet (x, y, sample index, parameter, derivative).
  void offer(int x, int y, int sample, int param, double value) {
    SampleTrace s;
    s.x = x;
    s.y = y;
    s.sample = sample;
    s.param = param;
    s.value = value;
    offer(std::move(s));
  }
  /// Offers a sample as it is (its path kept if it is kept). A zero value is never kept.
  void offer(SampleTrace s) {
    if (capacity_ == 0 || !(std::abs(s.value) > 0)) return;
    if (int(heap_.size()) < capacity_) {
      heap_.push_back(std::move(s));
      std::push_heap(heap_.begin(), heap_.end(), larger);
    } else if (larger(s, heap_.front())) {
      std::pop_heap(heap_.begin(), heap_.end(), larger);
      heap_.back() = std::move(s);
      std::push_heap(heap_.begin(), heap_.end(), larger);
    }
  }
  /// Adds every sample of `other`.
  void merge(const TopSamples& other) {
    for (const SampleTrace& s : other.heap_) offer(s);
  }
  /// The kept samples, largest |value| first.
  std::vector<SampleTrace> sorted() const {
    std::vector<SampleTrace> out = heap_;
    std::sort(out.begin(), out.end(), larger);
    return out;
  }

 private:
  /// Strict order: larger |value| first; ties by pixel, then sample index (deterministic).
  static bool larger(const SampleTrace& a, const SampleTrace& b) {
    if (std::abs(a.value) != std::abs(b.value)) return std::abs(a.value) > std::abs(b.value);
    if (a.y != b.y) return a.y < b.y;
    if (a.x != b.x) return a.x < b.x;
    return a.sample < b.sample;
  }
  int capacity_;
  std::vector<SampleTrace> heap_;  ///< a heap whose front is the smallest kept sample
};

}  // namespace qsil
