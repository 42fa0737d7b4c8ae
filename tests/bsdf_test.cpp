/// @file bsdf_test.cpp
/// Tests of BSDF evaluation and sampling (include/qsil/bsdf.h), in the style of pbrt-v4's
/// bsdfs_test.cpp and Mitsuba 3's chi2 tests.
///
/// Configurations: diffuse (cosine density, and the defensive mixture of derivative-carrying paths,
/// kDerivativeDiffuseUniformShare), and GGX at alpha {0.01, 0.1, 0.3, 0.7}, each at incident
/// (viewing) angles {0, 30, 60, 85} degrees (azimuth 0.3 rad, so nothing aligns with the bins by accident).
/// Integrals over the sphere use test::sphere_quadrature centred on the lobe (the mirror
/// direction), whose cells shrink toward the centre (2500 x 1280 cells): it resolves the
/// alpha = 0.01 lobe (width ~0.02 rad) with thousands of points; its error is < 1e-4 on the
/// integrals checked here (tolerances below state the margin taken).
/// Chi-square: 41 x 80 (cos theta, phi) bins of the local frame, 10^6 samples per configuration,
/// family-wise significance 1% over the 24 configurations (Šidák), pooling expected < 5.

#include "qsil/bsdf.h"
#include "qsil/dual.h"
#include "qsil/sampling.h"

#include "chi2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace qsil {
namespace {

using test::TestRng;

// ---------------------------------------------------------------------------------------------
// Configurations
// ---------------------------------------------------------------------------------------------

struct Config {
  BSDFDesc bsdf;
  double theta_deg = 0;
  std::string name;
  double uniform_share = 0;  ///< bsdf_sample's and bsdf_pdf's uniform_share
};

BSDFDesc diffuse(const Color& r = Color(0.7, 0.5, 0.2)) {
  BSDFDesc b;
  b.type = BSDFDesc::Type::Diffuse;
  b.reflectance = r;
  return b;
}

BSDFDesc ggx(double alpha, const Color& ks = Color::Constant(1.0)) {
  BSDFDesc b;
  b.type = BSDFDesc::Type::RoughConductor;
  b.alpha = alpha;
  b.specular_reflectance = ks;
  return b;
}

std::vector<Config> all_configs() {
  std::vector<Config> out;
  const double thetas[] = {0, 30, 60, 85};
  for (double t : thetas) out.push_back({diffuse(), t, "Diffuse_theta" + std::to_string(int(t))});
  for (double t : thetas)
    out.push_back({diffuse(), t, "DiffuseDefensive_theta" + std::to_string(int(t)), kDerivativeDiffuseUniformShare});
  const std::pair<double, const char*> alphas[] = {{0.01, "0p01"}, {0.1, "0p1"}, {0.3, "0p3"}, {0.7, "0p7"}};
  for (auto [a, an] : alphas)
    for (double t : thetas)
      out.push_back({ggx(a), t, std::string("GGX_alpha") + an + "_theta" + std::to_string(int(t))});
  return out;
}

const int kNumConfigs = int(all_configs().size());
const double kSignificance = test::sidak(0.01, kNumConfigs);

/// Viewing direction at polar angle theta (degrees), azimuth 0.3 rad, local frame.
Vec3 view_dir(double theta_deg) {
  const double t = theta_deg * kPi / 180, phi = 0.3;
  return {std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t)};
}

/// Where the lobe of wi is: the mirror direction of wo for GGX, the normal for diffuse.
Vec3 lobe_center(const BSDFDesc& b, const Vec3& wo) {
  return b.type == BSDFDesc::Type::Diffuse ? Vec3(0, 0, 1) : Vec3(-wo.x(), -wo.y(), wo.z());
}

/// The quadrature's cap around lobe_center: the upper hemisphere for diffuse, whose pdf vanishes
/// below the horizon and (with a uniform share) jumps there, so no cell straddles the jump; the
/// whole sphere for GGX, whose proposal density is continuous.
double quadrature_cap(const BSDFDesc& b) { return b.type == BSDFDesc::Type::Diffuse ? 0.5 * kPi : kPi; }

