/// @file attached_camera_test.cpp
/// Attached camera hits (qsil/integrators/attached_camera.h):
/// - the warped camera ray carries its hit with the material point where the bump is 1, and is
///   the detached ray on the pixel's border (exact properties);
/// - the warp's Jacobian is the divergence of w V, against central differences of a film velocity
///   computed by moving the triangle's vertices and projecting the material point (an oracle that
///   shares no code with the dual arithmetic);
/// - the adaptive strength attaches the thin glossy ring and not a smooth sphere at 32 x 32, and a
///   diffuse teapot's smoothed creases (not the whole teapot) with a ramp no steeper than its bound;
///   it leaves the ordinary turns of a coarse bunny's normals (edges about a pixel long) detached;
/// - the control variate's parts cancel: grad with c less grad without it (same seeds, same
///   samples) has mean zero at a silhouette with an intersection curve and behind a static post,
///   with the power to see a flux that leaves c out (the Jacobian's part, integrated on a grid
///   outside the estimator, must be 6 and 8 standard errors from 0); with c left out of the flux
///   both fail (docs/experiments/2026-11-29-attached-control.md);
/// - with every hit on a moving shape attached (CameraHits::Attached), `qsil grad` agrees with
///   central finite differences where the attached form's flux crosses a silhouette and an
///   intersection curve (a sphere sunk into a floor, rising) and a static post's outline (an edge
///   of a static shape). Criterion: image sums within 3 combined standard errors (99.7 % for a
///   correct estimator), that standard error at most `power` of the sum (12 % and 5 %: a 40 % and
///   a 15 % bias fail). Without the flux at the post's edges (static primary edges left out) the
///   post case is 15 % low (z = -3.2: the test fails), without any attached flux the sunk sphere is
///   90 % high (measured 2026-11-28, docs/experiments/2026-11-28-attached-camera.md);
/// - the adaptive rule on a diffuse mesh with smoothed creases (the teapot: partial strengths, the
///   ramp, intersection curves) agrees with FD too (power 8 %). Attached everywhere, a diffuse
///   object's samples carry the warp's Jacobian noise (docs/experiments/2026-11-28-attached-camera.md), so these runs
///   are long (label slow).

#include "qsil/integrators/attached_camera.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/surface_interaction.h"
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"

