/// @file sah_split.cpp
/// Binned SAH split of edges [QSS 4.1].

#include "sah_split.h"

#include <algorithm>
#include <vector>

namespace qsil::edgetree {

namespace {
double box_area(const Box3& b) {
  if (b.empty()) return 0.0;
  const Vec3 e = b.extent();
  return 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
}
}  // namespace

int sah_split(std::span<EdgeBoxRef> edges, int buckets) {
  const int n = int(edges.size());
  Box3 cb;
  for (const auto& e : edges) cb.expand(0.5 * (e.lo + e.hi));
  int axis = 0;
  cb.extent().maxCoeff(&axis);
  const double lo = cb.lo[axis], ext = cb.hi[axis] - cb.lo[axis];
  auto median = [&]() {
    const int mid = n / 2;
    std::stable_sort(edges.begin(), edges.end(), [axis](const EdgeBoxRef& a, const EdgeBoxRef& b) {
      return a.lo[axis] + a.hi[axis] < b.lo[axis] + b.hi[axis];
    });
    return mid;
  };
  if (!(ext > 0.0)) return median();

  const int B = std::max(2, buckets);
  auto bucket_of = [&](const EdgeBoxRef& e) {
    const double c = 0.5 * (e.lo[axis] + e.hi[axis]);
    return std::clamp(int(B * ((c - lo) / ext)), 0, B - 1);
  };
  std::vector<int> cnt(B, 0);
  std::vector<Box3> box(B);
  for (const auto& e : edges) {
    const int k = bucket_of(e);
    cnt[k]++;
    box[k].expand(e.lo);
    box[k].expand(e.hi);
  }
  // Sweep: prefix from the left, suffix from the right.
  std::vector<double> left_cost(B, 0.0);
  std::vector<int> left_n(B, 0);
  Box3 acc;
  int accn = 0;
  for (int k = 0; k < B; ++k) {
    acc.expand(box[k]);
    accn += cnt[k];
    left_cost[k] = box_area(acc) * accn;
    left_n[k] = accn;
  }
  acc = Box3();
  accn = 0;
  double best = kInf;
  int best_k = -1;
  for (int k = B - 1; k >= 1; --k) {
    acc.expand(box[k]);
    accn += cnt[k];
    // split between bucket k-1 and k
    if (left_n[k - 1] == 0 || accn == 0) continue;
    const double c = left_cost[k - 1] + box_area(acc) * accn;
    if (c < best) {
      best = c;
      best_k = k;
    }
  }
  if (best_k < 0) return median();
  auto it = std::partition(edges.begin(), edges.end(), [&](const EdgeBoxRef& e) { return bucket_of(e) < best_k; });
  return int(it - edges.begin());
}

}  // namespace qsil::edgetree
