/// @file film.cpp
/// Film accumulation and channel layout; see qsil/film.h.

#include "qsil/film.h"

#include "qsil/dual.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace qsil {

FilmLayout::FilmLayout(int num_params) : num_params_(num_params) {
  QSIL_CHECK(num_params >= 0 && num_params <= kMaxParameters);
}

std::string FilmLayout::derivative_prefix(int k) { return "dtheta" + std::to_string(k); }

std::string FilmLayout::derivative_name(int k, int c) {
  QSIL_DCHECK(c >= 0 && c < 3);
  return derivative_prefix(k) + "." + "RGB"[c];
}

std::vector<std::string> FilmLayout::names() const {
  std::vector<std::string> names{"R", "G", "B"};
  for (int k = 0; k < num_params_; ++k)
    for (int c = 0; c < 3; ++c) names.push_back(derivative_name(k, c));
  return names;
}

std::vector<std::string> FilmLayout::standard_error_names() const {
  std::vector<std::string> names = this->names();
  for (std::string& n : names) n += ".se";
  return names;
}

Film::Film(int width, int height, const FilmLayout& layout, double stratum_fraction)
    : width_(width),
      height_(height),
      channels_(layout.channels()),
      layout_(layout),
      stratum_fraction_(stratum_fraction),
      sum_(size_t(width) * height * channels_, 0.0),
      sum_sq_(size_t(width) * height * channels_, 0.0),
      splat_sum_(size_t(width) * height * channels_, 0.0),
      splat_sq_(size_t(width) * height * channels_, 0.0),
      sum1_(stratum_fraction > 0 ? size_t(width) * height * channels_ : 0, 0.0),
      sum_sq1_(stratum_fraction > 0 ? size_t(width) * height * channels_ : 0, 0.0),
      count_(size_t(width) * height, 0),
      count1_(stratum_fraction > 0 ? size_t(width) * height : 0, 0) {
  QSIL_CHECK(width > 0 && height > 0);
  QSIL_CHECK(stratum_fraction >= 0 && stratum_fraction < 1);
}

namespace {

/// Adds values[0 .. n) to sum[0 .. n) and their squares to sum_sq[0 .. n).
void accumulate(const double* values, int n, double* sum, double* sum_sq) {
  for (int c = 0; c < n; ++c) {
    sum[c] += values[c];
    sum_sq[c] += values[c] * values[c];
  }
}

}  // namespace

void Film::add_sample(int x, int y, const double* values, int stratum) {
  QSIL_DCHECK(x >= 0 && x < width_ && y >= 0 && y < height_ && (stratum == 0 || (stratum == 1 && stratified())));
  const size_t p = size_t(y) * width_ + x;
  accumulate(values, channels_, &sum_[p * channels_], &sum_sq_[p * channels_]);
  ++count_[p];
  if (stratum == 1 && stratified()) {
    accumulate(values, channels_, &sum1_[p * channels_], &sum_sq1_[p * channels_]);
    ++count1_[p];
  }
}

void Film::splat(int x, int y, int channel, double value) {
  QSIL_DCHECK(x >= 0 && x < width_ && y >= 0 && y < height_ && channel >= 0 && channel < channels_);
  const size_t i = (size_t(y) * width_ + x) * channels_ + channel;
  splat_sum_[i] += value;
  splat_sq_[i] += value * value;
}

double Film::mean(int c, int x, int y) const {
  QSIL_DCHECK(c >= 0 && c < channels_);
  const size_t p = size_t(y) * width_ + x;
  const size_t i = p * channels_ + c;
  return count_[p] > 0 ? (sum_[i] + splat_sum_[i]) / double(count_[p]) : 0.0;
}

namespace {

/// The sample variance (n - 1 in the denominator) of n values with this sum and squared sum.
double sample_variance(double sum, double sum_sq, double n) {
  const double m = sum / n;
  const double spread = sum_sq / n - m * m;
  // Samples beyond 1e154 overflow their squares: the variance is beyond a double's range, not 0
  // (std::max(0, NaN) would report a pixel of such samples as the most certain of all).
  if (!std::isfinite(spread)) return std::numeric_limits<double>::infinity();
  return std::max(0.0, spread) * n / (n - 1);
}

}  // namespace

double Film::standard_error(int c, int x, int y) const {
  QSIL_DCHECK(c >= 0 && c < channels_);
  const size_t p = size_t(y) * width_ + x;
  const size_t i = p * channels_ + c;
  const double n = double(count_[p]);
  if (n < 2) return 0.0;
  const double n1 = stratified() ? double(count1_[p]) : 0.0, n0 = n - n1;
  double var_of_sum;  // the variance of the sum of the n samples
  if (n0 >= 2 && n1 >= 2) {
    // Stratified: each stratum's own variance (the strata's means differ), and the variance of
    // the pick's count, floor or ceil of f n, times the squared gap between the strata's means.
    const double s0 = sum_[i] - sum1_[i], m0 = s0 / n0, m1 = sum1_[i] / n1;
    const double fn = stratum_fraction_ * n, g = fn - std::floor(fn);
    var_of_sum = n0 * sample_variance(s0, sum_sq_[i] - sum_sq1_[i], n0) +
                 n1 * sample_variance(sum1_[i], sum_sq1_[i], n1) + g * (1 - g) * (m1 - m0) * (m1 - m0);
  } else {
    var_of_sum = n * sample_variance(sum_[i], sum_sq_[i], n);
  }
  return std::sqrt(var_of_sum / (n * n) + splat_sq_[i] / (n * n));
}

