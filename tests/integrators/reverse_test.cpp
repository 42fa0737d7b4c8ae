// Reverse mode (qsil/integrators/reverse.h) against forward mode, the oracle it must reproduce:
// for a parameter theta with vertex velocities v_j = dx_j/dtheta, sum_j (dL/dx_j) . v_j must equal
// sum_x,c w_c(x) dI_c(x)/dtheta of `qsil grad` (forward mode, itself checked against finite
// differences in gradient_vs_fd_test.cpp).
// - Interior term: with the same seed both modes trace the same paths, so the two sums agree to
//   rounding (relative 1e-9) for translations, rotations and a single vertex of two shapes at
//   once, through paths with up to five chosen-shape hits (replayed passes).
// - Boundary terms: the edge sampler's importance differs (reverse mode has no velocities), so
//   the check is statistical: independent seeds, the difference from forward mode and from
//   central finite differences each within 3.5 combined standard errors (two-sided, 99.95 % for
//   a correct estimator), with power: each combined standard error below 4 % of the value; on
//   spot-selfshadow (a diffuse mesh under a small light; both modes at the quadric method's
//   default of one traversal every other sample, boundary_traversals) and on spot-mirror (whose
//   glossy mirror vertices estimate contour sets, qsil/edgetree/contour_set.h; one traversal per
//   sample, for power at a test's spp). Both modes are bit-identical
//   for 1 and 2 threads on both scenes.
// - Attached camera hits (attached_camera.h): where no path meets an edge that hides anything (a
//   convex sphere alone; one segment) the secondary boundary term is zero and both modes draw
//   the same primary samples, so the whole gradient agrees to rounding: the warped direction, the
//   warp's Jacobian less the control variate, and the attached flux at a silhouette, an
//   intersection curve and a static shape's outline (each left out once, the test fails). Behind a
//   static post on a floor, reverse mode agrees with FD as above.
#include "qsil/integrators/reverse.h"
#include "qsil/error.h"
#include "qsil/integrators/boundary_schedule.h"
#include "qsil/integrators/estimator.h"
#include "qsil/ray_tracer.h"
#include "qsil/rng.h"
#include "qsil/scene.h"
#include "qsil/vertex_normals.h"
#include "test_data.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

namespace qsil {
namespace {

/// A fixed pseudo-random adjoint image with both signs in every channel.
std::vector<double> random_adjoint(const Scene& scene, uint64_t seed) {
  Sampler rng(seed, 0, 0);
  std::vector<double> w(size_t(scene.camera.width) * scene.camera.height * 3);
  for (double& v : w) v = 2 * rng.next() - 1;
  return w;
}

/// sum_x,c w_c(x) dI_c/dtheta_k of a forward-mode film.
double forward_dot(const Film& film, const FilmLayout& layout, int k, const std::vector<double>& w) {
  double s = 0;
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x)
      for (int c = 0; c < 3; ++c) s += w[3 * (size_t(y) * film.width() + x) + c] * film.mean(layout.derivative(k, c), x, y);
  return s;
}

/// sum_j g_j . v_j for parameter k (velocities of the chosen shapes, in ReverseConfig order).
double reverse_dot(const ReverseResult& r, const std::vector<int>& shapes, const SceneVelocities& vel, int k) {
  double s = 0;
  for (size_t i = 0; i < shapes.size(); ++i)
    for (size_t v = 0; v < r.gradient[i].size(); ++v)
      s += r.gradient[i][v].dot(vel.position[size_t(shapes[i])][v].col(k));
  return s;
}

TEST(ReverseMode, VertexNormalsAdjointIsTheTransposeOfTheirForwardDerivative) {
  // A bumpy icosphere (irregular areas), a random adjoint per normal and a random motion per
  // vertex: a . (dN/dx) delta in forward mode equals (dL/dx) . delta from the adjoint.
  TriangleMesh mesh = test::icosphere(2);
  Sampler rng(7, 0, 0);
  for (Vec3& p : mesh.positions) p *= 0.8 + 0.4 * rng.next();
  std::vector<Vec3> d_normal(mesh.positions.size()), delta(mesh.positions.size());
  for (size_t i = 0; i < d_normal.size(); ++i) {
    d_normal[i] = Vec3(rng.next(), rng.next(), rng.next()) - Vec3::Constant(0.5);
    delta[i] = Vec3(rng.next(), rng.next(), rng.next()) - Vec3::Constant(0.5);
  }
  std::vector<Vec3T<Dual<1>>> pos(mesh.positions.size());
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = lift<1>(mesh.positions[i], Eigen::Matrix<double, 3, 1>(delta[i]));
  const auto n = vertex_normals_t(mesh, pos);
  double forward = 0, scale = 0;
  for (size_t i = 0; i < n.size(); ++i)
    for (int r = 0; r < 3; ++r) {
      forward += d_normal[i][r] * n[i][r].derivatives()[0];
      scale += std::abs(d_normal[i][r] * n[i][r].derivatives()[0]);
    }
  std::vector<Vec3> d_position(mesh.positions.size(), Vec3::Zero());
  vertex_normals_adjoint(mesh, d_normal, d_position);
  double reverse = 0;
  for (size_t i = 0; i < delta.size(); ++i) reverse += d_position[i].dot(delta[i]);
  ASSERT_GT(scale, 1.0);  // not vacuous
  EXPECT_NEAR(reverse, forward, 1e-10 * scale);
}

TEST(ReverseMode, InteriorTermEqualsForwardModeOnTheSamePaths) {
  // Spot above a GGX mirror under an environment map, 6 segments: paths hit Spot and the mirror
  // several times. Four parameters of both shapes, all from one reverse run.
  const Scene scene = load_scene(test::repo_path("scenes/spot-mirror.xml"),
                                 {{"res", "24"}, {"spp", "4"}, {"max_depth", "6"}});
  const std::vector<ParameterSpec> params =
      parse_parameters({"spot:translate:0.3,1,-0.2", "spot:rotate:0,1,0", "spot:vertex:100:1,0.5,0",
                        "mirror:rotate:1,0,0"},
                       scene);
  const std::vector<int> shapes = resolve_shapes(scene, {"spot", "mirror"});
  const std::vector<double> w = random_adjoint(scene, 3);
  RenderOptions opt;
  opt.seed = 11;
  opt.progress = false;
  const Estimator forward(scene, EstimatorConfig::gradient(params, Method::None));
  const RenderResult f = forward.run(opt);
  const ReverseEstimator reverse(scene, ReverseConfig{shapes, Method::None, 1});
  const ReverseResult r = reverse.run(w, opt);
  EXPECT_GT(r.replays, 0u) << "no path had more than two chosen-shape hits: the replay is untested";
  EXPECT_EQ(r.nonfinite, 0u);
  const SceneVelocities vel = compute_velocities(scene, params);
  for (int k = 0; k < int(params.size()); ++k) {
    const double a = forward_dot(f.film, forward.layout(), k, w), b = reverse_dot(r, shapes, vel, k);
    std::printf("%-28s forward %.12g reverse %.12g\n", params[size_t(k)].text.c_str(), a, b);
    EXPECT_GT(std::abs(a), 1e-3) << "vacuous";
    EXPECT_NEAR(b, a, 1e-9 * std::abs(a)) << params[size_t(k)].text;
  }
  // The primal image of the same paths, and the loss of the linear adjoint.
  double loss = 0;
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = 3 * (size_t(y) * scene.camera.width + x) + c;
        EXPECT_NEAR(r.image[i], f.film.mean(forward.layout().primal(c), x, y), 1e-12 * (1 + std::abs(r.image[i])));
        loss += w[i] * r.image[i];
      }
  EXPECT_NEAR(r.loss, loss, 1e-9 * std::abs(loss));
}