#include "estimator_runs.h"
#include "integrators/attached_control.h"
#include "integrators/render_setup.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace qsil {
namespace {

/// metal-sunk-post at 32 x 32 with the sphere translated along x.
struct PostScene {
  Scene scene = load_scene(test::data_file("tests/data/gradient/metal-sunk-post.xml"), {{"res", "32"}});
  std::vector<ParameterSpec> params{parse_parameter("sphere:translate:1,0,0", scene)};
  SceneVelocities vel = compute_velocities(scene, params);
  RayTracer tracer{scene};
  CameraAttachment everywhere = camera_attachment(scene, vel.moving, CameraHits::Attached);
  /// The camera ray through film position f (pixels).
  CameraRay ray(const Vec2& f) const {
    const Vec3 d = scene.camera.direction(f.x(), f.y());
    return {d, tracer.intersect(scene.camera.origin(), d)};
  }
  /// A film position on the sphere, its pixel's offset `offset` in [0, 1]^2: the pixel is the
  /// first, in row order, whose closed square (a 5 x 5 grid of film positions, borders included)
  /// sees the sphere only, so that the hit's triangle is the sphere's wherever the test samples.
  Vec2 on_sphere(const Vec2& offset) const {
    const int w = scene.camera.width, h = scene.camera.height;
    for (int py = 0; py < h; ++py)
      for (int px = 0; px < w; ++px) {
        bool all = true;
        for (int i = 0; i <= 4 && all; ++i)
          for (int j = 0; j <= 4 && all; ++j) {
            const CameraRay r = ray(Vec2(px + 0.25 * i, py + 0.25 * j));
            all = r.hit.valid() && scene.shapes[size_t(r.hit.shape)].id == "sphere";
          }
        if (all) return Vec2(px + offset.x(), py + offset.y());
      }
    ADD_FAILURE() << "no pixel sees the sphere only";
    return Vec2::Zero();
  }
};

TEST(AttachedCamera, HitFollowsTheMaterialPointInsideThePixelAndIsDetachedOnItsBorder) {
  const PostScene s;
  const DualView<1> view{&s.scene, &s.vel};
  const Vec3 o = s.scene.camera.origin();
  for (const Vec2& offset : {Vec2(0.5, 0.5), Vec2(0.3, 0.8), Vec2(0.0, 0.4), Vec2(0.6, 1.0)}) {
    const Vec2 f = s.on_sphere(offset);
    const CameraRay ray = s.ray(f);
    ASSERT_TRUE(ray.hit.valid());
    ASSERT_EQ(s.scene.shapes[size_t(ray.hit.shape)].id, "sphere");
    const int px = int(std::floor(f.x())), py = int(std::floor(f.y()));
    const AttachedCameraRay<1> a = attached_camera_ray<1>(s.scene, s.vel, s.everywhere, ray, f, px, py);
    const SurfaceInteraction<Dual<1>> att = make_interaction(view, ray.hit, lift<Dual<1>>(o), a.dir);
    const SurfaceInteraction<Dual<1>> det = make_interaction(view, ray.hit, lift<Dual<1>>(o), ray.dir);
    const double bump = attached_bump_1d(offset.x()) * attached_bump_1d(offset.y());
    // The hit moves by (1 - w) of its slide along the ray plus w of the material point's motion:
    // its barycentrics' derivatives are (1 - w) of the detached ones.
    EXPECT_NEAR(att.b1.derivatives()[0], (1 - bump) * det.b1.derivatives()[0], 1e-9) << offset.transpose();
    EXPECT_NEAR(att.b2.derivatives()[0], (1 - bump) * det.b2.derivatives()[0], 1e-9) << offset.transpose();
    if (bump == 1.0) {
      const Eigen::Matrix<double, 3, 1> v =
          material_velocity<1>(s.vel, s.scene, ray.hit.shape, ray.hit.triangle, value(att.b1), value(att.b2));
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(att.p[i].derivatives()[0], v[i], 1e-9);
      }
    }
    if (bump == 0.0) {
      EXPECT_EQ(a.jacobian.derivatives()[0], 0.0);
    }
  }
}

