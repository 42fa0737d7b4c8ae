/// @file cli_compare.cpp
/// See cli_compare.h.

#include "cli_compare.h"

#include "qsil/error.h"

#include <cmath>
#include <cstdio>
#include <fstream>

namespace qsil::cli {

GradientMethod parse_gradient_method(const std::string& name) {
  GradientMethod m;
  m.name = name;
  if (name == "fd") m.fd = true;
  else m.boundary = parse_boundary_method(name);
  return m;
}

PassFunction make_gradient_pass(const Scene& scene, const std::vector<ParameterSpec>& params,
                                const GradientMethod& method, const std::vector<double>& steps, int boundary_spp,
                                std::shared_ptr<PassTotals> totals) {
  if (method.fd)
    return [&scene, &params, &steps](const RenderOptions& o) {
      return render_finite_differences(scene, params, steps, o);
    };
  GradientOptions g;
  g.boundary = method.boundary;
  g.boundary_spp = boundary_spp;
  return [&scene, &params, g, totals](const RenderOptions& o) {
    GradientReport rep;
    RenderResult r = render_gradient(scene, params, o, g, &rep);
    if (totals) {
      totals->report.forest_seconds += rep.forest_seconds;
      totals->report.boundary_seconds += rep.boundary_seconds;
      totals->report.traversals += rep.traversals;
      totals->report.zero_traversals += rep.zero_traversals;
    }
    return r;
  };
}

std::vector<double> fd_steps(const Scene& scene, const std::vector<ParameterSpec>& params, const std::vector<double>& h) {
  std::vector<double> steps;
  for (size_t k = 0; k < params.size(); ++k) {
    if (h.empty()) steps.push_back(default_fd_step(scene, params[k]));
    else if (h.size() == 1) steps.push_back(h[0]);
    else if (h.size() == params.size()) steps.push_back(h[k]);
    else throw Error("--h: give one value or one per --param (" + std::to_string(params.size()) + ")");
  }
  return steps;
}

Image reference_image(const RenderResult& r, int num_params) {
  const auto names = gradient_channel_names(num_params);
  Image img = r.film.to_image(names);
  std::vector<std::string> se_names;
  for (const auto& n : names) se_names.push_back(n + ".se");
  const Image se = r.film.standard_error_image(se_names);
  for (size_t c = 0; c < se_names.size(); ++c) {
    img.channel_names.push_back(se_names[c]);
    img.planes.push_back(se.planes[c]);
  }
  for (int k = 0; k < num_params; ++k) {
    const ImageSum s = derivative_image_sum(r.film, num_params, k);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", s.sum);
    img.attributes["qsil:sum" + std::to_string(k)] = buf;
    std::snprintf(buf, sizeof buf, "%.17g", s.standard_error);
    img.attributes["qsil:sum_se" + std::to_string(k)] = buf;
  }
  return img;
}

namespace {
std::string deriv_channel(int k, int c) { return "dtheta" + std::to_string(k) + "." + "RGB"[c]; }
}  // namespace

void summarize_reference(Reference& ref) {
  const Image& im = ref.image;
  const size_t n = size_t(im.width) * im.height;
  double floor = 0, sq = 0;
  ref.sum.assign(ref.num_params, 0);
  ref.sum_se.assign(ref.num_params, 0);
  for (int k = 0; k < ref.num_params; ++k) {
    for (int c = 0; c < 3; ++c) {
      const auto& v = im.planes[im.channel_index(deriv_channel(k, c))];
      const auto& s = im.planes[im.channel_index(deriv_channel(k, c) + ".se")];
      for (size_t i = 0; i < n; ++i) {
        sq += double(v[i]) * v[i];
        floor += double(s[i]) * s[i];
        ref.sum[k] += v[i] / 3.0;
      }
    }
    // The image sum's standard error: exact if the renderer stored it, else a bound from the
    // channel errors (treating R, G, B as fully correlated).
    auto it = im.attributes.find("qsil:sum_se" + std::to_string(k));
    if (it != im.attributes.end()) {
      ref.sum_se[k] = std::stod(it->second);
    } else {
      double var = 0;
      for (size_t i = 0; i < n; ++i) {
        double s = 0;
        for (int c = 0; c < 3; ++c) s += im.planes[im.channel_index(deriv_channel(k, c) + ".se")][i] / 3.0;
        var += s * s;
      }
      ref.sum_se[k] = std::sqrt(var);
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
        if (ref.image.channel_index(deriv_channel(k, c) + suffix) < 0)
          throw Error(path.string() + ": reference has no channel " + deriv_channel(k, c) + suffix +
                      " (render it with `qsil reference`)");
  summarize_reference(ref);
  return ref;
}

ErrorMetrics measure_error(const Film& film, const Reference& ref) {
  ErrorMetrics m;
  const int K = ref.num_params;
  const Image est = film.to_image(gradient_channel_names(K));
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
      const auto& e = est.planes[est.channel_index(deriv_channel(k, c))];
      const auto& r = ref.image.planes[ref.image.channel_index(deriv_channel(k, c))];
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
    const ImageSum s = derivative_image_sum(film, K, k);
    m.sum.push_back(s.sum);
    m.sum_se.push_back(s.standard_error);
    m.sum_error.push_back(s.sum - ref.sum[k]);
  }
  return m;
}

std::vector<float> luminance(const Image& image, const std::string& prefix) {
  const int r = image.channel_index(prefix + ".R"), g = image.channel_index(prefix + ".G"),
            b = image.channel_index(prefix + ".B");
  if (r < 0 || g < 0 || b < 0) throw Error("image has no " + prefix + " channels");
  std::vector<float> out(size_t(image.width) * image.height);
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = float(0.2126 * image.planes[r][i] + 0.7152 * image.planes[g][i] + 0.0722 * image.planes[b][i]);
  return out;
}

void write_npy(const std::filesystem::path& path, int height, int width, const std::vector<float>& data) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(height) + ", " +
                       std::to_string(width) + "), }";
  // Magic (6) + version (2) + header length (2) + header, padded with spaces to a multiple of 64
  // and ended by a newline.
  const size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header.push_back('\n');
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw Error(path.string() + ": cannot write");
    f.write("\x93NUMPY\x01\x00", 8);
    const uint16_t len = uint16_t(header.size());
    const unsigned char l[2] = {(unsigned char)(len & 0xff), (unsigned char)(len >> 8)};
    f.write(reinterpret_cast<const char*>(l), 2);
    f.write(header.data(), std::streamsize(header.size()));
    f.write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size() * sizeof(float)));
    if (!f) throw Error(path.string() + ": write failed");
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace qsil::cli
