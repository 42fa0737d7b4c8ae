#pragma once
/// @file film.h
/// Per-pixel accumulation of C channels (primal RGB, then RGB per derivative) with the running
/// sum and sum of squares of each channel, so that every output pixel carries its sample mean and
/// the standard error of that mean. Box pixel filter: a sample counts for the pixel it lies in.

#include "qsil/image.h"

#include <string>
#include <vector>

namespace qsil {

class Film {
 public:
  Film(int width, int height, int channels);
  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }

  /// Adds one sample (C values) to pixel (x, y). Not thread-safe for the same pixel; the renderer
  /// gives each pixel to one thread.
  void add_sample(int x, int y, const double* values);
  /// Adds a splatted estimate to pixel (x, y) without counting a sample (primary-edge boundary
  /// samples land in pixels other than the one being sampled). `value` is in the units of one
  /// pixel sample; the pixel's mean becomes (sum of samples + sum of splats) / samples, and its
  /// standard error adds sum(value^2) / samples^2 (the splats are independent; this bound drops
  /// the negligible mean-square correction). Not thread-safe: merge per-thread buffers in a
  /// fixed order (determinism).
  void splat(int x, int y, int channel, double value);
  /// Number of samples per pixel (the same for all pixels after a full pass).
  long long samples(int x, int y) const { return count_[size_t(y) * width_ + x]; }
  /// Sample mean of channel c at (x, y), splats included (divided by the pixel's sample count).
  double mean(int c, int x, int y) const;
  /// Standard error of the mean of channel c at (x, y): sqrt(sample variance / n).
  double standard_error(int c, int x, int y) const;
  /// Adds another film's sums (same size): combining passes of progressive rendering.
  void merge(const Film& other);

  /// The means as an Image with the given channel names (size C).
  Image to_image(const std::vector<std::string>& names) const;
  /// The standard errors as an Image with the given channel names.
  Image standard_error_image(const std::vector<std::string>& names) const;

 private:
  int width_, height_, channels_;
  std::vector<double> sum_, sum_sq_;
  std::vector<double> splat_sum_, splat_sq_;
  std::vector<long long> count_;
};

}  // namespace qsil