TEST(ReverseMode, InteriorTermEqualsForwardModeOnTheOtherBundledScenes) {
  // shadow-quad (the bunny over a floor under an area light) and direct (Spot before a backdrop):
  // a rotation and a scale or a vertex of the object, and a translation of the other shape.
  struct Case {
    const char* file;
    std::vector<std::string> params, shapes;
  };
  const std::vector<Case> cases = {
      {"scenes/shadow-quad.xml", {"object:rotate:0,1,0", "object:scale", "floor:translate:0,1,0"},
       {"object", "floor"}},
      // Vertex 2088 faces the camera near the image centre (the primary rays reach it; a vertex on
      // Spot's far side is reached by few secondary paths at 16² and 4 spp, or by none).
      {"scenes/direct.xml", {"spot:rotate:1,0,0", "spot:vertex:2088:1,1,0", "backdrop:translate:0,0,1"},
       {"spot", "backdrop"}}};
  for (const Case& c : cases) {
    const Scene scene = load_scene(test::repo_path(c.file), {{"res", "16"}, {"spp", "4"}, {"max_depth", "4"}});
    const std::vector<ParameterSpec> params = parse_parameters(c.params, scene);
    const std::vector<int> shapes = resolve_shapes(scene, c.shapes);
    const std::vector<double> w = random_adjoint(scene, 4);
    RenderOptions opt;
    opt.seed = 12;
    opt.progress = false;
    const Estimator forward(scene, EstimatorConfig::gradient(params, Method::None));
    const Film film = forward.run(opt).film;
    const ReverseResult r = ReverseEstimator(scene, ReverseConfig{shapes, Method::None, 1}).run(w, opt);
    const SceneVelocities vel = compute_velocities(scene, params);
    for (int k = 0; k < int(params.size()); ++k) {
      const double a = forward_dot(film, forward.layout(), k, w), b = reverse_dot(r, shapes, vel, k);
      std::printf("%-18s %-26s forward %.12g reverse %.12g\n", c.file, params[size_t(k)].text.c_str(), a, b);
      EXPECT_GT(std::abs(a), 1e-6) << "vacuous: " << params[size_t(k)].text;
      EXPECT_NEAR(b, a, 1e-9 * std::abs(a)) << c.file << " " << params[size_t(k)].text;
    }
  }
}

