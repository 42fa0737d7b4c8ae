#pragma once
/// @file cli_common.h
/// Pieces shared by the subcommands of `qsil`: the common flags and options (CLI11), scene
/// loading with -D overrides and warnings, EXR output with metadata, warnings, running the
/// chart scripts, and the process group of an MPI job (qsil/integrators/distributed.h).

#include "qsil/image.h"
#include "qsil/integrators/distributed.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/method.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

#include "cli_parse.h"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace qsil::cli {

/// Sets the process group of this program (main() makes it first; it must outlive every command).
void set_process_group(const ProcessGroup& group);
/// The process group set by set_process_group, or a group of one process.
const ProcessGroup& process_group();

/// Collective: runs `step` on rank 0 only (printing, writing outputs), and agrees on its outcome
/// (ProcessGroup::all_or_none), so that a failure there ends every rank with the same exit code.
template <class F>
void on_root(F&& step) {
  const ProcessGroup& group = process_group();
  group.all_or_none([&] {
    if (group.root()) step();
  });
}

/// Flags every rendering subcommand has.
struct CommonFlags {
  std::string scene;
  std::vector<std::string> defines;  ///< -D name=value
  RenderOptions render;
  std::string output;
  std::string preview;
  double exposure = 0;  ///< preview exposure in stops
};

/// Adds SCENE, -D, --spp, --seed, --threads, -o, --preview, --exposure, --quiet to `app`.
void add_common_flags(CLI::App& app, CommonFlags& flags, const std::string& default_output);

/// Adds the positional SCENE and the repeatable -D name=value.
void add_scene_options(CLI::App& app, std::string& scene, std::vector<std::string>& defines);

/// Adds the repeatable --param SPEC (1 to 8), required.
void add_param_option(CLI::App& app, std::vector<std::string>& params);

/// Adds --sppi R, alias --boundary-spp (secondary boundary-term samples per shading point on
/// average over a pixel's samples; 0: the method's default; EstimatorConfig::sppi), and --sppp R,
/// alias --primary-samples (primary boundary-term edge samples per pixel sample,
/// EstimatorConfig::sppp).
void add_sample_rate_options(CLI::App& app, double& sppi, double& sppp);

/// The boundary-term flags of `grad`, `reverse` and `reference`.
struct BoundaryFlags {
  std::string method = "quadric";  ///< a --boundary (or --method) name, parse_method
  double sppi = 0;
  double sppp = kDefaultSppp;
  bool intersection_curves = true;  ///< false: --no-intersection-curves
  std::string camera_hits = "adaptive";  ///< --camera-hits (EstimatorConfig::camera_hits, camera_hits_named)
  int camera_control_spp = kAttachedControlSpp;  ///< --camera-control-spp (EstimatorConfig::camera_control_spp)
  /// --reg-width: regularized's blur width, as a fraction of the scene's bounding-box diagonal
  /// (Regularization::for_scene).
  double reg_width = 1e-3;
  /// --was-rays, --was-kappa, --was-exponent: was's auxiliary rays (WarpedAreaSampling).
  WarpedAreaSampling warped_area;
  /// --guiding-resolution, --guiding-share, --guiding-training, --guiding-octree, --guiding-seeds:
  /// projective's guide (ProjectiveGuiding).
  ProjectiveGuiding projective_guiding;
  /// --forest-guide-training, --forest-guide-rounds, --forest-guide-resolution,
  /// --forest-guide-depth, --forest-guide-share: the quadric methods' forest guide (ForestGuiding).
  ForestGuiding forest_guiding;
};

/// Adds --was-rays, --was-kappa and --was-exponent (WarpedAreaSampling) to `app`, into `was`;
/// `what` says for which option (for the help text).
void add_warped_area_options(CLI::App& app, WarpedAreaSampling& was, const std::string& what);

/// Adds --guiding-resolution R (0: none), --guiding-share S, --guiding-training T, --guiding-octree and
/// --guiding-seeds S (ProjectiveGuiding)
/// to `app`, into `guiding`; `what` says for which option (for the help text).
void add_projective_guiding_options(CLI::App& app, ProjectiveGuiding& guiding, const std::string& what);

/// Adds --forest-guide-training SPP (0: none), --forest-guide-rounds N, --forest-guide-resolution R,
/// --forest-guide-depth D and --forest-guide-share S (ForestGuiding) to `app`, into `guiding`;
/// `what` says for which option (for the help text).
void add_forest_guiding_options(CLI::App& app, ForestGuiding& guiding, const std::string& what);

/// Adds --reg-width W (Regularization::for_scene) to `app`, into `width`; `what` says what it
/// regularises (for the help text).
void add_regularization_options(CLI::App& app, double& width, const std::string& what);

/// Adds the method option `method_option` (e.g. "--boundary") with `method_help`, --sppi and
/// --sppp, and with `curves_flag` --no-intersection-curves (EstimatorConfig::intersection_curves).
void add_boundary_flags(CLI::App& app, BoundaryFlags& flags, const std::string& method_option,
                        const std::string& method_help, bool curves_flag);

/// The gradient configuration of `params` over `scene` with `method` and the rates, switches and
/// (for regularized) the blur of `flags`.
EstimatorConfig gradient_config(const Scene& scene, std::vector<ParameterSpec> params, Method method,
                                const BoundaryFlags& flags);

