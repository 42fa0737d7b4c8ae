/// @file forest_guide.cpp
/// See forest_guide.h.

#include "qsil/edgetree/forest_guide.h"

#include "qsil/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace qsil::edgetree {

void check_forest_guide_options(const ForestGuideOptions& options) {
  if (!(options.resolution >= 1 && options.resolution <= 64))
    throw Error("forest guide: resolution " + std::to_string(options.resolution) + " out of range [1, 64]");
  if (!(options.depth >= 0 && options.depth <= 8))
    throw Error("forest guide: depth " + std::to_string(options.depth) + " out of range [0, 8]");
  if (!(options.share > 0 && options.share <= 1))
    throw Error("forest guide: defensive share " + std::to_string(options.share) + " out of range (0, 1]");
}

ForestGuide::ForestGuide(const EdgeForest& forest, const ForestGuideOptions& options) : options_(options) {
  check_forest_guide_options(options);
  node_slot_.assign(forest.nodes().size(), -1);
  loose_slot_.assign(forest.always_edges().size(), -1);
  // Breadth-first from every root, to `depth`: a node's children get consecutive slots.
  std::vector<int> level;
  auto add_root = [&](int r) {
    node_slot_[size_t(r)] = slots_++;
    level.push_back(r);
  };
  for (int r : forest.roots()) add_root(r);
  for (int r : forest.always_roots()) add_root(r);
  for (int i : forest.loose_always_edges()) loose_slot_[size_t(i)] = slots_++;
  for (int d = 0; d < options.depth && !level.empty(); ++d) {
    std::vector<int> next;
    for (int n : level) {
      const ForestNode& node = forest.node(n);
      if (node.is_leaf()) continue;
      for (int c = node.first; c < node.first + node.count; ++c) {
        node_slot_[size_t(c)] = slots_++;
        next.push_back(c);
      }
    }
    level.swap(next);
  }
}

int ForestGuide::cell_index(const Vec3& p) const {
  const int R = options_.resolution;
  int idx = 0;
  for (int a = 0; a < 3; ++a) {
    const double extent = box_.hi[a] - box_.lo[a];
    const double u = extent > 0 ? (p[a] - box_.lo[a]) / extent : 0.0;
    // Clamped before the cast (a box thin on one axis makes u huge off it); NaN lands in cell 0
    // (the comparison is false): a valid cell whatever p is.
    const int i = u > 0 ? std::min(R - 1, int(std::min(u, 1.0) * R)) : 0;
    idx = idx * R + i;
  }
  return idx;
}

void ForestGuide::train(const std::vector<GuideRecord>& records) {
  auto valid = [&](const GuideRecord& r) {
    return r.slot >= 0 && r.slot < slots_ && r.value > 0 && std::isfinite(r.value) && r.p.allFinite();
  };
  box_ = Box3();
  for (const GuideRecord& r : records)
    if (valid(r)) box_.expand(r.p);
  const int R = options_.resolution;
  cell_of_.assign(size_t(R) * R * R, -1);
  cell_values_.clear();
  if (box_.empty()) return;
  for (const GuideRecord& r : records) {
    if (!valid(r)) continue;
    int& block = cell_of_[size_t(cell_index(r.p))];
    if (block < 0 && cell_values_.size() + 2 * size_t(slots_) > kMaxGuideValues)
      throw Error("forest guide: more than " + std::to_string(kMaxGuideValues) + " values (" + std::to_string(slots_) +
                  " slots per cell); lower --forest-guide-resolution or --forest-guide-depth");
    if (block < 0) {
      block = occupied_cells();
      cell_values_.resize(cell_values_.size() + 2 * size_t(slots_), 0.0);
    }
    double* v = cell_values_.data() + 2 * size_t(block) * size_t(slots_);
    v[r.slot] += r.value;
    v[slots_ + r.slot] += 1;
  }
}

const double* ForestGuide::cell_values(const Vec3& p) const {
  if (cell_values_.empty()) return nullptr;
  const int block = cell_of_[size_t(cell_index(p))];
  return block < 0 ? nullptr : cell_values_.data() + 2 * size_t(block) * size_t(slots_);
}

bool ForestGuide::guided(const double* values, const int* slot, int k, const double* pu, double* out) const {
  if (!values) return false;
  double sum = 0, n = 0;
  for (int i = 0; i < k; ++i) {
    sum += pu[i] * values[slot[i]];
    n += values[slots_ + slot[i]];
  }
  if (!(sum > 0) || !std::isfinite(sum)) return false;
  const double learnt = n / (n + kGuidePriorRecords);
  for (int i = 0; i < k; ++i) out[i] = learnt * pu[i] * values[slot[i]] / sum + (1 - learnt) * pu[i];
  return true;
}

}  // namespace qsil::edgetree