/// "ID:vertex:V:1,0.5,0" for the vertex V of shape `id` nearest the image centre that the camera
/// sees (faces it, nothing in front of it).
std::string visible_vertex_param(const Scene& scene, const std::string& id) {
  const TriangleMesh& mesh = scene.shapes[size_t(scene.find_shape(id))].mesh;
  const Vec2 centre(0.5 * scene.camera.width, 0.5 * scene.camera.height);
  const RayTracer tracer(scene);
  const Vec3 o = scene.camera.origin();
  int vertex = 0;
  double best = kInf;
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    if (!(mesh.normals[v].dot(o - mesh.positions[v]) > 0)) continue;
    const double to_vertex = (mesh.positions[v] - o).norm();
    if (tracer.intersect(o, (mesh.positions[v] - o) / to_vertex).t < to_vertex * (1 - 1e-6)) continue;  // hidden
    const double d = (scene.camera.project(mesh.positions[v]) - centre).norm();
    if (d < best) best = d, vertex = int(v);
  }
  return id + ":vertex:" + std::to_string(vertex) + ":1,0.5,0";
}

/// Forward and reverse mode with every camera hit on the chosen shapes `ids` attached
/// (CameraHits::Attached) and the control variate, at `sppi` secondary traversals per vertex and
/// seed `seed`: both modes trace the same paths and draw the same primary edge samples, so where
/// the secondary boundary term is zero (the scene's comment, or no traversal scheduled: sppi
/// 1/1024 and a seed that schedules none, which the function checks) the two sums agree to
/// rounding for each parameter. Detached, the sum of some parameter differs (the attached form's
/// parts are not vacuous); `replays`: paths meet the chosen shapes more than twice (replayed passes after an
/// attached first pass of one hit).
void expect_attached_reverse_equals_forward(const Scene& scene, const std::vector<std::string>& ids,
                                            const std::vector<std::string>& param_texts, double sppi, uint64_t seed,
                                            bool replays) {
  const std::string& file = scene.file.string();
  const std::vector<ParameterSpec> params = parse_parameters(param_texts, scene);
  const std::vector<int> shapes = resolve_shapes(scene, ids);
  if (sppi < 1) {
    for (uint64_t pixel = 0; pixel < uint64_t(scene.camera.width) * scene.camera.height; ++pixel)
      for (int s = 0; s < scene.camera.spp; ++s)
        ASSERT_EQ(boundary_traversals(sppi, seed, pixel, uint64_t(s)), 0)
            << "seed " << seed << " schedules a traversal";
  }
  const std::vector<double> w = random_adjoint(scene, 5);
  RenderOptions opt;
  opt.seed = seed;
  opt.progress = false;
  EstimatorConfig fc = EstimatorConfig::gradient(params, Method::Quadric, sppi);
  fc.camera_hits = CameraHits::Attached;
  const Estimator forward(scene, fc);
  const Film film = forward.run(opt).film;
  ReverseConfig rc{shapes, Method::Quadric, sppi};
  rc.camera_hits = CameraHits::Attached;
  const ReverseEstimator reverse(scene, rc);
  ASSERT_GT(reverse.setup().attached_vertices, 0) << file;
  ASSERT_GT(reverse.setup().control_pixels, 0) << file;
  EXPECT_EQ(reverse.setup().control_pixels, forward.setup().control_pixels) << file;
  EXPECT_EQ(reverse.setup().static_primary_edges, forward.setup().static_primary_edges) << file;
  const ReverseResult r = reverse.run(w, opt);
  EXPECT_EQ(r.nonfinite, 0u) << file;
  if (replays) {
    EXPECT_GT(r.replays, 0u) << file << ": no path met the chosen shapes more than once after its camera hit";
  }
  rc.camera_hits = CameraHits::Detached;
  const ReverseResult d = ReverseEstimator(scene, rc).run(w, opt);
  const SceneVelocities vel = compute_velocities(scene, params);
  int attached_differs = 0;
  for (int k = 0; k < int(params.size()); ++k) {
    const double a = forward_dot(film, forward.layout(), k, w), b = reverse_dot(r, shapes, vel, k),
                 c = reverse_dot(d, shapes, vel, k);
    std::printf("%s %-30s forward %.12g reverse %.12g (detached %.6g)\n", file.c_str(), params[size_t(k)].text.c_str(),
                a, b, c);
    EXPECT_GT(std::abs(a), 1e-3) << "vacuous";
    attached_differs += std::abs(c - a) > 1e-3 * std::abs(a);
    EXPECT_NEAR(b, a, 1e-9 * std::abs(a)) << file << " " << params[size_t(k)].text;
  }
  EXPECT_GT(attached_differs, 0) << file << ": attached and detached agree: the test tests nothing";
}

