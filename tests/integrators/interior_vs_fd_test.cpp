// Interior-only scenes (env-lit, no occluders, nothing entering or leaving the view), where the
// interior term is the full derivative: `grad --boundary none` must agree with central finite
// differences. Criteria: per pixel within 4 combined standard errors in at
// least 99% of pixels, and the image sum within 3 combined standard errors. Fixed seeds.
#include "qsil/image.h"
#include "qsil/integrators/estimator.h"
#include "test_data.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

namespace qsil {
namespace {

/// A 100 x 100 plane at y = 0 facing +y under studio.exr (bright softboxes), seen from above at an
/// angle so that the whole view is plane and its outline stays far outside the view.
Scene plane_scene(BSDFDesc::Type type, double alpha) {
  Scene s;
  BSDFDesc b;
  b.type = type;
  b.alpha = alpha;
  b.reflectance = Color(0.7, 0.6, 0.5);
  s.bsdfs.push_back(b);
  Shape plane;
  plane.id = "plane";
  plane.type = "rectangle";
  plane.mesh.positions = {{-50, 0, 50}, {50, 0, 50}, {50, 0, -50}, {-50, 0, -50}};
  plane.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  plane.mesh.normals = vertex_normals(plane.mesh);
  plane.bsdf = 0;
  s.shapes.push_back(plane);
  s.environment.type = Environment::Type::EnvMap;
  s.environment.filename = test::data_file("tests/data/envmaps/studio.exr");
  s.environment.texels = read_exr(s.environment.filename);
  s.camera = test::look_at(Vec3(0, 2, 3), Vec3(0, 0, 0), 40, 24, 24, 32);
  s.max_depth = 3;
  return s;
}

struct Agreement {
  double pixel_fraction_within_4se = 0;
  double sum_grad = 0, sum_fd = 0, sum_se = 0;
};

Agreement compare(const RenderResult& g, const RenderResult& f, int k) {
  Agreement a;
  int within = 0, total = 0;
  for (int y = 0; y < g.film.height(); ++y)
    for (int x = 0; x < g.film.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const int ch = g.film.layout().derivative(k, c);
        const double se = std::hypot(g.film.standard_error(ch, x, y), f.film.standard_error(ch, x, y));
        within += std::abs(g.film.mean(ch, x, y) - f.film.mean(ch, x, y)) <= 4 * se + 1e-12;
        ++total;
      }
  a.pixel_fraction_within_4se = double(within) / total;
  const ImageSum sg = g.film.derivative_sum(k), sf = f.film.derivative_sum(k);
  a.sum_grad = sg.sum;
  a.sum_fd = sf.sum;
  a.sum_se = std::hypot(sg.standard_error, sf.standard_error);
  return a;
}

void expect_agreement(Scene scene, const std::string& spec, int spp) {
  scene.camera.spp = spp;
  const std::vector<ParameterSpec> params{parse_parameter(spec, scene)};
  RenderOptions o;
  o.progress = false;
  o.seed = 21;
  const RenderResult g = Estimator(scene, EstimatorConfig::gradient(params, Method::None)).run(o);
  o.seed = 22;  // independent of the gradient's samples
  const RenderResult f = Estimator(scene, EstimatorConfig::finite_differences(params)).run(o);
  const Agreement a = compare(g, f, 0);
  EXPECT_GE(a.pixel_fraction_within_4se, 0.99) << spec;
  EXPECT_NEAR(a.sum_grad, a.sum_fd, 3 * a.sum_se) << spec;
  EXPECT_GT(std::abs(a.sum_fd), 3 * a.sum_se) << spec << ": the derivative must be clearly non-zero";
  EXPECT_EQ(g.nonfinite + f.nonfinite, 0u);
}

}  // namespace

TEST(InteriorVsFD, DiffusePlaneRotatingAboutAnInPlaneAxis) {
  expect_agreement(plane_scene(BSDFDesc::Type::Diffuse, 0), "plane:rotate:1,0,0.3@0,0,0", 32);
}

TEST(InteriorVsFD, RoughConductorPlaneRotatingAboutAnInPlaneAxis) {
  // Glossy reflections of small bright softboxes are noisier: 512 spp.
  expect_agreement(plane_scene(BSDFDesc::Type::RoughConductor, 0.1), "plane:rotate:1,0,0.3@0,0,0", 512);
}

// Translating the plane along its normal changes nothing: the hit point slides along each fixed
// camera ray, the normal and every direction stay the same. Both estimators must say zero.
TEST(InteriorVsFD, PlaneTranslatedAlongItsNormalHasZeroDerivativeOnBothSides) {
  for (auto type : {BSDFDesc::Type::Diffuse, BSDFDesc::Type::RoughConductor}) {
    const Scene scene = plane_scene(type, 0.1);
    const std::vector<ParameterSpec> params{parse_parameter("plane:translate:0,1,0", scene)};
    RenderOptions o;
    o.progress = false;
    const RenderResult g = Estimator(scene, EstimatorConfig::gradient(params, Method::None)).run(o);
    const RenderResult f = Estimator(scene, EstimatorConfig::finite_differences(params)).run(o);
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 24; ++x)
        for (int c = 3; c < 6; ++c) {
          const double scale = 1e-6 * (1 + g.film.mean(c - 3, x, y));  // float ray offsets only
          EXPECT_NEAR(g.film.mean(c, x, y), 0.0, scale);
          EXPECT_NEAR(f.film.mean(c, x, y), 0.0, 1e3 * scale);  // FD divides float noise by 2h
        }
  }
}

}  // namespace qsil