constexpr int kQuadS = 2500, kQuadPhi = 1280;  // kQuadPhi is a multiple of the 80 phi bins
const test::SphereBins kBins{41, 80};
constexpr int kSamples = 1000000;

/// gtest prints the configuration by name.
void PrintTo(const Config& c, std::ostream* os) { *os << c.name; }

class BSDFSampling : public testing::TestWithParam<Config> {};

// ---------------------------------------------------------------------------------------------
// (a) the pdf integrates to one over the sphere
// ---------------------------------------------------------------------------------------------

TEST_P(BSDFSampling, PdfIntegratesToOne) {
  const Config& c = GetParam();
  const Vec3 wo = view_dir(c.theta_deg);
  const double integral = test::integrate_sphere(lobe_center(c.bsdf, wo), kQuadS, kQuadPhi,
                                                 [&](const Vec3& wi) { return bsdf_pdf(c.bsdf, wi, wo, c.uniform_share); },
                                                 quadrature_cap(c.bsdf));
  // Quadrature error < 1e-4 (see file comment); a 5% error in the pdf is 500x the tolerance.
  EXPECT_NEAR(integral, 1.0, 5e-4);
  RecordProperty("pdf_integral", std::to_string(integral));
}

// ---------------------------------------------------------------------------------------------
// (b) chi-square: the histogram of bsdf_sample matches bsdf_pdf integrated per bin
// ---------------------------------------------------------------------------------------------

/// Chi-square of `sample` (returning a BSDFSample) against the density `pdf`.
template <class SampleFn, class PdfFn>
test::Chi2Result chi2_bsdf(const Vec3& center, SampleFn sample, PdfFn pdf, uint64_t seed, std::string* note,
                           double cap = kPi) {
  std::vector<double> obs(size_t(kBins.count()), 0.0);
  TestRng rng(seed);
  int no_direction = 0;
  for (int i = 0; i < kSamples; ++i) {
    const BSDFSample s = sample(rng.uniform2());
    if (!(s.pdf > 0)) {  // no direction was proposed at all
      ++no_direction;
      continue;
    }
    obs[size_t(kBins.index(s.wi))] += 1;
  }
  double total = 0;
  const std::vector<double> exp = test::expected_counts(kBins, center, kQuadS, kQuadPhi, kSamples, pdf, &total, cap);
  std::ostringstream os;
  os << "pdf integral " << total << ", samples without a direction " << no_direction;
  *note = os.str();
  return test::chi2_test(obs, exp, kSignificance);
}

TEST_P(BSDFSampling, Chi2SampleMatchesPdf) {
  const Config& c = GetParam();
  const Vec3 wo = view_dir(c.theta_deg);
  std::string note;
  const auto r = chi2_bsdf(
      lobe_center(c.bsdf, wo), [&](const Vec2& u) { return bsdf_sample(c.bsdf, wo, u, c.uniform_share); },
      [&](const Vec3& wi) { return bsdf_pdf(c.bsdf, wi, wo, c.uniform_share); }, 1000 + uint64_t(c.theta_deg), &note,
      quadrature_cap(c.bsdf));
  EXPECT_TRUE(r.passed) << r.message << "; " << note;
  RecordProperty("chi2", r.message + "; " + note);
}

// Negative controls: the chi-square test must reject a sampler whose distribution is off by 5%
// (alpha off by 5%), and a density perturbed by 5% (a tilt of the lobe, renormalised).
TEST(BSDFSamplingPower, Chi2RejectsFivePercentAlphaError) {
  const Vec3 wo = view_dir(30);
  const BSDFDesc b = ggx(0.3), wrong = ggx(0.3 * 1.05);
  std::string note;
  const auto r = chi2_bsdf(
      lobe_center(b, wo), [&](const Vec2& u) { return bsdf_sample(wrong, wo, u); },
      [&](const Vec3& wi) { return bsdf_pdf(b, wi, wo); }, 77, &note);
  EXPECT_FALSE(r.passed) << r.message;
}

