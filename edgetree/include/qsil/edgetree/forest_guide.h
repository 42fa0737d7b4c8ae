#pragma once
/// @file forest_guide.h
/// A learnt correction of the edge forest's choices at its upper levels, per region of shading
/// points: guided quadric silhouette sampling, the future work of [QSS] §5.2 ("adding guiding to
/// our method"), in the manner of path guiding (Müller et al. 2017: learn from earlier samples
/// where the integrand's mass lies, mix what was learnt with the unguided choice).
///
/// Layout: the guided *slots* are the forest's nodes of depth <= `depth` below every root and
/// always-candidate root (depth 0: the roots), and its loose always-candidate edges, each with an
/// index of its own in [0, slots()). Shading points are binned by a uniform grid of
/// `resolution` cells per axis over a box (the training points' bounds; a point outside is binned
/// in the nearest cell).
///
/// What is learnt is a *correction* of the unguided choice, not a distribution of its own. The
/// unguided traversal chooses among candidates by their importance at the shading point (LTC
/// integrals, lights, distance: what is known locally), which a region-wide distribution cannot
/// match. What it cannot know (visibility, the radiance a sub-path finds, the velocity) varies
/// slowly over a region. So a cell holds, per slot i, the sum over training samples that chose i
/// at a choice of the traversal of v / P_u(i), v = |contribution| / pdf of the sample, P_u(i) the
/// unguided probability of that choice (GuideRecord): an estimate of r_i = E_p[F_i(p) / P_u(i|p)],
/// F_i the integral of the boundary term's magnitude over the slot's edges; siblings' r differ
/// where the importance mis-weighs them. The guided strategy chooses among candidates that are
/// all slots (the top level, and the children of a node of depth < `depth`) with
///   P_g(i) = w P_u(i) r_i / sum_j P_u(j) r_j + (1 - w) P_u(i),  w = n / (n + kGuidePriorRecords),
/// n the candidates' records in the cell (guided), and everywhere else (and where the products
/// sum to 0) as the unguided one. A distribution learnt on its own (P_g ∝ the summed
/// contributions, path guiding's target) raised the boundary term's variance 1.1-2.6× on 8 of 10
/// scenes at 4 training spp, about as much as this correction did there. Neither pays
/// (docs/experiments/2026-11-26-forest-guiding.md): guiding is off by default.
///
/// A traversal follows the unguided strategy with probability s (the defensive share, > 0) and
/// the guided one otherwise, and the probability of a path to an edge is the one-sample mixture
///   P = s prod P_u + (1 - s) prod P_g
/// over the levels of the path, not a mixture per level: a per-level mixture bounds 1 / P by
/// s^-(levels) times the unguided one, which on the wing nut made tails worse than no guide at
/// all; the path mixture bounds it by 1 / s. Every edge keeps P >= s P_u > 0
/// wherever the unguided traversal can reach it, so guiding never makes a false reject:
/// unbiased for any learnt values.

#include "qsil/edgetree/edge_forest.h"
#include "qsil/math.h"

#include <vector>