TEST(ReverseMode, AttachedCameraHitsEqualForwardModeOnTheSamePaths) {
  // A rough-metal sphere alone under an environment map, three segments: the path's derivative
  // along the warped direction, the warp's Jacobian less c, the flux at the sphere's silhouette.
  const Scene sphere = load_scene(test::data_file("tests/data/gradient/metal-sphere.xml"),
                                  {{"res", "16"}, {"spp", "4"}, {"max_depth", "3"}});
  expect_attached_reverse_equals_forward(
      sphere, {"sphere"},
      {"sphere:translate:0.3,1,-0.2", "sphere:rotate:1,0,0", visible_vertex_param(sphere, "sphere")}, 0, 13, false);
  // An emissive sphere sunk into a floor behind a static post, one segment: the Jacobian term and
  // the flux at the silhouette, at the intersection curve and at the post's outline, an edge of a
  // shape that is not chosen.
  const Scene post = load_scene(test::data_file("tests/data/gradient/glowing-sunk-post.xml"),
                                {{"res", "16"}, {"spp", "4"}, {"max_depth", "1"}});
  expect_attached_reverse_equals_forward(
      post, {"sphere"}, {"sphere:translate:0.3,1,-0.2", "sphere:rotate:1,0,0", visible_vertex_param(post, "sphere")}, 0,
      13, false);
  // Spot and the glossy mirror both chosen and attached, 6 segments, and no secondary traversal
  // scheduled (seed 14): the camera sees Spot only in the mirror, so its hits come after an
  // attached camera hit on the mirror whose first pass holds one hit, and later windows start at
  // hit 1 (replays); Spot's parameters do not move the mirror's warp, the mirror's do.
  const Scene mirror =
      load_scene(test::data_file("scenes/spot-mirror.xml"), {{"res", "16"}, {"spp", "4"}, {"max_depth", "6"}});
  expect_attached_reverse_equals_forward(
      mirror, {"spot", "mirror"},
      {"spot:translate:0.3,1,-0.2", "spot:rotate:0,1,0", visible_vertex_param(mirror, "spot"), "mirror:rotate:1,0,0"},
      1.0 / 1024, 14, true);
}

/// Mean and standard error of `runs` independent estimates.
struct Estimate {
  double mean = 0, se = 0;
};
template <class F>
Estimate estimate(int runs, F&& one) {
  std::vector<double> v;
  for (int i = 0; i < runs; ++i) v.push_back(one(uint64_t(1000 + 17 * i)));
  Estimate e;
  e.mean = std::accumulate(v.begin(), v.end(), 0.0) / runs;
  double var = 0;
  for (double x : v) var += (x - e.mean) * (x - e.mean);
  e.se = std::sqrt(var / (runs - 1) / runs);
  return e;
}

/// The boundary-term check of the file comment for `param` of shape `shape_id` in a scene. The
/// adjoint is the sign of a pilot forward-mode derivative per pixel-channel (its own seed), so
/// that the weighted sum adds the derivative's magnitude everywhere instead of cancelling. Both
/// modes run at `rate` secondary traversals per vertex (EstimatorConfig::sppi; 0: the
/// method's default, a stratified pick of half the samples), both with camera hits `hits`;
/// `against_forward` false: against FD alone (where forward mode's noise would need a longer run).
void expect_boundary_agreement(const Scene& scene, const std::string& param, const std::string& shape_id, int runs,
                               double rate, CameraHits hits = CameraHits::Adaptive, bool against_forward = true) {
  const std::vector<ParameterSpec> params = parse_parameters({param}, scene);
  const std::vector<int> shapes = resolve_shapes(scene, {shape_id});
  const SceneVelocities vel = compute_velocities(scene, params);
  EstimatorConfig fc = EstimatorConfig::gradient(params, Method::Quadric, rate);
  fc.camera_hits = hits;
  const Estimator forward(scene, fc);
  ReverseConfig rc{shapes, Method::Quadric, rate};
  rc.camera_hits = hits;
  const ReverseEstimator reverse(scene, rc);
  RenderOptions pilot_options;
  pilot_options.seed = 99;
  pilot_options.progress = false;
  const RenderResult pilot = forward.run(pilot_options);
  std::vector<double> w(size_t(scene.camera.width) * scene.camera.height * 3);
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const double d = pilot.film.mean(forward.layout().derivative(0, c), x, y);
        w[3 * (size_t(y) * scene.camera.width + x) + c] = d > 0 ? 1.0 : (d < 0 ? -1.0 : 0.0);
      }
  // Forward mode's seeds are the reverse runs' + 1: independent samples.
  const Estimate a = estimate(against_forward ? runs : 2, [&](uint64_t seed) {
    if (!against_forward) return 0.0;
    RenderOptions opt;
    opt.seed = seed + 1;
    opt.progress = false;
    return forward_dot(forward.run(opt).film, forward.layout(), 0, w);
  });
  const Estimate b = estimate(runs, [&](uint64_t seed) {
    RenderOptions opt;
    opt.seed = seed;
    opt.progress = false;
    return reverse_dot(reverse.run(w, opt), shapes, vel, 0);
  });
  // Central finite differences with common random numbers (step 1e-2, as gradient_check's cases),
  // at 4x the spp: FD is cheap per sample and noisier at silhouettes.
  const Estimator fd(scene, EstimatorConfig::finite_differences(params, {1e-2}));
  const Estimate c = estimate(runs, [&](uint64_t seed) {
    RenderOptions opt;
    opt.spp = 4 * scene.camera.spp;
    opt.seed = seed + 2;
    opt.progress = false;
    return forward_dot(fd.run(opt).film, fd.layout(), 0, w);
  });
  const double se = std::hypot(a.se, b.se), se_fd = std::hypot(c.se, b.se);
  if (against_forward)
    std::printf("%s: forward %.5g +- %.3g (z %.2f)\n", param.c_str(), a.mean, a.se, (b.mean - a.mean) / se);
  std::printf("%s: reverse %.5g +- %.3g, FD %.5g +- %.3g (z %.2f)\n", param.c_str(), b.mean, b.se, c.mean, c.se,
              (b.mean - c.mean) / se_fd);
  if (against_forward) {
    EXPECT_LT(se, 0.04 * std::abs(a.mean)) << "no power";
    EXPECT_NEAR(b.mean, a.mean, 3.5 * se);
  }
  EXPECT_LT(se_fd, 0.04 * std::abs(c.mean)) << "no power";
  EXPECT_NEAR(b.mean, c.mean, 3.5 * se_fd);
}