TEST(BSDFSamplingPower, Chi2RejectsFivePercentPdfTilt) {
  const Vec3 wo = view_dir(0);
  const BSDFDesc b = diffuse();
  std::string note;
  // (1 + 0.05 wi.x) integrates to the same total under the cosine density (odd in x).
  const auto r = chi2_bsdf(
      lobe_center(b, wo), [&](const Vec2& u) { return bsdf_sample(b, wo, u); },
      [&](const Vec3& wi) { return bsdf_pdf(b, wi, wo) * (1.0 + 0.05 * wi.x()); }, 78, &note, quadrature_cap(b));
  EXPECT_FALSE(r.passed) << r.message;
}

// The mixture's pdf must describe its own samples: the cosine density (share 0) against samples
// drawn with kDerivativeDiffuseUniformShare is rejected, near the horizon where they differ most.
TEST(BSDFSamplingPower, Chi2RejectsTheCosineDensityForTheMixture) {
  const Vec3 wo = view_dir(30);
  const BSDFDesc b = diffuse();
  std::string note;
  const auto r = chi2_bsdf(
      lobe_center(b, wo), [&](const Vec2& u) { return bsdf_sample(b, wo, u, kDerivativeDiffuseUniformShare); },
      [&](const Vec3& wi) { return bsdf_pdf(b, wi, wo); }, 79, &note, quadrature_cap(b));
  EXPECT_FALSE(r.passed) << r.message;
}

// ---------------------------------------------------------------------------------------------
// (c) eval and pdf are consistent: the albedo by sampling equals the quadrature of eval;
// (d) energy: GGX with F = 1 has albedo <= 1; diffuse albedo = reflectance.
// ---------------------------------------------------------------------------------------------