namespace qsil::edgetree {

/// Guided levels of a traversal at most (depth 8 and the top level).
inline constexpr int kMaxGuideLevels = 9;

/// Records of a choice's candidates in a cell at which the guided strategy's choice is half the
/// learnt one and half the unguided one (ForestGuide::guided): a prior of that many records that
/// the unguided choice is right, against the sparse cells of short training (5.5× the variance at
/// worst without it, at 4 training spp). One value tried, at 16 training spp only
/// (docs/experiments/2026-11-26-forest-guiding.md).
inline constexpr double kGuidePriorRecords = 32;

/// Values (sums and record counts, 8 bytes each) a guide holds at most: 2^27, 1 GiB. Each cell that
/// learns something holds 2 per slot, and slots grow as 4^depth per root.
inline constexpr size_t kMaxGuideValues = size_t(1) << 27;

/// One training sample of the boundary term at one guided choice, for ForestGuide::train.
struct GuideRecord {
  Vec3 p = Vec3::Zero();  ///< the shading point (world)
  int slot = -1;          ///< the slot the traversal chose (SilhouetteSample::guide_slots)
  /// |contribution| / pdf of the edge point, divided by the slot's unguided probability at that
  /// choice (SilhouetteSample::guide_pu); > 0 and finite (others are skipped).
  double value = 0;
};

/// The parameters of a forest guide.
struct ForestGuideOptions {
  int resolution = 8;  ///< cells per axis of the grid over shading points, in [1, 64]
  int depth = 3;       ///< guided levels below the roots, in [0, 8]
  double share = 0.5;  ///< defensive share s of the unguided choice, in (0, 1]
};

/// Throws qsil::Error ("forest guide: resolution R out of range [1, 64]", and likewise for depth,
/// [0, 8], and the defensive share, (0, 1]) unless the options are valid.
void check_forest_guide_options(const ForestGuideOptions& options);

/// A learnt distribution over the forest's upper levels per cell of shading points (see the file
/// comment). Empty (default-constructed): no slots; the traversal is then unguided.
class ForestGuide {
 public:
  ForestGuide() = default;
  /// The layout for `forest` (slots to `options.depth`), every value 0: guides nothing until
  /// trained. The forest must outlive the guide and stay unchanged (a refit changes no node, so
  /// the layout survives it; values learnt before a refit stay valid weights: any values are
  /// unbiased). Throws qsil::Error when the options are out of range.
  ForestGuide(const EdgeForest& forest, const ForestGuideOptions& options);

  /// Learns from `records` (replacing what was learnt): the grid's box becomes the bounds of
  /// their points, and each record adds its value to its slot in its point's cell. Records with
  /// a slot < 0 or a value not finite and positive are skipped. The result depends on the
  /// records' order only through the rounding of the sums. Throws qsil::Error when the cells
  /// that learn would hold more than kMaxGuideValues values.
  void train(const std::vector<GuideRecord>& records);

  bool empty() const { return slots_ == 0; }
  int slots() const { return slots_; }
  int occupied_cells() const { return int(cell_values_.size() / size_t(std::max(2 * slots_, 1))); }
  double share() const { return options_.share; }
  const ForestGuideOptions& options() const { return options_; }

  /// The slot of forest node `node` (-1: not guided, deeper than `depth`).
  int node_slot(int node) const { return node >= 0 && node < int(node_slot_.size()) ? node_slot_[size_t(node)] : -1; }
  /// The slot of always-candidate edge `index` (into EdgeForest::always_edges(); -1: none, an
  /// edge of an always-candidate tree).
  int loose_edge_slot(int index) const {
    return index >= 0 && index < int(loose_slot_.size()) ? loose_slot_[size_t(index)] : -1;
  }

  /// The values of the cell that holds `p`, one per slot, then the number of records of each
  /// slot, or null where that cell learnt nothing (and for an empty or untrained guide): the
  /// choice is then unguided.
  const double* cell_values(const Vec3& p) const;

  /// The guided strategy's probabilities of a choice among candidates with slots slot[0..k)
  /// (each >= 0) and unguided probabilities pu[0..k): out[i] = w pu_i r_i / sum_j pu_j r_j +
  /// (1 - w) pu_i, r = `values` (cell_values), w = n / (n + kGuidePriorRecords), n the
  /// candidates' records in the cell (the learnt choice trusted as far as its records go). False
  /// (out untouched) where values is null or the products sum to 0: the guided strategy then
  /// chooses as the unguided.
  bool guided(const double* values, const int* slot, int k, const double* pu, double* out) const;

 private:
  ForestGuideOptions options_;
  int slots_ = 0;
  std::vector<int> node_slot_, loose_slot_;
  Box3 box_;
  std::vector<int> cell_of_;         ///< grid cell -> block of cell_values_ (-1: nothing learnt)
  std::vector<double> cell_values_;  ///< blocks of slots_ values
  int cell_index(const Vec3& p) const;
};

}  // namespace qsil::edgetree