TEST(ReverseMode, SecondaryBoundaryTermAgreesWithForwardMode) {
  // Spot translating under a small light: its shadows on itself (a moving p sees the static
  // light's outline and Spot's own silhouettes move), and its outline against the environment.
  const Scene scene =
      load_scene(test::data_file("tests/data/gradient/spot-selfshadow.xml"), {{"res", "16"}, {"spp", "192"}});
  expect_boundary_agreement(scene, "spot:translate:1,0,0", "spot", 12, 0);
}

TEST(ReverseMode, PrimaryBoundaryTermAgreesWithForwardMode) {
  // Spot under a constant environment with one segment: Spot is black and the environment is
  // seen around it, so the derivative is Spot's outline moving across the image, the primary
  // boundary term alone.
  const Scene scene = load_scene(test::data_file("tests/data/gradient/spot-selfshadow.xml"),
                                 {{"res", "16"}, {"spp", "64"}, {"max_depth", "1"}});
  expect_boundary_agreement(scene, "spot:translate:1,0,0", "spot", 8, 1);
}

TEST(ReverseMode, SecondaryBoundaryTermAgreesWithForwardModeAtAGlossyMirror) {
  // Spot seen only in a GGX alpha 0.01 mirror: the mirror's boundary term uses contour sets. Two
  // segments: Spot is black, so the term is Spot's reflected outline against the environment.
  const Scene scene =
      load_scene(test::data_file("scenes/spot-mirror.xml"), {{"res", "16"}, {"spp", "256"}, {"max_depth", "2"}});
  expect_boundary_agreement(scene, "spot:translate:0,1,0", "spot", 8, 1);
}

TEST(ReverseMode, SecondaryBoundaryTermAgreesWithForwardModeUnderASphereLight) {
  // A sphere occluder between a floor and a small sphere light (a mesh emitter, which the edge
  // choice knows by its bounding sphere): the floor's penumbra, the boundary term alone.
  const Scene scene =
      load_scene(test::data_file("scenes/stability/sphere-light.xml"), {{"res", "16"}, {"spp", "256"}});
  expect_boundary_agreement(scene, "occluder:translate:1,0,0", "occluder", 8, 0);
}

TEST(SlowReverseMode, AttachedCameraHitsAgreeWithFDBehindAStaticPost) {
  // Every camera hit on the rough sphere attached: its flux crosses the sphere's silhouette, the
  // circle where it pierces the floor (an intersection curve) and the static post's outline (an
  // edge of a shape that is not chosen), where the detached form has no term at all. Against FD
  // alone: forward mode is as noisy as reverse mode here and would double the run. Its power (the
  // combined standard error at most 4 % of the value) sees a 14 % bias; the post's share of the
  // flux is smaller (a run without it gave z = -1.4), and AttachedCameraHitsEqualForwardModeOnThe-
  // SamePaths checks that share exactly.
  const Scene scene = load_scene(test::data_file("tests/data/gradient/metal-sunk-post.xml"),
                                 {{"res", "8"}, {"spp", "2048"}, {"alpha", "1"}});
  expect_boundary_agreement(scene, "sphere:translate:0,1,0", "sphere", 16, 0, CameraHits::Attached, false);
}

/// Reverse mode's gradient is bit-identical for 1 and 2 threads (a diffuse scene, and the glossy
/// mirror whose vertices use contour sets).
void expect_same_gradient_for_any_thread_count(const Scene& scene) {
  const ReverseEstimator reverse(scene, ReverseConfig{resolve_shapes(scene, {"spot"}), Method::Quadric, 1});
  const std::vector<double> w = random_adjoint(scene, 5);
  RenderOptions opt;
  opt.seed = 3;
  opt.progress = false;
  opt.threads = 1;
  const ReverseResult one = reverse.run(w, opt);
  opt.threads = 2;
  const ReverseResult two = reverse.run(w, opt);
  ASSERT_EQ(one.gradient.size(), two.gradient.size());
  size_t nonzero = 0;
  for (size_t v = 0; v < one.gradient[0].size(); ++v) {
    EXPECT_EQ(one.gradient[0][v], two.gradient[0][v]) << "vertex " << v;
    nonzero += !one.gradient[0][v].isZero(0.0);
  }
  EXPECT_GT(nonzero, 100u);
  EXPECT_EQ(one.loss, two.loss);
}

TEST(ReverseMode, SameGradientForAnyThreadCount) {
  expect_same_gradient_for_any_thread_count(
      load_scene(test::data_file("tests/data/gradient/spot-selfshadow.xml"), {{"res", "16"}, {"spp", "4"}}));
  expect_same_gradient_for_any_thread_count(
      load_scene(test::data_file("scenes/spot-mirror.xml"), {{"res", "16"}, {"spp", "4"}}));
}