/// A scene and an estimator over it (set_up_estimator). The estimator refers to the scene: the
/// struct is neither copied nor moved.
struct SceneEstimator {
  SceneEstimator() = default;
  SceneEstimator(const SceneEstimator&) = delete;
  SceneEstimator& operator=(const SceneEstimator&) = delete;
  std::optional<Scene> scene;
  std::vector<ParameterSpec> params;
  std::optional<Estimator> estimator;
};

/// Collective: loads the scene of `flags`, parses `param_specs` against it and builds the
/// estimator of `make_config(scene, params)` into `out`, on every rank of the process group or on
/// none (ProcessGroup::all_or_none: a failure on any rank ends every rank with its message).
void set_up_estimator(const CommonFlags& flags, const std::vector<std::string>& param_specs,
                      const std::function<EstimatorConfig(const Scene&, const std::vector<ParameterSpec>&)>& make_config,
                      SceneEstimator& out);

/// Adds --h H (finite-difference steps: one for all, or one per --param).
void add_fd_step_option(CLI::App& app, std::vector<double>& h);

/// Parses the -D list and loads the scene, printing counted warnings to stderr (on rank 0 of the
/// process group only). Throws qsil::Error.
Scene load_scene_with_flags(const std::string& scene, const std::vector<std::string>& defines);

/// Standard EXR attributes (scene, spp, seed, seconds, defines; processes when the process group
/// has more than one).
void add_render_attributes(Image& image, const CommonFlags& flags, const RenderResult& r);

/// Prints a warning line if samples were non-finite (they were replaced by 0), and one if
/// `invalid_rays` rays were invalid for Embree (RayTracer::total_invalid_rays(), summed over the
/// process group: treated as misses).
void report_nonfinite(const RenderResult& r, uint64_t invalid_rays);

/// Collective: RayTracer::total_invalid_rays() summed over the process group (every rank).
uint64_t group_invalid_rays();

/// ", N processes" when the process group has N > 1 processes, else "" (for summary lines).
std::string processes_note();

/// Mrays/s of a run (0 for a run without time).
double mrays_per_second(const RenderResult& r);

/// "; pixel (X, Y) holds S % of its variance" for an image-sum line (ImageSum::largest_share), or
/// "" on a film without variance.
std::string largest_share_note(const ImageSum& s);

/// Where has_dominant_pixel(s, film): one warning line on stderr, "qsil COMMAND: warning:
/// " + dominant_pixel_warning(s, k), naming --seed and, with `largest_samples_hint`, grad's
/// --largest-samples. Nothing otherwise.
void warn_if_dominant_pixel(const std::string& command, int k, const ImageSum& s, const Film& film,
                            bool largest_samples_hint);

/// Writes a gradient EXR (R,G,B + dtheta<k>.R/G/B, each parameter spec as attribute
/// qsil:param<k>, `method` as qsil:method), and with a preview directory one diverging PNG per
/// parameter plus the primal PNG; prints each parameter's image sum +- standard error, the pixel
/// that holds the largest share of its variance, and preview range; then, once the EXR and
/// previews are written, warns on stderr (warn_if_dominant_pixel, as `qsil COMMAND`: "grad" or "fd") where that
/// pixel dominates.
void write_gradient_outputs(const CommonFlags& flags, const std::vector<ParameterSpec>& params, const RenderResult& r,
                            const std::string& preview_dir, const std::string& command, const std::string& method);

/// Adds `--scripts-dir DIR` (where the chart scripts are, see find_script) to `app`.
void add_scripts_dir_option(CLI::App& app, std::string& scripts_dir);

/// Where a study command (`candidates`, `slices`) writes its pictures, and whether it draws the
/// labelled grid with its chart script.
struct ChartOutputFlags {
  std::string out_dir;  ///< "" = the command's default
  bool no_grid = false;
  std::string scripts_dir;
};

/// Adds --out-dir (`default_dir` named in the help), --no-grid and --scripts-dir.
void add_chart_output_options(CLI::App& app, ChartOutputFlags& flags, const std::string& default_dir);

/// The chart script `name` (e.g. "plot_compare.py"), looked up in this order, independent of the
/// working directory and of where the source tree was: `scripts_dir` (--scripts-dir) if
/// non-empty, the environment variable QSIL_SCRIPTS_DIR if set, `<exe_dir>/share/qsil` (the build
/// tree: CMake copies tools/*.py there) and `<exe_dir>/../share/qsil` (an installed layout:
/// bin/qsil and share/qsil/*.py), where exe_dir is the directory of the running executable
/// (/proc/self/exe). Returns an empty path if no candidate directory holds the file.
std::filesystem::path find_script(const std::string& name, const std::string& scripts_dir);

/// Runs `PYTHON SCRIPT ARGS...` with the script located by find_script and waits for it. PYTHON is
/// the environment variable QSIL_PYTHON if set (e.g. /usr/bin/python3 when another python3 without
/// matplotlib shadows Debian's on PATH), else `python3` found on PATH; arguments are passed
/// without a shell. Returns its exit code; -1 with a warning line on stderr (prefixed by `who`)
/// when the script is not found, python3 cannot be started or the script fails.
int run_python_script(const std::string& who, const std::string& name, const std::vector<std::string>& args,
                      const std::string& scripts_dir);

}  // namespace qsil::cli
