#pragma once
/// @file env_map_images.h
/// Environment maps written in tests: an RGB Image from a function of the texel, and the map-frame
/// direction of a texel's centre, both by Mitsuba 3's `envmap` convention written out
/// independently of qsil's EnvironmentLight (include/qsil/environment_light.h).

#include "qsil/image.h"
#include "qsil/math.h"

#include <cmath>
#include <functional>
#include <vector>

namespace qsil::test {

/// The unit map-frame direction of (u, v): theta = pi v from +y, phi = 2 pi u.
inline Vec3 envmap_direction(double u, double v) {
  const double theta = kPi * v, phi = 2 * kPi * u;
  return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

/// A w x h RGB Image with texel(x, y) at column x, row y (top row first), its channels stored in
/// B, G, R order (as in the bundled EXRs, so that readers must look channels up by name).
inline Image envmap_image(int w, int h, const std::function<Color(int, int)>& texel) {
  Image img;
  img.width = w;
  img.height = h;
  img.channel_names = {"B", "G", "R"};
  img.planes.assign(3, std::vector<float>(size_t(w) * size_t(h)));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Color c = texel(x, y);
      img.at(0, x, y) = float(c[2]);
      img.at(1, x, y) = float(c[1]);
      img.at(2, x, y) = float(c[0]);
    }
  return img;
}

}  // namespace qsil::test
