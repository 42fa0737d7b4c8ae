/// @file ltc_fit.cpp
/// The LTC fit; see qsil/edgetree/ltc_fit.h.

#include "qsil/edgetree/ltc_fit.h"

#include "qsil/bsdf.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/sampling.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace qsil::edgetree {

namespace {

using Params = std::array<double, 4>;

struct Target {
  double alpha = 1;
  Vec3 wo = Vec3::UnitZ();
  double albedo = 0;
  Vec3 avg = Vec3::UnitZ();
  Mat3 R = Mat3::Identity();
  // BRDF samples: direction, target density f cos / albedo (0 below the horizon), BRDF pdf.
  std::vector<Vec3> bx;
  std::vector<double> bf, bp;
  // Cosine-domain samples for the LTC strategy.
  std::vector<Vec3> cs;
};

double target_density(const Target& t, const Vec3& w) {
  return w.z() > 0.0 ? ggx_eval_cos<double>(t.alpha, w, t.wo) / t.albedo : 0.0;
}

Target make_target(double alpha, double cos_theta, int n_fit) {
  Target t;
  t.alpha = alpha;
  const double c = std::clamp(cos_theta, kLTCMinCos, 1.0);
  t.wo = Vec3(std::sqrt(std::max(0.0, 1.0 - c * c)), 0.0, c);
  // Albedo and average direction from 128 x 128 stratified visible-normal samples.
  const int na = 128;
  double alb = 0.0;
  Vec3 avg = Vec3::Zero();
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < na; ++j) {
      const Vec2 u((i + 0.5) / na, (j + 0.5) / na);
      const Vec3 m = ggx_sample_visible_normal(alpha, t.wo, u);
      const Vec3 wi = reflect(t.wo, m);
      if (!(wi.z() > 0.0)) continue;
      const double pdf = ggx_reflection_pdf(alpha, wi, t.wo);
      if (!(pdf > 0.0)) continue;
      const double w = ggx_eval_cos<double>(alpha, wi, t.wo) / pdf;
      alb += w;
      avg += w * wi;
    }
  t.albedo = alb / (na * na);
  avg.y() = 0.0;  // symmetric about the xz-plane
  t.avg = avg.norm() > 0 ? Vec3(avg / avg.norm()) : Vec3::UnitZ();
  const double ca = t.avg.z(), sa = t.avg.x();
  t.R << ca, 0.0, sa, 0.0, 1.0, 0.0, -sa, 0.0, ca;
  for (int i = 0; i < n_fit; ++i)
    for (int j = 0; j < n_fit; ++j) {
      const Vec2 u((i + 0.5) / n_fit, (j + 0.5) / n_fit);
      const Vec3 m = ggx_sample_visible_normal(alpha, t.wo, u);
      const Vec3 wi = reflect(t.wo, m).normalized();
      const double p = ggx_reflection_pdf(alpha, wi, t.wo);
      if (!(p > 0.0)) continue;
      t.bx.push_back(wi);
      t.bf.push_back(target_density(t, wi));
      t.bp.push_back(p);
      t.cs.push_back(square_to_cosine_hemisphere(u));
    }
  return t;
}

Mat3 forward_matrix(const Target& t, const Params& p) {
  Mat3 P;
  P << p[0], 0.0, p[2], 0.0, p[1], 0.0, p[3], 0.0, 1.0;
  return t.R * P;
}

/// LTC density of the forward matrix M (det_inv = 1/det M) at unit w, over the whole sphere.
double ltc_density(const Mat3& M_inv, double det_inv, const Vec3& w) {
  const Vec3 c = M_inv * w;
  if (!(c.z() > 0.0)) return 0.0;
  const double l = c.norm();
  return c.z() / l * kInvPi * std::abs(det_inv) / (l * l * l);
}

/// Balance-heuristic estimate of  integral |target - D|^k  over the sphere (k = 3 for the fit,
/// k = 1 for the report), samples from the BRDF and from the LTC.
double error(const Target& t, const Params& p, int k) {
  const Mat3 M = forward_matrix(t, p);
  const double det = M.determinant();
  if (!(det > 0.0) || !std::isfinite(det) || !(p[0] > 0.0) || !(p[1] > 0.0)) return 1e300;
  const Mat3 Mi = M.inverse();
  const double det_inv = 1.0 / det;
  auto pw = [k](double x) { return k == 3 ? x * x * x : x; };
  double e = 0.0;
  const size_t n = t.bx.size();
  for (size_t i = 0; i < n; ++i) {
    const double d = ltc_density(Mi, det_inv, t.bx[i]);
    e += pw(std::abs(t.bf[i] - d)) / (t.bp[i] + d);
  }
  for (size_t i = 0; i < n; ++i) {
    const Vec3 mc = M * t.cs[i];
    const double l = mc.norm();
    const Vec3 w = mc / l;
    const double d = t.cs[i].z() * kInvPi * det_inv * l * l * l;  // D at w = Mc/|Mc|
    if (!(d > 0.0) || !std::isfinite(d)) continue;
    const double f = target_density(t, w);
    const double pb = ggx_reflection_pdf(t.alpha, w, t.wo);
    e += pw(std::abs(f - d)) / (pb + d);
  }
  return e / double(n);
}

