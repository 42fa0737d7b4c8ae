#pragma once
/// @file compare.h
/// The comparison driver of `qsil compare` (docs/architecture.md §11): every method, set up once
/// (one Estimator per method for the whole run), rendered progressively at every budget (equal
/// time) or spp count (equal samples) and measured against a reference (reference.h); results as
/// DIR/results.csv, DIR/results.json (through nlohmann/json) and DIR/images/ (an EXR and a .npy
/// luminance map per method at the largest target, the reference's .npy maps) for
/// tools/plot_compare.py.
///
/// Equal time: a method's budget covers its progressive passes; its one-time set-up (edge set,
/// forest fit, v-sphere tree, ...) is not charged to any budget and is reported per method
/// (setup_seconds in the CSV and JSON, and one log line per method).

#include "qsil/integrators/method.h"
#include "qsil/integrators/projective_sampling.h"
#include "qsil/integrators/warped_area_sampling.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"
#include "qsil/study/progressive.h"
#include "qsil/study/reference.h"

#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace qsil {

/// What to compare and where to write it.
struct CompareOptions {
  std::string scene;                 ///< the scene path as given (outputs carry portable_path of it)
  std::vector<std::string> defines;  ///< the -D list (recorded in results.json)
  std::vector<Method> methods;       ///< any of kAllMethods
  std::vector<double> targets;       ///< budgets in seconds (equal_time) or spp counts
  bool equal_time = true;
  std::string reference;        ///< reference EXR (`qsil reference`); empty: render one
  double reference_factor = 8;  ///< automatic reference: this times the largest target, quadric
  std::vector<double> h;        ///< FD steps (fd_steps())
  /// EstimatorConfig::sppi and sppp of every edge-sampling method (0: each
  /// method's default rate).
  double sppi = 0;
  double sppp = kDefaultSppp;
  /// `regularized`: its blur width as a fraction of the scene's bounding-box diagonal
  /// (Regularization::for_scene).
  double reg_width = 1e-3;
  WarpedAreaSampling warped_area;  ///< was's auxiliary rays (EstimatorConfig::warped_area)
  ProjectiveGuiding projective_guiding;  ///< projective's guide (EstimatorConfig::projective_guiding)
  ForestGuiding forest_guiding;          ///< the quadric methods' guide (EstimatorConfig::forest_guiding)
  std::filesystem::path out;  ///< output directory (created)
  uint64_t seed = 0;          ///< base seed: every method, target and the reference derive theirs
  int threads = 0;
};

/// One measured run: a method at one target.
struct CompareRow {
  Method method = Method::Quadric;
  double target = 0;  ///< budget in seconds, or spp
  int order = 0;      ///< position in the run sequence
  ProgressiveResult run;
  ErrorMetrics err;
  double zero_rate = 0;  ///< boundary samples that contributed nothing (NaN for fd/none)
  uint64_t traversals = 0;
};

/// A method's one-time set-up.
struct CompareSetup {
  Method method = Method::Quadric;
  SetupReport report;
};

/// Everything a comparison measured.
struct CompareReport {
  Reference reference;
  std::string reference_path;         ///< the reference EXR (read or written)
  std::string reference_description;  ///< e.g. "reference/quadric, 1024 spp (automatic)"
  std::vector<double> targets;        ///< sorted
  std::vector<CompareSetup> setups;   ///< in CompareOptions::methods order
  std::vector<CompareRow> rows;       ///< in run order: per target, every method (order rotated per target)
  std::vector<double> fd_steps;
  int width = 0, height = 0;
};

/// Runs the comparison of `options` on `scene` with parameters `params`, writing the images,
/// results.csv and results.json to options.out. Progress lines go to `log` (null: quiet).
/// Throws qsil::Error for bad options (no method, no target, a bad reference, a reference
/// derivative that is zero everywhere).
CompareReport run_compare(const Scene& scene, const std::vector<ParameterSpec>& params, const CompareOptions& options,
                          std::ostream* log);

/// Writes results.csv and results.json of a comparison to options.out (atomically).
void write_compare_results(const CompareReport& report, const std::vector<ParameterSpec>& params,
                           const CompareOptions& options);

}  // namespace qsil