void Film::merge(const Film& other) {
  QSIL_CHECK(other.width_ == width_ && other.height_ == height_ && other.channels_ == channels_ &&
             other.stratum_fraction_ == stratum_fraction_);
  for (size_t i = 0; i < sum_.size(); ++i) {
    sum_[i] += other.sum_[i];
    sum_sq_[i] += other.sum_sq_[i];
    splat_sum_[i] += other.splat_sum_[i];
    splat_sq_[i] += other.splat_sq_[i];
  }
  for (size_t i = 0; i < sum1_.size(); ++i) {
    sum1_[i] += other.sum1_[i];
    sum_sq1_[i] += other.sum_sq1_[i];
  }
  for (size_t i = 0; i < count_.size(); ++i) count_[i] += other.count_[i];
  for (size_t i = 0; i < count1_.size(); ++i) count1_[i] += other.count1_[i];
}

void Film::copy_part(const Film& other, int part, int parts) {
  QSIL_CHECK(other.width_ == width_ && other.height_ == height_ && other.channels_ == channels_ &&
             other.stratum_fraction_ == stratum_fraction_);
  QSIL_CHECK(parts >= 1 && part >= 0 && part < parts);
  const size_t C = size_t(channels_);
  for (size_t p = size_t(part); p < count_.size(); p += size_t(parts)) {
    std::copy_n(&other.sum_[p * C], C, &sum_[p * C]);
    std::copy_n(&other.sum_sq_[p * C], C, &sum_sq_[p * C]);
    count_[p] = other.count_[p];
    if (stratified()) {
      std::copy_n(&other.sum1_[p * C], C, &sum1_[p * C]);
      std::copy_n(&other.sum_sq1_[p * C], C, &sum_sq1_[p * C]);
      count1_[p] = other.count1_[p];
    }
  }
}

std::vector<double> Film::state() const {
  std::vector<double> s;
  s.reserve(state_size());
  for (const std::vector<double>* v : {&sum_, &sum_sq_, &splat_sum_, &splat_sq_, &sum1_, &sum_sq1_})
    s.insert(s.end(), v->begin(), v->end());
  for (long long n : count_) s.push_back(double(n));
  for (long long n : count1_) s.push_back(double(n));
  return s;
}

void Film::set_state(const std::vector<double>& s) {
  QSIL_CHECK(s.size() == state_size());
  auto it = s.begin();
  for (std::vector<double>* v : {&sum_, &sum_sq_, &splat_sum_, &splat_sq_, &sum1_, &sum_sq1_}) {
    std::copy_n(it, v->size(), v->begin());
    it += std::ptrdiff_t(v->size());
  }
  for (long long& n : count_) n = (long long)*it++;
  for (long long& n : count1_) n = (long long)*it++;
}

ImageSum Film::derivative_sum(int k) const {
  const int c = layout_.derivative_mean(k);
  ImageSum s;
  double var = 0, largest = 0;
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      s.sum += mean(c, x, y);
      const double se = standard_error(c, x, y);
      var += se * se;
      if (se * se > largest) {
        largest = se * se;
        s.largest_x = x;
        s.largest_y = y;
      }
    }
  s.standard_error = std::sqrt(var);
  // A pixel whose squared standard error overflowed (a sample beyond 1e154) holds it all.
  s.largest_share = var > 0 ? (std::isfinite(largest) ? largest / var : 1.0) : 0.0;
  return s;
}

bool has_dominant_pixel(const ImageSum& s, const Film& film) {
  return film.width() * film.height() > 1 && s.largest_x >= 0 && s.largest_share >= kDominantPixelShare;
}

std::string dominant_pixel_warning(const ImageSum& s, int k) {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "dtheta%d: pixel (%d, %d) holds %.3g %% of the image sum's variance, as much as all other pixels "
                "together or more: a few samples may carry the sum (a heavy tail?); compare another seed",
                k, s.largest_x, s.largest_y, 100 * s.largest_share);
  return buf;
}

Image Film::to_image() const {
  Image img;
  img.width = width_;
  img.height = height_;
  img.channel_names = layout_.names();
  img.planes.assign(img.channel_names.size(), std::vector<float>(size_t(width_) * height_));
  for (int c = 0; c < int(img.channel_names.size()); ++c)
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x) img.at(c, x, y) = float(mean(c, x, y));
  return img;
}

Image Film::to_image_with_standard_errors() const {
  Image img = to_image();
  const std::vector<std::string> se_names = layout_.standard_error_names();
  for (int c = 0; c < int(se_names.size()); ++c) {
    img.channel_names.push_back(se_names[size_t(c)]);
    img.planes.emplace_back(size_t(width_) * height_);
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x) img.planes.back()[size_t(y) * width_ + x] = float(standard_error(c, x, y));
  }
  return img;
}

}  // namespace qsil