/// The probe pass (ReverseConfig::probe_paths) changes what a run costs, not what it estimates:
/// with and without it, one seed gives the same image, loss and gradient to rounding (relative
/// 1e-12: a path's radiance in doubles and as a dual's value may differ in the last bit), and the
/// probe completes some samples but not all (the others meet the chosen shapes). The counters are
/// equal too, except that replayed passes after a probe start their boundary term at the first
/// chosen-shape hit (fewer rays and traversals; `replays`: there must be some). Fails if
/// the probe sampled diffuse directions from the cosine density (other paths), completed a path
/// that meets a chosen shape (its interior term lost), or if a dual pass after a probe redid the
/// boundary term of the vertices before the first chosen-shape hit (counted twice) or did not
/// continue the probe's boundary stream (other boundary samples).
void expect_probe_changes_nothing(const Scene& scene, const std::vector<std::string>& ids, bool replays,
                                  CameraHits hits = CameraHits::Adaptive) {
  ReverseConfig config{resolve_shapes(scene, ids), Method::Quadric, 1};
  config.camera_hits = hits;
  const ReverseEstimator probing(scene, config);
  if (hits == CameraHits::Attached) {
    ASSERT_GT(probing.setup().attached_vertices, 0) << "nothing attached: the probe's stop at the camera is untested";
  }
  config.probe_paths = false;
  const ReverseEstimator duals(scene, config);
  const std::vector<double> w = random_adjoint(scene, 7);
  RenderOptions opt;
  opt.seed = 9;
  opt.progress = false;
  opt.threads = 2;
  const ReverseResult a = probing.run(w, opt), b = duals.run(w, opt);
  const uint64_t samples = uint64_t(scene.camera.width) * scene.camera.height * uint64_t(a.spp);
  EXPECT_GT(a.probed, samples / 20) << "the probe completed too few samples to test it";
  EXPECT_LT(a.probed, samples - samples / 20) << "too few samples met the chosen shapes to test the probe";
  EXPECT_EQ(b.probed, 0u);
  EXPECT_EQ(a.replays, b.replays);
  // (A path whose camera hit is attached holds one hit in its first pass, so a scene without
  // replays may have a few.)
  if (replays) {
    EXPECT_GT(a.replays, 0u) << "no replayed pass: the replay after a probe is untested";
  }
  const auto close = [](double x, double y) { return std::abs(x - y) <= 1e-12 * std::max(std::abs(x), std::abs(y)); };
  ASSERT_EQ(a.image.size(), b.image.size());
  size_t image_differ = 0;
  for (size_t i = 0; i < a.image.size(); ++i) image_differ += !close(a.image[i], b.image[i]);
  EXPECT_EQ(image_differ, 0u) << "of " << a.image.size() << " pixel channels";
  EXPECT_TRUE(close(a.loss, b.loss)) << a.loss << " vs " << b.loss;
  if (replays) {
    EXPECT_LT(a.rays, b.rays);
    EXPECT_LT(a.traversals, b.traversals);
  } else if (a.replays > 0) {  // replays of attached camera hits, whose probe stops at the camera
    EXPECT_LE(a.rays, b.rays);
    EXPECT_LE(a.traversals, b.traversals);
  } else {
    EXPECT_EQ(a.rays, b.rays);
    EXPECT_EQ(a.traversals, b.traversals);
    EXPECT_EQ(a.zero_traversals, b.zero_traversals);
  }
  EXPECT_EQ(a.nonfinite, b.nonfinite);
  ASSERT_EQ(a.gradient.size(), b.gradient.size());
  size_t nonzero = 0, differ = 0, entries = 0;
  for (size_t i = 0; i < a.gradient.size(); ++i)
    for (size_t v = 0; v < a.gradient[i].size(); ++v) {
      for (int c = 0; c < 3; ++c) differ += !close(a.gradient[i][v][c], b.gradient[i][v][c]);
      nonzero += !a.gradient[i][v].isZero(0.0);
      entries += 3;
    }
  EXPECT_EQ(differ, 0u) << "of " << entries << " gradient entries";
  EXPECT_GT(nonzero, 100u);
}

TEST(ReverseMode, ProbePassChangesNothingButTheCost) {
  // An object casting a shadow on a diffuse floor under a quad light (the paths that scatter on
  // the floor and miss the object skip the duals: the probe must sample and weigh diffuse
  // directions as a dual path does); Spot in a glossy mirror under an environment map; and the
  // same with 6 segments and the mirror chosen too, where paths meet the chosen shapes more than
  // twice (replayed passes after a probe).
  expect_probe_changes_nothing(load_scene(test::data_file("scenes/shadow-quad.xml"), {{"res", "16"}, {"spp", "4"}}),
                               {"object"}, false);
  expect_probe_changes_nothing(load_scene(test::data_file("scenes/spot-mirror.xml"), {{"res", "16"}, {"spp", "4"}}),
                               {"spot"}, false);
  expect_probe_changes_nothing(
      load_scene(test::data_file("scenes/spot-mirror.xml"), {{"res", "32"}, {"spp", "8"}, {"max_depth", "8"}}),
      {"spot"}, true);
  // An emissive sphere with every camera hit on it attached, one segment: no path scatters, so a
  // probe that did not stop at an attached camera hit would complete the sample without the
  // warp's Jacobian term.
  expect_probe_changes_nothing(
      load_scene(test::data_file("tests/data/gradient/glowing-sunk-post.xml"), {{"res", "16"}, {"spp", "4"}}),
      {"sphere"}, false, CameraHits::Attached);
}