TEST_P(BSDFSampling, AlbedoBySamplingMatchesQuadratureAndConservesEnergy) {
  const Config& c = GetParam();
  const Vec3 wo = view_dir(c.theta_deg);
  // Monte Carlo: mean of eval/pdf over bsdf_sample (invalid samples count as 0).
  TestRng rng(2000 + uint64_t(c.theta_deg));
  const int n = 200000;
  Eigen::Array3d sum = Eigen::Array3d::Zero(), sum2 = Eigen::Array3d::Zero();
  for (int i = 0; i < n; ++i) {
    const BSDFSample s = bsdf_sample(c.bsdf, wo, rng.uniform2(), c.uniform_share);
    if (!s.valid) continue;
    const Color w = bsdf_eval<double>(c.bsdf, s.wi, wo) / s.pdf;
    // The sample's pdf is the one bsdf_pdf reports for the same pair.
    ASSERT_NEAR(s.pdf, bsdf_pdf(c.bsdf, s.wi, wo, c.uniform_share), 1e-9 * s.pdf);
    sum += w;
    sum2 += w * w;
  }
  const Eigen::Array3d mc = sum / n;
  const Eigen::Array3d sigma = ((sum2 / n - mc * mc).max(0.0) / n).sqrt();
  // Quadrature of eval over the sphere (per channel).
  Eigen::Array3d quad = Eigen::Array3d::Zero();
  test::sphere_quadrature(lobe_center(c.bsdf, wo), kQuadS, kQuadPhi,
                          [&](const Vec3& wi, double w) { quad += bsdf_eval<double>(c.bsdf, wi, wo) * w; });
  std::ostringstream os;
  os << "mc " << mc.transpose() << " +- " << sigma.transpose() << ", quadrature " << quad.transpose();
  RecordProperty("albedo", os.str());
  for (int k = 0; k < 3; ++k) {
    // 4.5 sigma (two-sided 7e-6 per comparison) plus 1e-4 quadrature error.
    EXPECT_NEAR(mc[k], quad[k], 4.5 * sigma[k] + 1e-4) << "channel " << k;
    if (c.bsdf.type == BSDFDesc::Type::Diffuse) {
      // Cosine density: eval/pdf = reflectance exactly for every sample, the albedo is the
      // reflectance. The mixture's weights vary; its mean is checked against quadrature above.
      if (c.uniform_share == 0) EXPECT_NEAR(mc[k], c.bsdf.reflectance[k], 1e-9);  // summation rounding of 2e5 terms
      EXPECT_NEAR(quad[k], c.bsdf.reflectance[k], 1e-4);
    } else {
      EXPECT_LE(quad[k], 1.0 + 1e-4);
      EXPECT_LE(mc[k], 1.0 + 4.5 * sigma[k]);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, BSDFSampling, testing::ValuesIn(all_configs()),
                         [](const testing::TestParamInfo<Config>& info) { return info.param.name; });

// ---------------------------------------------------------------------------------------------
// (e) reciprocity, support, twosided, and known values
// ---------------------------------------------------------------------------------------------

Vec3 random_upper(TestRng& rng) {
  Vec3 d = square_to_uniform_sphere(rng.uniform2());
  d.z() = std::abs(d.z());
  return d;
}

std::vector<BSDFDesc> some_bsdfs() {
  std::vector<BSDFDesc> v = {diffuse(), ggx(0.01), ggx(0.1, Color(0.9, 0.6, 0.3)), ggx(0.3), ggx(0.7)};
  const size_t n = v.size();
  for (size_t i = 0; i < n; ++i) {
    BSDFDesc t = v[i];
    t.twosided = true;
    v.push_back(t);
  }
  return v;
}

TEST(BSDFEval, Reciprocity) {
  // f(wi,wo) = f(wo,wi): eval(wi,wo)/|cos_i| = eval(wo,wi)/|cos_o|, to rounding (relative 1e-12).
  TestRng rng(31);
  for (const BSDFDesc& b : some_bsdfs())
    for (int i = 0; i < 2000; ++i) {
      Vec3 wi = random_upper(rng), wo = random_upper(rng);
      if (b.twosided && i % 2) {  // the back side of a twosided BSDF is reciprocal too
        wi.z() = -wi.z();
        wo.z() = -wo.z();
      }
      const Color a = bsdf_eval<double>(b, wi, wo) / std::abs(wi.z());
      const Color c = bsdf_eval<double>(b, wo, wi) / std::abs(wo.z());
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(a[k], c[k], 1e-12 * std::max(1.0, std::abs(a[k])));
    }
}

TEST(BSDFEval, SupportOneSidedAndTwosided) {
  TestRng rng(32);
  for (const BSDFDesc& b : some_bsdfs())
    for (int i = 0; i < 500; ++i) {
      const Vec3 wi = random_upper(rng), wo = random_upper(rng);
      const Vec3 wi_b(wi.x(), wi.y(), -wi.z()), wo_b(wo.x(), wo.y(), -wo.z());
      // Opposite sides: always zero (reflection only).
      EXPECT_TRUE((bsdf_eval<double>(b, wi_b, wo) == 0).all());
      EXPECT_TRUE((bsdf_eval<double>(b, wi, wo_b) == 0).all());
      EXPECT_GT(bsdf_eval<double>(b, wi, wo).maxCoeff(), 0.0);
      const Color back = bsdf_eval<double>(b, wi_b, wo_b);
      if (b.twosided) {
        // Mirrored: the same value, the same pdf, and a mirrored sample.
        EXPECT_TRUE((back == bsdf_eval<double>(b, wi, wo)).all());
        EXPECT_EQ(bsdf_pdf(b, wi_b, wo_b), bsdf_pdf(b, wi, wo));
        const Vec2 u = rng.uniform2();
        const BSDFSample s = bsdf_sample(b, wo, u), sb = bsdf_sample(b, wo_b, u);
        EXPECT_EQ(sb.wi, Vec3(s.wi.x(), s.wi.y(), -s.wi.z()));
        EXPECT_EQ(sb.pdf, s.pdf);
        EXPECT_EQ(sb.valid, s.valid);
      } else {
        // One-sided (Mitsuba 3): black from behind, nothing sampled.
        EXPECT_TRUE((back == 0).all());
        EXPECT_EQ(bsdf_pdf(b, wi_b, wo_b), 0.0);
        const BSDFSample sb = bsdf_sample(b, wo_b, rng.uniform2());
        EXPECT_FALSE(sb.valid);
        EXPECT_EQ(sb.pdf, 0.0);
      }
    }
}

// The diffuse proposal density (cosine, and the mixture of derivative-carrying paths) is zero
// below the horizon, which the quadratures above no longer visit (they stop at it), and a
// twosided BSDF's mixture is mirrored like its cosine density.
TEST(BSDFEval, DiffusePdfVanishesBelowTheHorizonAndMirrorsWhenTwosided) {
  TestRng rng(33);
  BSDFDesc two = diffuse();
  two.twosided = true;
  for (double share : {0.0, kDerivativeDiffuseUniformShare})
    for (int i = 0; i < 500; ++i) {
      const Vec3 wi = random_upper(rng), wo = random_upper(rng);
      const Vec3 wi_b(wi.x(), wi.y(), -wi.z()), wo_b(wo.x(), wo.y(), -wo.z());
      EXPECT_EQ(bsdf_pdf(diffuse(), wi_b, wo, share), 0.0);
      EXPECT_GT(bsdf_pdf(diffuse(), wi, wo, share), 0.0);
      EXPECT_EQ(bsdf_pdf(two, wi_b, wo_b, share), bsdf_pdf(two, wi, wo, share));
      const Vec2 u = rng.uniform2();
      const BSDFSample s = bsdf_sample(two, wo, u, share), sb = bsdf_sample(two, wo_b, u, share);
      EXPECT_EQ(sb.wi, Vec3(s.wi.x(), s.wi.y(), -s.wi.z()));
      EXPECT_EQ(sb.pdf, s.pdf);
    }
}

TEST(BSDFEval, KnownValues) {
  // Diffuse: R cos_i / pi.
  const Vec3 wi = Vec3(0.6, 0.0, 0.8), wo = Vec3(0, 0, 1);
  const Color d = bsdf_eval<double>(diffuse(Color(0.5, 0.25, 1.0)), wi, wo);
  EXPECT_NEAR(d[0], 0.5 * 0.8 / kPi, 1e-15);
  EXPECT_NEAR(d[2], 1.0 * 0.8 / kPi, 1e-15);
  // GGX at normal incidence and exitance: h = n, D = 1/(pi alpha^2), G = 1:
  // f cos_i = D / (4 cos_o) = 1/(4 pi alpha^2); for alpha = 0.5 that is 1/pi.
  const Color g = bsdf_eval<double>(ggx(0.5, Color(1.0, 0.5, 0.25)), wo, wo);
  EXPECT_NEAR(g[0], 1.0 / kPi, 1e-14);
  EXPECT_NEAR(g[1], 0.5 / kPi, 1e-14);
  // G1 equals the textbook tan form 2 / (1 + sqrt(1 + alpha^2 tan^2 theta)) [Walter Eq. 34] and
  // D the form 1 / (pi alpha^2 cos^4 (1 + tan^2/alpha^2)^2) [Walter Eq. 33].
  for (double alpha : {0.01, 0.3, 1.0})
    for (double theta : {0.1, 0.7, 1.4}) {
      const Vec3 v(std::sin(theta), 0, std::cos(theta));
      const double t2 = std::tan(theta) * std::tan(theta);
      EXPECT_NEAR(ggx_G1<double>(alpha, v, Vec3(0, 0, 1)), 2.0 / (1.0 + std::sqrt(1.0 + alpha * alpha * t2)), 1e-14);
      const double c4 = std::pow(std::cos(theta), 4);
      const double dref = 1.0 / (kPi * alpha * alpha * c4 * std::pow(1.0 + t2 / (alpha * alpha), 2));
      EXPECT_NEAR(ggx_D<double>(alpha, v), dref, 1e-12 * dref);
    }
  // The separable Smith G (Mitsuba 3) rather than the height-correlated one: at a configuration
  // where they differ, eval matches D G1 G1 / (4 cos_o).
  const Vec3 a(std::sin(1.2), 0, std::cos(1.2)), o(-std::sin(1.0) * 0.6, std::sin(1.0) * 0.8, std::cos(1.0));
  const Vec3 h = (a + o).normalized();
  const double alpha = 0.4;
  const double expected =
      ggx_D<double>(alpha, h) * ggx_G1<double>(alpha, a, h) * ggx_G1<double>(alpha, o, h) / (4 * o.z());
  EXPECT_NEAR(bsdf_eval<double>(ggx(alpha), a, o)[0], expected, 1e-14 * expected);
}

TEST(BSDFEval, GGXNormalizations) {
  // integral D(m) cos(theta_m) dm = 1, and the visible normal distribution
  // integral G1(v,m) max(0, v.m) D(m) / v.z dm = 1 (Heitz 2014 Eq. 18): this pins G1 to the Smith
  // masking of GGX. Quadrature over the upper hemisphere (D jumps to 0 at its rim); error < 1e-4.
  for (double alpha : {0.01, 0.1, 0.3, 0.7}) {
    const double nd = test::integrate_sphere(
        Vec3(0, 0, 1), kQuadS, kQuadPhi / 4,
        [&](const Vec3& m) { return ggx_D<double>(alpha, m) * std::max(0.0, m.z()); }, kPi / 2);
    EXPECT_NEAR(nd, 1.0, 2e-4) << "alpha " << alpha;
    for (double theta : {0.0, 1.0, 1.48}) {
      const Vec3 v(std::sin(theta), 0, std::cos(theta));
      const double vis = test::integrate_sphere(
          Vec3(0, 0, 1), kQuadS, kQuadPhi / 4, [&](const Vec3& m) { return ggx_visible_normal_pdf(alpha, v, m); },
          kPi / 2);
      EXPECT_NEAR(vis, 1.0, 2e-4) << "alpha " << alpha << " theta " << theta;
    }
  }
}

TEST(BSDFEval, DualDerivativesMatchCentralDifferences) {
  // bsdf_eval on forward-mode duals: directions depend on two parameters (a rotation of the
  // shading frame and a change of wi); the derivatives match central differences in double.
  using D = Dual<2>;
  // Parametrisation: wi(t) = normalize(a + t0 e0 + t1 e1), wo(t) = normalize(b + t0 e2).
  const Vec3 a(0.3, -0.2, 0.9), bvec(-0.4, 0.1, 0.8), e0(1, 0, 0.2), e1(0, 1, -0.3), e2(0.2, 0.5, 0);
  auto eval_double = [&](const BSDFDesc& bs, double t0, double t1) {
    const Vec3 wi = (a + t0 * e0 + t1 * e1).normalized(), wo = (bvec + t0 * e2).normalized();
    return bsdf_eval<double>(bs, wi, wo);
  };
  for (const BSDFDesc& bs : some_bsdfs()) {
    Vec3T<D> wi, wo;
    for (int k = 0; k < 3; ++k) {
      wi[k] = D(a[k], Eigen::Vector2d(e0[k], e1[k]));
      wo[k] = D(bvec[k], Eigen::Vector2d(e2[k], 0.0));
    }
    using std::sqrt;
    const D ni = sqrt(wi.dot(wi)), no = sqrt(wo.dot(wo));
    for (int k = 0; k < 3; ++k) {
      wi[k] = wi[k] / ni;
      wo[k] = wo[k] / no;
    }
    const ColorT<D> f = bsdf_eval<D>(bs, wi, wo);
    const Color f0 = eval_double(bs, 0, 0);
    const double h = 1e-6;
    const Color d0 = (eval_double(bs, h, 0) - eval_double(bs, -h, 0)) / (2 * h);
    const Color d1 = (eval_double(bs, 0, h) - eval_double(bs, 0, -h)) / (2 * h);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(f[k].value(), f0[k], 1e-14 * std::max(1.0, f0[k]));
      const double scale = std::max(1.0, std::abs(f0[k]));
      EXPECT_NEAR(f[k].derivatives()[0], d0[k], 1e-6 * scale) << "alpha " << bs.alpha;
      EXPECT_NEAR(f[k].derivatives()[1], d1[k], 1e-6 * scale) << "alpha " << bs.alpha;
    }
  }
}

}  // namespace
}  // namespace qsil