/// LTC mass below the shading horizon (samples from the LTC).
double mass_below(const Target& t, const Params& p) {
  const Mat3 M = forward_matrix(t, p);
  int below = 0;
  for (const Vec3& c : t.cs) below += (M * c).z() <= 0.0;
  return double(below) / double(t.cs.size());
}

/// Nelder-Mead (Nelder & Mead 1965; standard coefficients 1, 2, 0.5, 0.5) from x0 with initial
/// steps of 10% of each |coordinate| (at least `min_step`).
Params nelder_mead(const Target& t, const Params& x0, int max_evals, double min_step) {
  constexpr int n = 4;
  std::array<Params, n + 1> s;
  std::array<double, n + 1> f;
  s[0] = x0;
  for (int i = 0; i < n; ++i) {
    s[size_t(i + 1)] = x0;
    s[size_t(i + 1)][size_t(i)] += std::max(0.1 * std::abs(x0[size_t(i)]), min_step);
  }
  int evals = 0;
  auto F = [&](const Params& x) {
    ++evals;
    return error(t, x, 3);
  };
  for (int i = 0; i <= n; ++i) f[size_t(i)] = F(s[size_t(i)]);
  while (evals < max_evals) {
    std::array<int, n + 1> idx;
    for (int i = 0; i <= n; ++i) idx[size_t(i)] = i;
    std::sort(idx.begin(), idx.end(), [&](int a, int b) { return f[size_t(a)] < f[size_t(b)]; });
    std::array<Params, n + 1> s2;
    std::array<double, n + 1> f2;
    for (int i = 0; i <= n; ++i) {
      s2[size_t(i)] = s[size_t(idx[size_t(i)])];
      f2[size_t(i)] = f[size_t(idx[size_t(i)])];
    }
    s = s2;
    f = f2;
    if (f[n] - f[0] <= 1e-9 * std::abs(f[0]) + 1e-300) break;
    Params c{};
    for (int i = 0; i < n; ++i)
      for (int d = 0; d < n; ++d) c[size_t(d)] += s[size_t(i)][size_t(d)] / n;
    auto along = [&](double a) {
      Params x;
      for (int d = 0; d < n; ++d) x[size_t(d)] = c[size_t(d)] + a * (s[n][size_t(d)] - c[size_t(d)]);
      return x;
    };
    const Params xr = along(-1.0);
    const double fr = F(xr);
    if (fr < f[0]) {
      const Params xe = along(-2.0);
      const double fe = F(xe);
      if (fe < fr) {
        s[n] = xe;
        f[n] = fe;
      } else {
        s[n] = xr;
        f[n] = fr;
      }
    } else if (fr < f[n - 1]) {
      s[n] = xr;
      f[n] = fr;
    } else {
      const bool outside = fr < f[n];
      const Params xc = along(outside ? -0.5 : 0.5);
      const double fc = F(xc);
      if (fc < (outside ? fr : f[n])) {
        s[n] = xc;
        f[n] = fc;
      } else {
        for (int i = 1; i <= n; ++i) {
          for (int d = 0; d < n; ++d)
            s[size_t(i)][size_t(d)] = s[0][size_t(d)] + 0.5 * (s[size_t(i)][size_t(d)] - s[0][size_t(d)]);
          f[size_t(i)] = F(s[size_t(i)]);
        }
      }
    }
  }
  int best = 0;
  for (int i = 1; i <= n; ++i)
    if (f[size_t(i)] < f[size_t(best)]) best = i;
  return s[size_t(best)];
}

}  // namespace

std::vector<LTCFitNode> fit_ltc_table(const std::function<void(double alpha)>& progress) {
  constexpr int NA = kLTCAlphaCount, NC = kLTCCosCount;
  std::vector<LTCFitNode> table(size_t(NA * NC));
  Params prev_row0{1.0, 1.0, 0.0, 0.0};
  for (int i = NA - 1; i >= 0; --i) {
    const double alpha = ltc_table_alpha(i);
    Params prev = prev_row0;
    for (int j = 0; j < NC; ++j) {
      const Target t = make_target(alpha, ltc_table_cos(j), 32);
      // Two rounds of Nelder-Mead (the restart rebuilds a fresh simplex around the optimum).
      Params p = nelder_mead(t, prev, 600, 1e-3 * alpha);
      p = nelder_mead(t, p, 300, 1e-4 * alpha);
      prev = p;
      if (j == 0) prev_row0 = p;
      const Mat3 M = forward_matrix(t, p);
      Mat3 Mi = M.inverse();
      Mi /= Mi(1, 1);
      LTCFitNode& e = table[size_t(i * NC + j)];
      e.m[0] = Mi(0, 0);
      e.m[1] = Mi(0, 2);
      e.m[2] = Mi(2, 0);
      e.m[3] = Mi(2, 2);
      e.m[4] = t.albedo;
      e.l1 = error(t, p, 1);
      e.mass_below = mass_below(t, p);
    }
    if (progress) progress(alpha);
  }
  return table;
}

}  // namespace qsil::edgetree