/// Moves shape `id`'s vertices by a smooth field of amplitude amp times its bounding-box diagonal
/// and recomputes its vertex normals, as Python's set_vertices does.
void displace(Scene& scene, const std::string& id, double amp) {
  TriangleMesh& mesh = scene.shapes[size_t(resolve_shapes(scene, {id})[0])].mesh;
  const double d = mesh.bounds().diagonal();
  for (Vec3& p : mesh.positions)
    p += amp * d * Vec3(std::sin(5 * p.y() / d), std::cos(4 * p.z() / d), std::sin(3 * p.x() / d));
  mesh.normals = vertex_normals(mesh);
}

/// ReverseEstimator::update after the vertices moved equals a new estimator on the moved scene:
/// bit-identical without a boundary term and in the image (the ray tracer and lights moved; the
/// paths do not depend on the edge structure), and within 3.5 combined standard errors in the
/// gradient's boundary-weighted sum (the refitted forest draws other edges, the same integral;
/// with power: standard error below 4 % of the value). A stale ray tracer, primary edge set or
/// contour index fails it (checked by leaving each out of update).
TEST(ReverseMode, UpdateAfterMovedVerticesMatchesANewEstimator) {
  Scene scene =
      load_scene(test::data_file("tests/data/gradient/spot-selfshadow.xml"), {{"res", "16"}, {"spp", "192"}});
  const std::vector<int> shapes = resolve_shapes(scene, {"spot"});
  ReverseEstimator interior(scene, ReverseConfig{shapes, Method::None});
  ReverseEstimator boundary(scene, ReverseConfig{shapes, Method::Quadric, 1});
  displace(scene, "spot", 0.01);
  const ReverseUpdate ui = interior.update(), ub = boundary.update();
  EXPECT_FALSE(ui.refitted);
  EXPECT_TRUE(ub.refitted) << ub.reason;
  const ReverseEstimator fresh_interior(scene, ReverseConfig{shapes, Method::None});
  const ReverseEstimator fresh(scene, ReverseConfig{shapes, Method::Quadric, 1});
  const std::vector<double> w = random_adjoint(scene, 5);
  RenderOptions opt;
  opt.seed = 3;
  opt.spp = 8;
  opt.progress = false;
  const ReverseResult a = interior.run(w, opt), b = fresh_interior.run(w, opt);
  ASSERT_EQ(a.gradient[0].size(), b.gradient[0].size());
  for (size_t v = 0; v < a.gradient[0].size(); ++v) ASSERT_EQ(a.gradient[0][v], b.gradient[0][v]) << "vertex " << v;
  EXPECT_EQ(a.image, b.image);
  EXPECT_EQ(boundary.run(w, opt).image, fresh.run(w, opt).image);
  // The boundary-weighted sum: adjoint = sign of a pilot forward-mode derivative (translation).
  const std::vector<ParameterSpec> params = parse_parameters({"spot:translate:1,0,0"}, scene);
  const SceneVelocities vel = compute_velocities(scene, params);
  const Estimator forward(scene, EstimatorConfig::gradient(params, Method::Quadric, 1));
  RenderOptions pilot_options;
  pilot_options.seed = 99;
  pilot_options.progress = false;
  const RenderResult pilot = forward.run(pilot_options);
  std::vector<double> sign(w.size());
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const double d = pilot.film.mean(forward.layout().derivative(0, c), x, y);
        sign[3 * (size_t(y) * scene.camera.width + x) + c] = d > 0 ? 1.0 : (d < 0 ? -1.0 : 0.0);
      }
  auto run_dot = [&](const ReverseEstimator& e) {
    return [&](uint64_t seed) {
      RenderOptions o;
      o.seed = seed;
      o.progress = false;
      return reverse_dot(e.run(sign, o), shapes, vel, 0);
    };
  };
  const Estimate updated = estimate(8, run_dot(boundary));
  const Estimate anew = estimate(8, [&](uint64_t seed) { return run_dot(fresh)(seed + 1); });
  const double se = std::hypot(updated.se, anew.se);
  std::printf("updated %.5g +- %.3g, new %.5g +- %.3g (z %.2f)\n", updated.mean, updated.se, anew.mean, anew.se,
              (updated.mean - anew.mean) / se);
  EXPECT_LT(se, 0.04 * std::abs(anew.mean)) << "no power";
  EXPECT_NEAR(updated.mean, anew.mean, 3.5 * se);
}