TEST(AttachedCamera, JacobianIsTheDivergenceOfTheWarp) {
  const PostScene s;
  const Scene& scene = s.scene;
  const Vec3 o = scene.camera.origin();
  for (const Vec2& offset : {Vec2(0.5, 0.5), Vec2(0.07, 0.5), Vec2(0.9, 0.12), Vec2(0.3, 0.95)}) {
    const Vec2 f = s.on_sphere(offset);
    const CameraRay ray = s.ray(f);
    ASSERT_TRUE(ray.hit.valid());
    const int px = int(std::floor(f.x())), py = int(std::floor(f.y()));
    const AttachedCameraRay<1> a = attached_camera_ray<1>(scene, s.vel, s.everywhere, ray, f, px, py);
    // The oracle: w(u) V(u), V the film velocity of the material point that the ray through u meets
    // on the hit triangle's plane, by moving the vertices by +-eps along their velocities.
    const Eigen::Vector3i& tri = scene.shapes[size_t(ray.hit.shape)].mesh.triangles[size_t(ray.hit.triangle)];
    const auto& P = scene.shapes[size_t(ray.hit.shape)].mesh.positions;
    const auto& Vel = s.vel.position[size_t(ray.hit.shape)];
    auto wV = [&](const Vec2& u) {
      const Vec3 d = scene.camera.direction(u.x(), u.y());
      const Vec3 e1 = P[size_t(tri[1])] - P[size_t(tri[0])], e2 = P[size_t(tri[2])] - P[size_t(tri[0])];
      const Vec3 pv = d.cross(e2), tv = o - P[size_t(tri[0])], qv = tv.cross(e1);
      const double inv = 1.0 / e1.dot(pv), b1 = tv.dot(pv) * inv, b2 = d.dot(qv) * inv;
      auto at = [&](double eps) {
        Vec3 y = Vec3::Zero();
        const double b[3] = {1 - b1 - b2, b1, b2};
        for (int k = 0; k < 3; ++k) y += b[k] * (P[size_t(tri[k])] + eps * Vel[size_t(tri[k])].col(0));
        return scene.camera.project(y);
      };
      const double eps = 1e-6;
      const Vec2 V = (at(eps) - at(-eps)) / (2 * eps);
      return Vec2(V * attached_bump_1d(u.x() - px) * attached_bump_1d(u.y() - py));
    };
    const double h = 1e-4;
    const double div = (wV(f + Vec2(h, 0)).x() - wV(f - Vec2(h, 0)).x()) / (2 * h) +
                       (wV(f + Vec2(0, h)).y() - wV(f - Vec2(0, h)).y()) / (2 * h);
    const double j = a.jacobian.derivatives()[0];
    EXPECT_NEAR(j, div, 1e-4 * (1 + std::abs(div))) << offset.transpose();
    // The direction moves toward where the material point goes: d(direction)/dtheta = d(dir)/du w V.
    const Vec2 v = wV(f);
    const Vec3 dd = (scene.camera.direction(f.x() + h * v.x(), f.y() + h * v.y()) -
                     scene.camera.direction(f.x() - h * v.x(), f.y() - h * v.y())) /
                    (2 * h);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(a.dir[i].derivatives()[0], dd[i], 1e-6 * (1 + dd.norm()));
  }
}

TEST(AttachedCamera, AdaptiveStrengthAttachesTheThinGlossyRingNotASmoothSphere) {
  const Scene ring = load_scene(test::data_file("scenes/stability/thin-metal.xml"), {{"res", "32"}});
  const SceneVelocities vr = compute_velocities(ring, {parse_parameter("ring:translate:1,0,0", ring)});
  const CameraAttachment ar = camera_attachment(ring, vr.moving, CameraHits::Adaptive);
  ASSERT_TRUE(ar.any());
  int full = 0;
  for (double a : ar.strength[0]) full += a == 1.0;
  EXPECT_GT(full, int(ar.strength[0].size()) * 9 / 10);
  const PostScene s;  // GGX alpha 0.15, radius 0.5: the normal turns ~0.9 lobe widths per pixel
  EXPECT_FALSE(camera_attachment(s.scene, s.vel.moving, CameraHits::Adaptive).any());
  EXPECT_FALSE(camera_attachment(ring, vr.moving, CameraHits::Detached).any());
}

