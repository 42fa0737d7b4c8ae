/// @file reference.cpp
/// See qsil/study/reference.h.

#include "qsil/study/reference.h"

#include "qsil/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace qsil {

Image reference_image(const RenderResult& r) {
  Image img = r.film.to_image_with_standard_errors();
  for (int k = 0; k < r.film.layout().num_params(); ++k) {
    const ImageSum s = r.film.derivative_sum(k);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", s.sum);
    img.attributes["qsil:sum" + std::to_string(k)] = buf;
    std::snprintf(buf, sizeof buf, "%.17g", s.standard_error);
    img.attributes["qsil:sum_se" + std::to_string(k)] = buf;
  }
  return img;
}

void summarize_reference(Reference& ref) {
  const Image& im = ref.image;
  const size_t n = size_t(im.width) * im.height;
  auto plane = [&](int k, int c, const char* suffix) -> const std::vector<float>& {
    return im.planes[size_t(im.channel_index(FilmLayout::derivative_name(k, c) + suffix))];
  };
  double floor = 0, sq = 0;
  ref.sum.assign(size_t(ref.num_params), 0);
  ref.sum_se.assign(size_t(ref.num_params), 0);
  for (int k = 0; k < ref.num_params; ++k) {
    for (int c = 0; c < 3; ++c) {
      const auto& v = plane(k, c, "");
      const auto& s = plane(k, c, ".se");
      for (size_t i = 0; i < n; ++i) {
        sq += double(v[i]) * v[i];
        floor += double(s[i]) * s[i];
        ref.sum[size_t(k)] += v[i] / 3.0;
      }
    }
    // The image sum's standard error: exact if the renderer stored it, else a bound from the
    // channel errors (treating R, G, B as fully correlated).
    auto it = im.attributes.find("qsil:sum_se" + std::to_string(k));
    if (it != im.attributes.end()) {
      ref.sum_se[size_t(k)] = std::stod(it->second);
    } else {
      double var = 0;
      for (size_t i = 0; i < n; ++i) {
        double s = 0;
        for (int c = 0; c < 3; ++c) s += plane(k, c, ".se")[i] / 3.0;
        var += s * s;
      }
      ref.sum_se[size_t(k)] = std::sqrt(var);
    }
  }
  const double count = double(n) * 3 * ref.num_params;
  ref.noise_floor = floor / count;
  ref.mean_sq = sq / count;
}

Reference read_reference(const std::filesystem::path& path, int num_params, int width, int height) {
  Reference ref;
  ref.image = read_exr(path);
  ref.num_params = num_params;
  if (ref.image.width != width || ref.image.height != height)
    throw Error(path.string() + ": reference is " + std::to_string(ref.image.width) + "x" +
                std::to_string(ref.image.height) + ", the scene renders " + std::to_string(width) + "x" +
                std::to_string(height) + " (use the same -D res=...)");
  for (int k = 0; k < num_params; ++k)
    for (int c = 0; c < 3; ++c)
      for (const std::string suffix : {"", ".se"})
        if (ref.image.channel_index(FilmLayout::derivative_name(k, c) + suffix) < 0)
          throw Error(path.string() + ": reference has no channel " + FilmLayout::derivative_name(k, c) + suffix +
                      " (render it with `qsil reference`)");
  summarize_reference(ref);
  return ref;
}

ErrorMetrics measure_error(const Film& film, const Reference& ref) {
  ErrorMetrics m;
  const int K = ref.num_params;
  const Image est = film.to_image();
  const size_t n = size_t(est.width) * est.height;
  std::vector<char> bad(n, 0);
  for (size_t c = 0; c < est.planes.size(); ++c)
    for (size_t i = 0; i < n; ++i)
      if (!std::isfinite(est.planes[c][i])) bad[i] = 1;
  for (size_t i = 0; i < n; ++i) m.nonfinite_pixels += bad[i];
  double se = 0;
  long long count = 0;
  for (int k = 0; k < K; ++k)
    for (int c = 0; c < 3; ++c) {
      const std::string name = FilmLayout::derivative_name(k, c);
      const auto& e = est.planes[size_t(est.channel_index(name))];
      const auto& r = ref.image.planes[size_t(ref.image.channel_index(name))];
      for (size_t i = 0; i < n; ++i) {
        if (bad[i]) continue;
        const double d = double(e[i]) - double(r[i]);
        se += d * d;
        ++count;
      }
    }
  m.mse = count ? se / double(count) : std::nan("");
  m.rel_mse = ref.mean_sq > 0 ? m.mse / ref.mean_sq : std::nan("");
  for (int k = 0; k < K; ++k) {
    const ImageSum s = film.derivative_sum(k);
    m.sum.push_back(s.sum);
    m.sum_se.push_back(s.standard_error);
    m.sum_error.push_back(s.sum - ref.sum[size_t(k)]);
  }
  return m;
}

