/// @file film.cpp
/// Film accumulation; see qsil/film.h.

#include "qsil/film.h"

#include <cmath>

namespace qsil {

Film::Film(int width, int height, int channels)
    : width_(width), height_(height), channels_(channels),
      sum_(size_t(width) * height * channels, 0.0), sum_sq_(size_t(width) * height * channels, 0.0),
      splat_sum_(size_t(width) * height * channels, 0.0), splat_sq_(size_t(width) * height * channels, 0.0),
      count_(size_t(width) * height, 0) {}

void Film::add_sample(int x, int y, const double* values) {
  const size_t p = size_t(y) * width_ + x;
  double* s = &sum_[p * channels_];
  double* q = &sum_sq_[p * channels_];
  for (int c = 0; c < channels_; ++c) {
    s[c] += values[c];
    q[c] += values[c] * values[c];
  }
  ++count_[p];
}

void Film::splat(int x, int y, int channel, double value) {
  const size_t i = (size_t(y) * width_ + x) * channels_ + channel;
  splat_sum_[i] += value;
  splat_sq_[i] += value * value;
}

double Film::mean(int c, int x, int y) const {
  const size_t p = size_t(y) * width_ + x;
  const size_t i = p * channels_ + c;
  return count_[p] > 0 ? (sum_[i] + splat_sum_[i]) / double(count_[p]) : 0.0;
}

double Film::standard_error(int c, int x, int y) const {
  const size_t p = size_t(y) * width_ + x;
  const double n = double(count_[p]);
  if (n < 2) return 0.0;
  const double m = sum_[p * channels_ + c] / n;
  const double var = std::max(0.0, (sum_sq_[p * channels_ + c] / n - m * m)) * n / (n - 1);
  return std::sqrt(var / n + splat_sq_[p * channels_ + c] / (n * n));
}

void Film::merge(const Film& other) {
  for (size_t i = 0; i < sum_.size(); ++i) {
    sum_[i] += other.sum_[i];
    sum_sq_[i] += other.sum_sq_[i];
    splat_sum_[i] += other.splat_sum_[i];
    splat_sq_[i] += other.splat_sq_[i];
  }
  for (size_t i = 0; i < count_.size(); ++i) count_[i] += other.count_[i];
}

Image Film::to_image(const std::vector<std::string>& names) const {
  Image img;
  img.width = width_;
  img.height = height_;
  img.channel_names = names;
  img.planes.assign(names.size(), std::vector<float>(size_t(width_) * height_));
  for (int c = 0; c < int(names.size()) && c < channels_; ++c)
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x) img.at(c, x, y) = float(mean(c, x, y));
  return img;
}

Image Film::standard_error_image(const std::vector<std::string>& names) const {
  Image img = to_image(names);
  for (int c = 0; c < int(names.size()) && c < channels_; ++c)
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x) img.at(c, x, y) = float(standard_error(c, x, y));
  return img;
}

}  // namespace qsil