TEST(AttachedCamera, AdaptiveStrengthAttachesADiffuseMeshsSmoothedCreasesWithABoundedRamp) {
  // The teapot has no normals: its averaged vertex normals span its sharp creases (up to 104
  // degrees over one edge), the diffuse rule's case; a smooth diffuse sphere has no such edge.
  const Scene teapot = load_scene(test::data_file("scenes/stability/teapot.xml"), {{"res", "48"}});
  const SceneVelocities vt = compute_velocities(teapot, {parse_parameter("teapot:translate:0,1,0", teapot)});
  const CameraAttachment at = camera_attachment(teapot, vt.moving, CameraHits::Adaptive);
  const int shape = teapot.find_shape("teapot");
  ASSERT_GE(shape, 0);
  ASSERT_TRUE(at.any());
  const std::vector<double>& a = at.strength[size_t(shape)];
  const TriangleMesh& m = teapot.shapes[size_t(shape)].mesh;
  ASSERT_EQ(a.size(), m.positions.size());
  int full = 0, some = 0;
  for (double v : a) {
    full += v == 1.0;
    some += v > 0;
  }
  EXPECT_GT(full, 0);
  EXPECT_LT(some, int(a.size()) / 2) << "the diffuse rule attaches creases, not the whole teapot";
  // The ramp: along every edge the strength falls by at most len / (pixel width at the stronger
  // end x kAttachedRampPixels); without it a crease's strength drops from 1 to 0 across one of
  // its small triangles.
  const Camera& cam = teapot.camera;
  const double pixel_angle = 2.0 * cam.tan_half_fov().x() / cam.width;
  int checked = 0;
  for (const Eigen::Vector3i& t : m.triangles)
    for (int e = 0; e < 3; ++e) {
      int i = t[e], j = t[(e + 1) % 3];
      if (a[size_t(i)] < a[size_t(j)]) std::swap(i, j);
      const double s = cam.to_camera(m.positions[size_t(i)]).z() * pixel_angle;
      if (!(s > 0)) continue;
      const double len = (m.positions[size_t(i)] - m.positions[size_t(j)]).norm();
      EXPECT_LE(a[size_t(i)] - a[size_t(j)], len / (s * kAttachedRampPixels) + 1e-12) << i << " " << j;
      checked += a[size_t(i)] > 0;
    }
  EXPECT_GT(checked, 0);
  const Scene sphere = load_scene(test::data_file("tests/data/gradient/sunk-sphere.xml"), {{"res", "48"}});
  const SceneVelocities vs = compute_velocities(sphere, {parse_parameter("sphere:translate:0,1,0", sphere)});
  EXPECT_FALSE(camera_attachment(sphere, vs.moving, CameraHits::Adaptive).any());
}

TEST(AttachedCamera, AdaptiveStrengthLeavesACoarseMeshsOrdinaryTurnsDetached) {
  // The bunny of shadow-quad (1839 vertices) has no crease, but its averaged normals turn by 45-90
  // degrees over edges about a pixel long at 128²: there the warp's Jacobian costs more than the
  // turn's tail (twice the variance when 9 % of its vertices were attached,
  // docs/experiments/2026-11-28-diffuse-crease-rule.md). Criterion: at most 3 % of its vertices are
  // attached at 128² (the rule of 8fbbdd0 attaches 28, 1.5 %; the rule before it 172, 9 %), none at
  // 256², where a pixel is smaller than its edges. Positive control: at 128² some are attached (the
  // strongest turns), so the rule runs on this mesh and the bound is not met by attaching nothing
  // (it pins the rule's behaviour: a rule that attached none of the bunny would be as good here,
  // and would have to change this line).
  for (const auto& [res, most] : {std::pair<const char*, double>{"128", 0.03}, {"256", 0.0}}) {
    const Scene bunny = load_scene(test::data_file("scenes/shadow-quad.xml"), {{"res", res}});
    const SceneVelocities vb = compute_velocities(bunny, {parse_parameter("object:translate:0,1,0", bunny)});
    const CameraAttachment ab = camera_attachment(bunny, vb.moving, CameraHits::Adaptive);
    const int shape = bunny.find_shape("object");
    ASSERT_GE(shape, 0);
    const size_t n = bunny.shapes[size_t(shape)].mesh.positions.size();
    int some = 0;
    for (double v : ab.strength[size_t(shape)]) some += v > 0;
    EXPECT_LE(some, most * double(n)) << res << "²: " << some << " of " << n << " vertices attached";
    if (most > 0) { EXPECT_GT(some, 0) << res << "²: the rule attaches nothing on this mesh"; }
  }
}

