#pragma once
/// @file film.h
/// Per-pixel accumulation of a film's channels with the running sum and sum of squares of each,
/// so that every output pixel carries its sample mean and the standard error of that mean. Box
/// pixel filter: a sample counts for the pixel it lies in. FilmLayout is the one place that knows
/// which channel holds what.

#include "qsil/check.h"
#include "qsil/image.h"

#include <string>
#include <vector>

namespace qsil {

/// The channel layout of a film and of the images written from it (docs/architecture.md §2):
/// - primal R, G, B: channels 0, 1, 2 (names R, G, B);
/// - per parameter k (0 <= k < K): the derivative dI/dtheta_k R, G, B at 3(1+k) + c
///   (names dtheta<k>.R/G/B);
/// - per parameter k, hidden: the per-sample mean of its three derivative channels at
///   3(1+K) + k (never written to an image: it gives the image sum an exact standard error,
///   because R, G, B are correlated within a sample).
/// A primal film has K = 0 (three channels). Reference images add, for every named channel NAME,
/// its per-pixel standard error as NAME.se.
class FilmLayout {
 public:
  /// The layout for `num_params` parameters (0 for a primal image, at most kMaxParameters = 8;
  /// a larger count is a bug: parameter lists are checked by check_parameter_count).
  explicit FilmLayout(int num_params = 0);

  int num_params() const { return num_params_; }
  /// Stored channels: 3(1+K) + K.
  int channels() const { return 3 * (1 + num_params_) + num_params_; }
  /// Channels written to images (primal and derivatives): 3(1+K).
  int image_channels() const { return 3 * (1 + num_params_); }
  /// Primal colour channel c (0 R, 1 G, 2 B).
  int primal(int c) const {
    QSIL_DCHECK(c >= 0 && c < 3);
    return c;
  }
  /// Derivative channel c (0 R, 1 G, 2 B) of parameter k.
  int derivative(int k, int c) const {
    QSIL_DCHECK(k >= 0 && k < num_params_ && c >= 0 && c < 3);
    return 3 * (1 + k) + c;
  }
  /// The hidden per-sample mean of parameter k's three derivative channels.
  int derivative_mean(int k) const {
    QSIL_DCHECK(k >= 0 && k < num_params_);
    return 3 * (1 + num_params_) + k;
  }
  /// Names of the image channels: R, G, B, then dtheta<k>.R/G/B.
  std::vector<std::string> names() const;
  /// NAME.se for every image channel NAME.
  std::vector<std::string> standard_error_names() const;
  /// "dtheta<k>": the prefix of parameter k's derivative channels.
  static std::string derivative_prefix(int k);
  /// "dtheta<k>.R" (c = 0), ".G" (1), ".B" (2).
  static std::string derivative_name(int k, int c);

 private:
  int num_params_ = 0;
};

/// One splatted estimate, the arguments of Film::splat: `value` added to channel `channel` of pixel
/// (x, y). The primary boundary term of a part run keeps its splats as a list of these, in the
/// order a whole run adds them (RenderOptions::parts, qsil/integrators/distributed.h).
struct FilmSplat {
  int x, y, channel;
  double value;
};

/// Image sum over pixels of the mean of a parameter's R, G, B derivative, and its standard error
/// (pixels are independent: the variances add).
struct ImageSum {
  double sum = 0;
  double standard_error = 0;
  /// The largest share, in [0, 1], that one pixel's squared standard error holds of the image
  /// sum's (standard_error squared), and that pixel (x right, y down; -1 on a film without
  /// variance). Near 1 the image sum's error bar rests on one pixel's samples: where a heavy tail
  /// put one huge sample in a pixel (docs/design-notes.md "Interior-term tails at grazing hits"),
  /// this is how it shows (kDominantPixelShare).
  double largest_share = 0;
  int largest_x = -1, largest_y = -1;
};

/// The ImageSum::largest_share at and above which the CLI and Python warn that one pixel carries
/// the image sum's variance: as much as all the other pixels together or more, so that one pixel
/// can move the sum by as much as the error bar the others give it. On the bundled and stability
/// scenes the runs measured stayed at or below 45 %, and the runs with a single 10^5 sample went
/// far above it (99.8 %); ½ is a floor for "one pixel carries the sum", not a test that finds
/// every tail (docs/experiments/2026-11-27-dominant-pixel.md).
inline constexpr double kDominantPixelShare = 0.5;

class Film;

/// Whether image sum `s` of `film` has a dominant pixel: one pixel of a film of two or more holds
/// at least kDominantPixelShare of the sum's variance (ImageSum::largest_share).
bool has_dominant_pixel(const ImageSum& s, const Film& film);

/// The warning for a dominant pixel of parameter k's image sum `s` (has_dominant_pixel), one line
/// without a final newline: "dtheta<k>: pixel (X, Y) holds S % of the image sum's variance, ...";
/// the CLI and Python add how to choose another seed there.
std::string dominant_pixel_warning(const ImageSum& s, int k);

/// A width x height film of FilmLayout::channels() channels.
class Film {
 public:
  /// A film of width x height pixels. `stratum_fraction` in (0, 1): its pixels' samples come in
  /// two strata (add_sample), stratum 1 picked by a stratified pick of that fraction of a pixel's
  /// samples (boundary_traversals in qsil/integrators/boundary_term.h), whose sums it keeps apart
  /// (W H (2 channels() + 1) more numbers); 0: one stratum.
  Film(int width, int height, const FilmLayout& layout, double stratum_fraction = 0.0);
  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  const FilmLayout& layout() const { return layout_; }
  bool stratified() const { return stratum_fraction_ > 0; }
  double stratum_fraction() const { return stratum_fraction_; }