double Agreement::chi2_limit_for(long long dof) {
  return dof > 0 ? 1.0 + 5.0 * std::sqrt(2.0 / double(dof)) + 0.25 : 0.0;
}

bool Agreement::agrees() const {
  for (double z : sum_z)
    if (!(std::abs(z) <= 3)) return false;
  return unequal_exact == 0 && chi2_per_dof <= chi2_limit();
}

Agreement agreement(const Reference& a, const Reference& b, int block) {
  if (block < 1) throw Error("agreement: block size " + std::to_string(block) + " < 1");
  if (a.image.width != b.image.width || a.image.height != b.image.height)
    throw Error("agreement: the references are " + std::to_string(a.image.width) + "x" +
                std::to_string(a.image.height) + " and " + std::to_string(b.image.width) + "x" +
                std::to_string(b.image.height));
  if (a.num_params != b.num_params)
    throw Error("agreement: the references have " + std::to_string(a.num_params) + " and " +
                std::to_string(b.num_params) + " parameters");
  Agreement g;
  g.block = block;
  for (int k = 0; k < a.num_params; ++k) {
    const double var = a.sum_se[size_t(k)] * a.sum_se[size_t(k)] + b.sum_se[size_t(k)] * b.sum_se[size_t(k)];
    const double d = a.sum[size_t(k)] - b.sum[size_t(k)];
    g.sum_z.push_back(var > 0 ? d / std::sqrt(var) : (d == 0 ? 0.0 : INFINITY));
  }
  const int W = a.image.width, H = a.image.height;
  double chi2 = 0, chi2_seen = 0;
  long long above = 0;
  double diff2 = 0, noise2 = 0, mean2 = 0;  // per pixel: (a - b)^2, se_a^2 + se_b^2, ((a + b) / 2)^2
  double excess2 = 0;                       // per pixel: ((a - b)^2 - se_a^2 - se_b^2)^2
  long long pixels = 0;
  for (int k = 0; k < a.num_params; ++k)
    for (int c = 0; c < 3; ++c) {
      const std::string name = FilmLayout::derivative_name(k, c);
      const int va = a.image.channel_index(name), sa = a.image.channel_index(name + ".se");
      const int vb = b.image.channel_index(name), sb = b.image.channel_index(name + ".se");
      for (int y0 = 0; y0 < H; y0 += block)
        for (int x0 = 0; x0 < W; x0 += block) {
          double sum_a = 0, sum_b = 0, var_a = 0, var_b = 0;
          bool blank_a = true, blank_b = true;  // every pixel 0 with s.e. 0: never sampled
          for (int y = y0; y < std::min(H, y0 + block); ++y)
            for (int x = x0; x < std::min(W, x0 + block); ++x) {
              const double pa = a.image.at(va, x, y), pb = b.image.at(vb, x, y);
              sum_a += pa;
              sum_b += pb;
              const double ea = a.image.at(sa, x, y), eb = b.image.at(sb, x, y);
              var_a += ea * ea;
              var_b += eb * eb;
              blank_a = blank_a && pa == 0 && ea == 0;
              blank_b = blank_b && pb == 0 && eb == 0;
              const double d2 = (pa - pb) * (pa - pb), n2 = ea * ea + eb * eb;
              diff2 += d2;
              noise2 += n2;
              excess2 += (d2 - n2) * (d2 - n2);
              ++pixels;
              mean2 += 0.25 * (pa + pb) * (pa + pb);
            }
          const double d = sum_a - sum_b, var = var_a + var_b;
          if (var == 0) {
            if (std::abs(d) > 1e-6 * (std::abs(sum_a) + std::abs(sum_b))) ++g.unequal_exact;
            continue;
          }
          const double z = d / std::sqrt(var);
          chi2 += z * z;
          if ((blank_a && var_b > 0) || (blank_b && var_a > 0))
            ++g.unseen;
          else
            chi2_seen += z * z;
          g.max_abs_z = std::max(g.max_abs_z, std::abs(z));
          if (std::abs(z) > 3) ++above;
          ++g.tests;
        }
    }
  g.chi2_per_dof = g.tests ? chi2 / double(g.tests) : 0.0;
  g.frac_above_3 = g.tests ? double(above) / double(g.tests) : 0.0;
  g.chi2_per_dof_seen = g.tests > g.unseen ? chi2_seen / double(g.tests - g.unseen) : 0.0;
  g.excess_rel_mse = mean2 > 0 ? (diff2 - noise2) / mean2 : 0.0;
  g.noise_rel_mse = mean2 > 0 ? noise2 / mean2 : 0.0;
  if (mean2 > 0 && pixels > 0) {
    const double sum = diff2 - noise2;
    g.excess_se = std::sqrt(std::max(0.0, excess2 - sum * sum / double(pixels))) / mean2;
  }
  return g;
}

}  // namespace qsil