/// grad with every camera hit on a moving shape attached against central finite differences.
void expect_attached_agrees(const std::string& file, const std::map<std::string, std::string>& defaults,
                            const std::string& param, int grad_spp, int fd_spp, double power,
                            CameraHits hits = CameraHits::Attached) {
  const Scene scene = load_scene(test::data_file(file), defaults);
  const std::vector<ParameterSpec> params = {parse_parameter(param, scene)};
  EstimatorConfig config = EstimatorConfig::gradient(params, Method::Quadric);
  config.camera_hits = hits;
  if (hits == CameraHits::Adaptive) {  // the rule must attach something here, or the test tests nothing
    SceneVelocities vel = compute_velocities(scene, params);
    ASSERT_TRUE(camera_attachment(scene, vel.moving, hits).any()) << file;
  }
  const test::Sum g = test::derivative_sum(Estimator(scene, config).run(test::quiet(grad_spp, 31)));
  const test::Sum f =
      test::derivative_sum(Estimator(scene, EstimatorConfig::finite_differences(params)).run(test::quiet(fd_spp, 32)));
  const double se = std::hypot(g.se, f.se);
  std::printf("%s %s: attached grad %.5g +- %.3g, fd %.5g +- %.3g\n", file.c_str(), param.c_str(), g.value, g.se,
              f.value, f.se);
  EXPECT_NEAR(g.value, f.value, 3 * se) << file;
  EXPECT_LT(se, power * std::abs(f.value)) << file << ": not the power the test claims";
}

/// The image sum of the Jacobian term's control part, sum over pixels of c ∫_pixel div(w V) du
/// (channel mean), by a 16 x 16 grid of film positions per pixel (midpoint rule): what a flux that
/// left c out would leave uncancelled. An oracle built from attached_camera_ray and
/// set_attached_control directly, outside the estimator.
double jacobian_control_part(const Scene& scene, const std::vector<ParameterSpec>& params) {
  const SceneVelocities vel = compute_velocities(scene, params);
  const RenderSetup setup(scene);  // the estimators' tracer and lights
  CameraAttachment attachment = camera_attachment(scene, vel.moving, CameraHits::Attached);
  set_attached_control(setup.ctx, attachment, kAttachedControlSpp);
  const Camera& cam = scene.camera;
  constexpr int g = 16;
  double total = 0;
  for (int py = 0; py < cam.height; ++py)
    for (int px = 0; px < cam.width; ++px) {
      const double c = attachment.control_at(px, py).mean();
      if (c == 0) continue;
      for (int i = 0; i < g; ++i)
        for (int j = 0; j < g; ++j) {
          const Vec2 film(px + (i + 0.5) / g, py + (j + 0.5) / g);
          const Vec3 d = cam.direction(film.x(), film.y());
          const CameraRay ray{d, setup.tracer.intersect(cam.origin(), d)};
          total +=
              c * attached_camera_ray<1>(scene, vel, attachment, ray, film, px, py).jacobian.derivatives()[0] / (g * g);
        }
    }
  return total;
}

/// The control variate's part of the estimate: grad with the control (kAttachedControlSpp) less
/// grad without it (0) at the same seed, whose samples are the same (the pre-pass draws from a
/// stream of its own), is - c div(w V) summed over the camera samples plus c's part of the
/// attached flux; it must have mean zero (CameraAttachment::control). Over `seeds` seeds of `spp`,
/// the mean of the image sums' differences is within 3 standard errors of 0 (t with seeds - 1
/// degrees of freedom: 99 % for 16 seeds), and the Jacobian's part alone
/// (jacobian_control_part), which a flux without c would leave, is at least `power` of those
/// standard errors from 0.
void expect_control_part_vanishes(const std::string& file, const std::map<std::string, std::string>& defaults,
                                  const std::string& param, int spp, int seeds, double power) {
  const Scene scene = load_scene(test::data_file(file), defaults);
  const std::vector<ParameterSpec> params = {parse_parameter(param, scene)};
  EstimatorConfig with = EstimatorConfig::gradient(params, Method::Quadric);
  with.camera_hits = CameraHits::Attached;
  with.camera_control_spp = kAttachedControlSpp;  // the oracle's c (jacobian_control_part)
  EstimatorConfig without = with;
  without.camera_control_spp = 0;
  const Estimator a(scene, with), b(scene, without);
  ASSERT_GT(a.setup().control_pixels, 0) << file << ": no pixel has a control";
  double sum = 0, sum2 = 0;
  for (int i = 0; i < seeds; ++i) {
    const double d = test::derivative_sum(a.run(test::quiet(spp, uint64_t(100 + i)))).value -
                     test::derivative_sum(b.run(test::quiet(spp, uint64_t(100 + i)))).value;
    sum += d;
    sum2 += d * d;
  }
  const double mean = sum / seeds;
  const double se = std::sqrt(std::max(0.0, sum2 - seeds * mean * mean) / (seeds - 1) / seeds);
  const double jacobian = jacobian_control_part(scene, params);
  std::printf("%s %s: control's part %.4g +- %.3g; the Jacobian's alone %.4g\n", file.c_str(), param.c_str(), mean, se,
              jacobian);
  ASSERT_GT(se, 0) << file << ": c changed no sample";
  EXPECT_LE(std::abs(mean), 3 * se) << file << ": the control's part does not cancel";
  EXPECT_GE(std::abs(jacobian), power * se) << file << ": not the power the test claims";
}

