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

/// Whether two independent references of the same scene and parameters (e.g. finite differences
/// and the quadric method, or finite differences at steps h and h/2) estimate the same images,
/// judged by their own standard errors (`qsil agree`, tools/references.py).
///
/// Tests, for two-sided Gaussian z = (a - b) / sqrt(se_a^2 + se_b^2):
/// - the image sum of every parameter (sum_z, from the references' sum and sum_se);
/// - every block of block x block pixels, every derivative channel dtheta<k>.R/G/B: the block's
///   sum, with the variance the sum of its pixels' se^2 (pixels are independent). Block sums
///   average out the heavy per-pixel tails that make single-pixel z unreliable at finite spp.
///   Blocks where both variances are 0 (no sample moved there) must be equal (up to 1e-6
///   relative), otherwise they count as disagreeing (infinite z).
/// agrees(): every |sum_z| <= 3 (99.7 % each, if the references agree) and the mean z^2 over the
/// block tests (chi^2 / dof; 1 for agreeing references) <= 1 + 5 sqrt(2 / dof) + 0.25 (five
/// chi^2 standard deviations plus slack for standard errors estimated from the samples
/// themselves). Power: tests/integrators/reference_test.cpp (a 3 % scale error between
/// references whose block z has unit variance is refused; independent ones agree).
///
/// Diagnostic (not part of agrees()): `unseen` counts the tested blocks that one reference never
/// sampled (every pixel 0 with s.e. 0) while the other has a variance, and chi2_per_dof_seen is
/// the mean z^2 without them. Such a block's z tests the other reference against 0, not against
/// a reference that saw the block: an estimator that drew no sample of a rare event there
/// (finite differences at a small step, whose swept slivers a sample seldom hits) reports an s.e.
/// of 0 that is no estimate of its spread. agrees() keeps testing them: between two noisy
/// references a large share of the pixels are seen by one alone, and leaving them out would blind
/// the per-pixel test. Measured: docs/experiments/2026-11-25-header-notes.md,
/// "reference.h: Agreement::unseen".
struct Agreement {
  int block = 8;                ///< block size in pixels
  std::vector<double> sum_z;    ///< per parameter: image-sum z
  long long tests = 0;          ///< block tests with a non-zero variance (blocks x 3 x K)
  long long unequal_exact = 0;  ///< zero-variance blocks whose sums differ
  long long unseen = 0;         ///< tested blocks one reference never sampled (diagnostic, see above)
  double chi2_per_dof = 0;      ///< mean z^2 over the block tests
  double chi2_per_dof_seen = 0; ///< mean z^2 over the block tests that both references sampled
  double max_abs_z = 0;         ///< largest block |z|
  double frac_above_3 = 0;      ///< share of block tests with |z| > 3 (0.27 % if Gaussian)
  /// The squared difference of the two references' expectations, per pixel and derivative
  /// channel, relative to the images' mean square: (sum (a - b)^2 - sum (se_a^2 + se_b^2)) /
  /// sum ((a + b) / 2)^2 over every pixel and derivative channel (the charts' relative MSE of one
  /// against the other, with both noises removed; an unbiased estimate, so it can be < 0). The
  /// bias of a finite-difference step against a smaller one (tools/references.py): a step whose
  /// silhouettes move more than a pixel blurs the derivative image, which block sums hide.
  double excess_rel_mse = 0;
  double noise_rel_mse = 0;     ///< sum (se_a^2 + se_b^2) / sum ((a + b) / 2)^2: what excess_rel_mse removed
  /// Standard error of excess_rel_mse, from the spread of its per-pixel terms d = (a - b)^2 -
  /// (se_a^2 + se_b^2) (pixels independent): sqrt(sum (d - mean d)^2) / sum ((a + b) / 2)^2. When
  /// it is not small against a bias bound, excess_rel_mse cannot show that a step is within the
  /// bound (tools/references.py takes |excess| + 2 se: a 97.7 % upper bound, and a guard against an
  /// s.e. that heavy-tailed noise made too small, which shows as an excess far below 0).
  double excess_se = 0;
  /// The agrees() bound on a mean z^2 over `dof` block tests: 1 + 5 sqrt(2 / dof) + 0.25 (0 for
  /// dof <= 0).
  static double chi2_limit_for(long long dof);
  double chi2_limit() const { return chi2_limit_for(tests); }  ///< the agrees() bound on chi2_per_dof
  /// The same bound for chi2_per_dof_seen (over tests - unseen block tests).
  double chi2_limit_seen() const { return chi2_limit_for(tests - unseen); }
  bool agrees() const;          ///< see above
};

/// Computes the Agreement of two references with the same size and number of parameters;
/// `block` >= 1 (blocks at the right and bottom edges may be smaller). Throws qsil::Error if the
/// sizes or parameter counts differ or block < 1.
Agreement agreement(const Reference& a, const Reference& b, int block = 8);

}  // namespace qsil
