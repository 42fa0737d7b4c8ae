/// @file preview.cpp
/// PNG previews; see qsil/preview.h.

#include "qsil/preview.h"

#include "qsil/error.h"
#include "qsil/math.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace qsil {

void write_preview_png(const std::filesystem::path& path, const Image& image, double exposure) {
  const int r = image.channel_index("R"), g = image.channel_index("G"), b = image.channel_index("B");
  if (r < 0 || g < 0 || b < 0) throw Error(path.string() + ": image has no R,G,B channels");
  const double scale = std::pow(2.0, exposure);
  std::vector<unsigned char> rgb(size_t(image.width) * image.height * 3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const size_t i = (size_t(y) * image.width + x) * 3;
      const int ch[3] = {r, g, b};
      for (int c = 0; c < 3; ++c)
        rgb[i + size_t(c)] = (unsigned char)std::lround(255.0 * linear_to_srgb(scale * image.at(ch[c], x, y)));
    }
  write_png(path, image.width, image.height, rgb);
}

double write_derivative_png(const std::filesystem::path& path, const Image& image, const std::string& prefix) {
  const int r = image.channel_index(prefix + ".R"), g = image.channel_index(prefix + ".G"),
            b = image.channel_index(prefix + ".B");
  if (r < 0 || g < 0 || b < 0) throw Error(path.string() + ": image has no " + prefix + " channels");
  const size_t n = size_t(image.width) * image.height;
  std::vector<double> lum(n), mags;
  mags.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    lum[i] = luminance(image.planes[size_t(r)][i], image.planes[size_t(g)][i], image.planes[size_t(b)][i]);
    if (std::isfinite(lum[i])) mags.push_back(std::abs(lum[i]));
  }
  double range = 0;
  if (!mags.empty()) {
    const size_t k = std::min(mags.size() - 1, size_t(0.995 * double(mags.size())));
    std::nth_element(mags.begin(), mags.begin() + std::ptrdiff_t(k), mags.end());
    range = mags[k];
  }
  if (!(range > 0)) range = 1.0;
  std::vector<unsigned char> rgb(n * 3);
  for (size_t i = 0; i < n; ++i) {
    const double t = std::clamp(std::isfinite(lum[i]) ? lum[i] / range : 0.0, -1.0, 1.0);
    // Diverging map: white at zero, toward red (positive) or blue (negative), in sRGB.
    const double a = std::abs(t);
    const double red[3] = {0.70, 0.09, 0.17}, blue[3] = {0.13, 0.40, 0.67};
    const double* end = t >= 0 ? red : blue;
    for (int c = 0; c < 3; ++c)
      rgb[3 * i + size_t(c)] = (unsigned char)std::lround(255.0 * ((1 - a) * 1.0 + a * end[c]));
  }
  write_png(path, image.width, image.height, rgb);
  return range;
}

}  // namespace qsil