  /// Adds one sample (channels() values) to pixel (x, y), of stratum 0 or 1 (1 only on a
  /// stratified film): an estimator whose samples of a pixel are not all drawn alike marks the
  /// kind each is (the samples that make one more secondary boundary traversal,
  /// boundary_traversals in qsil/integrators/boundary_term.h: stratum 1), so that
  /// standard_error() weighs each stratum's own variance. Not thread-safe for the same pixel;
  /// the renderer gives each pixel to one thread.
  void add_sample(int x, int y, const double* values, int stratum = 0);
  /// Adds a splatted estimate to pixel (x, y) without counting a sample (primary-edge boundary
  /// samples land in pixels other than the one being sampled). `value` is in the units of one
  /// pixel sample; the pixel's mean becomes (sum of samples + sum of splats) / samples, and its
  /// standard error adds sum(value^2) / samples^2 (the splats are independent; this bound drops
  /// the negligible mean-square correction). Not thread-safe: merge per-thread buffers in a
  /// fixed order (determinism).
  void splat(int x, int y, int channel, double value);
  /// Number of samples of pixel (x, y) (the same for all pixels after a full run).
  long long samples(int x, int y) const { return count_[size_t(y) * width_ + x]; }
  /// Sample mean of channel c at (x, y), splats included (divided by the pixel's sample count).
  double mean(int c, int x, int y) const;
  /// Standard error of the mean of channel c at (x, y): sqrt(sample variance / n); when the pixel
  /// has samples of both strata (add_sample), the stratified estimate
  ///   sqrt((n0 s0² + n1 s1²) / n² + g (1 - g) (m1 - m0)² / n²),
  /// s_i² and m_i the sample variance and mean within stratum i, g the fractional part of
  /// stratum_fraction() × n: the pick's count of stratum-1 samples is floor or ceil of that
  /// product (the second term is its variance over the pick's random rotation; 0 when the product
  /// is whole, e.g. an even spp at 1/2). Where a stratum has fewer than two samples, the pooled
  /// variance (conservative). Splats add their squared sum / n².
  double standard_error(int c, int x, int y) const;
  /// Adds another film's sums (same size, layout and stratification): the films of disjoint sample ranges of the
  /// same estimator merge into the film of their union (sums add, so the result equals one run
  /// over the union up to the rounding of the additions).
  void merge(const Film& other);
  /// The part (0 .. parts - 1) that pixel index y W + x belongs to when a run is split into
  /// `parts` parts (RenderOptions::parts): index mod parts, interleaved so that every part gets an
  /// even share of the image's costly regions.
  static int part_of(long long pixel, int parts) { return int(pixel % parts); }
  /// Copies the samples (sums, squared sums and counts; not the splats) of the pixels of part
  /// `part` of `parts` (part_of) from `other` (same size and layout): copied, not added, so they
  /// are bit for bit the other film's.
  void copy_part(const Film& other, int part, int parts);
  /// The film's whole state as one array of state_size() doubles (sums, squared sums, splat sums,
  /// splat squared sums, on a stratified film stratum 1's sums and squared sums, then sample counts
  /// and on a stratified film stratum 1's sample counts, exact below 2^53), to send it between
  /// processes;
  /// set_state() restores it bit for bit.
  std::vector<double> state() const;
  /// Size of state(): W H (4 channels() + 1), W H (6 channels() + 2) when stratified.
  size_t state_size() const {
    return size_t(width_) * height_ * (stratified() ? 6 * size_t(channels_) + 2 : 4 * size_t(channels_) + 1);
  }
  /// Restores a state() of a film of the same size and layout (a wrong size is a bug: checked).
  void set_state(const std::vector<double>& state);
  /// Image sum of parameter k's derivative (its hidden mean channel) and its standard error.
  ImageSum derivative_sum(int k) const;

  /// The means of the image channels, named by the layout (R, G, B, dtheta<k>.R/G/B).
  Image to_image() const;
  /// to_image() followed by the standard error of every image channel as NAME.se (a reference).
  Image to_image_with_standard_errors() const;

 private:
  int width_, height_, channels_;
  FilmLayout layout_;
  double stratum_fraction_ = 0;
  std::vector<double> sum_, sum_sq_;
  std::vector<double> splat_sum_, splat_sq_;
  std::vector<double> sum1_, sum_sq1_;  ///< the sums of the samples of stratum 1 (stratified films)
  std::vector<long long> count_, count1_;
};

}  // namespace qsil