TEST(SlowAttachedCameraControl, PartCancelsAtASilhouetteAndACrossing) {
  expect_control_part_vanishes("tests/data/gradient/sunk-sphere.xml", {{"res", "8"}}, "sphere:translate:0,1,0", 1024,
                               16, 6);
}

TEST(AttachedCamera, ControlVariatesPartCancelsBehindAStaticPost) {
  expect_control_part_vanishes("tests/data/gradient/metal-sunk-post.xml", {{"res", "8"}, {"alpha", "1"}},
                               "sphere:translate:0,1,0", 256, 16, 8);
}

TEST(AttachedCamera, ControlPrePassOfFewerThanTwoSamplesIsRefused) {
  // Its shrinkage needs the samples' variance: 1 (or a negative count) is an error, 2 the least
  // accepted, 0 no control.
  const Scene scene = load_scene(test::data_file("tests/data/gradient/sunk-sphere.xml"), {{"res", "8"}});
  EstimatorConfig config = EstimatorConfig::gradient({parse_parameter("sphere:translate:0,1,0", scene)});
  config.camera_hits = CameraHits::Attached;
  for (const int spp : {1, -3}) {
    config.camera_control_spp = spp;
    EXPECT_NE(test::message_of([&] {
                Estimator(scene, config);
              }).find("at least 2 pre-pass spp (got " + std::to_string(spp) + ")"),
              std::string::npos);
  }
  config.camera_control_spp = 2;
  EXPECT_GT(Estimator(scene, config).setup().control_pixels, 0);
  config.camera_control_spp = 0;
  EXPECT_EQ(Estimator(scene, config).setup().control_pixels, 0);
}

TEST(SlowAttachedCameraVsFD, SphereSunkIntoAFloorRising) {
  expect_attached_agrees("tests/data/gradient/sunk-sphere.xml", {{"res", "8"}}, "sphere:translate:0,1,0", 8192, 16384,
                         0.12);
}

TEST(SlowAttachedCameraVsFD, SphereRisingBehindAStaticPost) {
  expect_attached_agrees("tests/data/gradient/metal-sunk-post.xml", {{"res", "8"}, {"alpha", "1"}},
                         "sphere:translate:0,1,0", 32768, 65536, 0.05);
}

TEST(SlowAttachedCameraVsFD, DiffuseTeapotsSmoothedCreasesAdaptive) {
  // The adaptive rule on a diffuse mesh: partial strengths, the ramp, and the teapot's own
  // intersection curves at its lid. Heavy-tailed at 8 x 8 (one pixel holds half the variance), so
  // its power is 8 % (a 25 % bias fails); the tighter check is the 48 x 48 reference comparison in
  // docs/experiments/2026-11-28-diffuse-creases.md.
  expect_attached_agrees("scenes/stability/teapot.xml", {{"res", "8"}}, "teapot:translate:0,1,0", 16384, 16384, 0.08,
                         CameraHits::Adaptive);
}

}  // namespace
}  // namespace qsil