/// ReverseEstimator::render is the primal estimator's image and counters, bit for bit, before and
/// after an update() for moved vertices and from another first sample (oracle: Estimator(primal)
/// set up on the scene as it is then); render and run refuse a scene changed without update().
TEST(ReverseMode, RenderIsThePrimalEstimatorsImage) {
  Scene scene = load_scene(test::data_file("tests/data/gradient/spot-selfshadow.xml"), {{"res", "16"}, {"spp", "4"}});
  const std::vector<int> shapes = resolve_shapes(scene, {"spot"});
  ReverseEstimator e(scene, ReverseConfig{shapes, Method::Quadric, 1});
  RenderOptions opt;
  opt.seed = 7;
  opt.spp = 4;
  opt.progress = false;
  const auto same_as_primal = [&](const char* when) {
    const RenderResult a = e.render(opt);
    const RenderResult b = Estimator(scene, EstimatorConfig::primal()).run(opt);
    ASSERT_EQ(a.film.channels(), b.film.channels()) << when;
    EXPECT_EQ(a.spp, b.spp) << when;
    EXPECT_EQ(a.first_sample, b.first_sample) << when;
    EXPECT_EQ(a.rays, b.rays) << when;
    EXPECT_EQ(a.nonfinite, b.nonfinite) << when;
    double sum = 0;
    for (int y = 0; y < scene.camera.height; ++y)
      for (int x = 0; x < scene.camera.width; ++x)
        for (int c = 0; c < a.film.channels(); ++c) {
          ASSERT_EQ(a.film.mean(c, x, y), b.film.mean(c, x, y)) << when << ": pixel " << x << ", " << y;
          sum += a.film.mean(c, x, y);
        }
    EXPECT_GT(sum, 0) << when << ": an empty image proves nothing";
  };
  same_as_primal("as set up");
  opt.first_sample = 3;
  same_as_primal("from sample 3");
  opt.first_sample = 0;
  const RenderResult before = e.render(opt);
  displace(scene, "spot", 0.05);
  EXPECT_THROW(e.render(opt), Error);  // stale: the scene changed without update()
  EXPECT_THROW(e.run(std::vector<double>(size_t(3 * 16 * 16), 1.0), opt), Error);
  e.update();
  same_as_primal("after update()");
  // The moved mesh changes the image: render follows the update, not the set-up.
  bool differs = false;
  const RenderResult after = e.render(opt);
  for (int y = 0; y < scene.camera.height && !differs; ++y)
    for (int x = 0; x < scene.camera.width && !differs; ++x) differs = before.film.mean(0, x, y) != after.film.mean(0, x, y);
  EXPECT_TRUE(differs);
  opt.parts = 2;
  EXPECT_THROW(e.render(opt), Error);
}

/// After a remeshing (other vertex and triangle counts) update sets up anew: the same result as a
/// new estimator, bit for bit.
TEST(ReverseMode, UpdateAfterARemeshingSetsUpAnew) {
  Scene scene = load_scene(test::data_file("tests/data/gradient/spot-selfshadow.xml"), {{"res", "8"}, {"spp", "4"}});
  const std::vector<int> shapes = resolve_shapes(scene, {"spot"});
  ReverseEstimator e(scene, ReverseConfig{shapes, Method::Quadric, 1});
  TriangleMesh& mesh = scene.shapes[size_t(shapes[0])].mesh;
  mesh.triangles.pop_back();  // one triangle fewer: an open mesh, other counts
  const ReverseUpdate u = e.update();
  EXPECT_FALSE(u.refitted);
  EXPECT_NE(u.reason.find("counts changed"), std::string::npos) << u.reason;
  const ReverseEstimator fresh(scene, ReverseConfig{shapes, Method::Quadric, 1});
  const std::vector<double> w = random_adjoint(scene, 7);
  RenderOptions opt;
  opt.seed = 4;
  opt.progress = false;
  const ReverseResult a = e.run(w, opt), b = fresh.run(w, opt);
  EXPECT_EQ(a.image, b.image);
  ASSERT_EQ(a.gradient[0].size(), b.gradient[0].size());
  for (size_t v = 0; v < a.gradient[0].size(); ++v) ASSERT_EQ(a.gradient[0][v], b.gradient[0][v]) << "vertex " << v;
}

TEST(ReverseMode, BadInputGetsAOneLineError) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/spot-selfshadow.xml"),
                                 {{"res", "8"}, {"spp", "1"}});
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([&] { resolve_shapes(scene, {"cow"}); }).rfind("--shape 'cow': no shape with this id in ", 0), 0u);
  EXPECT_EQ(message([&] { resolve_shapes(scene, {"spot", "spot"}); }), "--shape 'spot': given twice");
  EXPECT_EQ(message([&] { ReverseEstimator(scene, ReverseConfig{{7}, Method::None, 1}); }),
            "reverse mode: shape index 7 out of range (the scene has 2 shapes)");
  EXPECT_EQ(message([&] { ReverseEstimator(scene, ReverseConfig{{}, Method::None, 1}); }),
            "reverse mode: no shape to differentiate");
  const ReverseEstimator reverse(scene, ReverseConfig{{0}, Method::None, 1});
  RenderOptions opt;
  opt.progress = false;
  EXPECT_EQ(message([&] { reverse.run(std::vector<double>(10, 0.0), opt); }),
            "adjoint image: expected 8 x 8 x 3 = 192 values (got 10)");
  std::vector<double> w(192, 0.0);
  w[3 * (8 * 2 + 5) + 1] = std::nan("");
  EXPECT_EQ(message([&] { reverse.run(w, opt); }), "adjoint image: non-finite weight at pixel (5, 2)");
}

}  // namespace
}  // namespace qsil
