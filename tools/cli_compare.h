#pragma once
/// @file cli_compare.h
/// Pieces shared by `qsil compare` and `qsil reference`: gradient methods by name (the boundary
/// estimators and finite differences) as progressive passes, reference EXRs with per-pixel
/// standard errors, error metrics against a reference, and .npy output for the plotting script.

#include "qsil/integrators/progressive.h"
#include "qsil/integrators/render.h"
#include "qsil/image.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace qsil::cli {

/// A gradient method of `qsil compare`: a boundary estimator of render_gradient, or "fd".
struct GradientMethod {
  std::string name;     ///< as given: quadric, quadric-box, vsphere, vsphere-solid, uniform, none, fd
  bool fd = false;
  BoundaryMethod boundary = BoundaryMethod::Quadric;
};

/// Parses a method name; throws qsil::Error naming the value otherwise.
GradientMethod parse_gradient_method(const std::string& name);

/// Totals of the boundary term over all passes of a run (zero-contribution rate).
struct PassTotals {
  GradientReport report;   ///< forest/boundary seconds, traversals, zero traversals (summed)
};

/// One pass of `method` on `scene`: render_gradient (boundary_spp discontinuity samples per
/// shading point) or render_finite_differences with `steps`. Adds each pass's GradientReport to
/// `totals` (may be null). The scene and vectors must outlive the returned function.
PassFunction make_gradient_pass(const Scene& scene, const std::vector<ParameterSpec>& params,
                                const GradientMethod& method, const std::vector<double>& steps, int boundary_spp,
                                std::shared_ptr<PassTotals> totals);

/// FD steps: the --h list (empty = default_fd_step per parameter, one value = all, or one each).
/// Throws qsil::Error on a count mismatch.
std::vector<double> fd_steps(const Scene& scene, const std::vector<ParameterSpec>& params, const std::vector<double>& h);

/// Reference image of a gradient: the means (R,G,B, dtheta<k>.R/G/B) and, for every such channel
/// NAME, its per-pixel standard error as channel NAME.se. Image sums are stored as attributes
/// qsil:sum<k> and qsil:sum_se<k>.
Image reference_image(const RenderResult& r, int num_params);

/// A reference read back from an EXR.
struct Reference {
  Image image;
  int num_params = 0;
  std::vector<double> sum, sum_se;   ///< per parameter: image sum and its standard error
  double noise_floor = 0;            ///< mean over pixels and derivative channels of se^2
  double mean_sq = 0;                ///< mean over pixels and derivative channels of ref^2
};

/// Reads and checks a reference EXR (derivative channels and their .se channels for
/// `num_params` parameters, size width x height). Throws qsil::Error naming the file.
Reference read_reference(const std::filesystem::path& path, int num_params, int width, int height);
/// Fills noise_floor, mean_sq, sum, sum_se of a reference held in memory.
void summarize_reference(Reference& ref);

/// Errors of an estimate against the reference, over every pixel and derivative channel
/// (dtheta<k>.R/G/B for all k); pixels with a non-finite estimate are counted and left out.
struct ErrorMetrics {
  double mse = 0;
  double rel_mse = 0;            ///< mse / mean(ref^2)
  std::vector<double> sum;       ///< per parameter: estimate's image sum
  std::vector<double> sum_se;    ///< ...its standard error
  std::vector<double> sum_error; ///< ...minus the reference's image sum
  long long nonfinite_pixels = 0;
};

/// Computes ErrorMetrics of `film` (a gradient film of ref.num_params parameters).
ErrorMetrics measure_error(const Film& film, const Reference& ref);

/// Luminance (0.2126 R + 0.7152 G + 0.0722 B) of channels prefix.R/G/B, row-major, top row first.
std::vector<float> luminance(const Image& image, const std::string& prefix);

/// Writes a float32 2D array as a NumPy .npy file (version 1.0, C order).
void write_npy(const std::filesystem::path& path, int height, int width, const std::vector<float>& data);

}  // namespace qsil::cli
