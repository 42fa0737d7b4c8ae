#pragma once
/// @file reference.h
/// Reference gradient images and the error of an estimate against one (`qsil reference`,
/// `qsil compare`). A reference image holds the means of a gradient film's image channels (R, G,
/// B, dtheta<k>.R/G/B) and, for every such channel NAME, its per-pixel standard error as NAME.se
/// (FilmLayout); the image sums of the derivatives and their standard errors are stored as the
/// attributes qsil:sum<k> and qsil:sum_se<k>.

#include "qsil/film.h"
#include "qsil/image.h"
#include "qsil/integrators/estimator.h"

#include <filesystem>
#include <vector>

namespace qsil {

/// The reference image of a gradient run: Film::to_image_with_standard_errors() with the image
/// sums as attributes qsil:sum<k>, qsil:sum_se<k> (%.17g).
Image reference_image(const RenderResult& r);

/// A reference held in memory (read back from an EXR or just rendered).
struct Reference {
  Image image;
  int num_params = 0;
  std::vector<double> sum, sum_se;  ///< per parameter: image sum and its standard error
  double noise_floor = 0;           ///< mean over pixels and derivative channels of se^2
  double mean_sq = 0;               ///< mean over pixels and derivative channels of ref^2
};

/// Reads and checks a reference EXR (derivative channels and their .se channels for
/// `num_params` parameters, size width x height). Throws qsil::Error naming the file.
Reference read_reference(const std::filesystem::path& path, int num_params, int width, int height);

/// Fills noise_floor, mean_sq, sum, sum_se of a reference from its image (the sums' standard
/// errors from the qsil:sum_se<k> attributes when present, else a bound treating R, G, B as fully
/// correlated).
void summarize_reference(Reference& ref);

/// Errors of an estimate against the reference, over every pixel and derivative channel
/// (dtheta<k>.R/G/B for all k); pixels with a non-finite estimate are counted and left out.
struct ErrorMetrics {
  double mse = 0;
  double rel_mse = 0;             ///< mse / mean(ref^2)
  std::vector<double> sum;        ///< per parameter: estimate's image sum
  std::vector<double> sum_se;     ///< ...its standard error
  std::vector<double> sum_error;  ///< ...minus the reference's image sum
  long long nonfinite_pixels = 0;
};

/// Computes ErrorMetrics of `film` (a gradient film of ref.num_params parameters).
ErrorMetrics measure_error(const Film& film, const Reference& ref);

}  // namespace qsil
