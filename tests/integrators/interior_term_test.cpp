// Interior term (forward mode over geometry parameters, docs/architecture.md §4): the
// differentiable pieces against central differences of the same function in double, the
// detachment of sampled quantities, and exact zeros for unmoving geometry.
#include "qsil/bsdf.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/integrators/surface_interaction.h"
#include "qsil/parameters.h"
#include "qsil/ray_tracer.h"
#include "integrators/light_setup.h"
#include "test_data.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <random>
#include <type_traits>

namespace qsil {
namespace {

/// A scene holding one triangle (or the given mesh) with a diffuse BSDF.
Scene one_shape_scene(const TriangleMesh& mesh) {
  Scene s;
  s.bsdfs.push_back(BSDFDesc{});
  Shape sh;
  sh.id = "tri";
  sh.type = "obj";
  sh.mesh = mesh;
  sh.bsdf = 0;
  s.shapes.push_back(sh);
  return s;
}

/// Central difference of f at 0 with step h (double precision; f smooth).
/// Evaluated into the value type of f (an Eigen expression would dangle).
template <class F>
auto central(F&& f, double h) {
  const auto a = f(h), b = f(-h);
  decltype(f(h)) r = (a - b) / (2 * h);
  return r;
}

}  // namespace

// The hit point, distance, barycentrics and both normals of a fixed-direction ray from a moving
// origin on a moving triangle, in forward mode, equal central differences of the same
// computation in double (step 1e-6, relative tolerance 1e-6 of the scale of each quantity).
TEST(InteriorTerm, DifferentiableHitMatchesCentralDifferences) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    TriangleMesh mesh = test::icosphere(1);
    for (auto& p : mesh.positions) p += 0.05 * Vec3(U(rng), U(rng), U(rng));  // irregular normals
    mesh.normals = vertex_normals(mesh);
    Scene scene = one_shape_scene(mesh);
    const std::vector<std::string> specs = {"tri:rotate:0.3,1,0.2", "tri:vertex:0:1,-2,0.5", "tri:scale",
                                            "tri:translate:0,0,1"};
    std::vector<ParameterSpec> params;
    for (const auto& s : specs) params.push_back(parse_parameter(s, scene));
    const SceneVelocities vel = compute_velocities(scene, params);
    const DualView<4> view{&scene, &vel};
    // A ray from outside toward a random point on triangle 0's neighbourhood of vertex 0.
    const int tri = int(rng() % mesh.triangles.size());
    const auto& t = mesh.triangles[tri];
    const Vec3 target = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
    const Vec3 o = target + 3.0 * Vec3(U(rng), U(rng), 2.0).normalized();
    const Vec3 d = (target - o).normalized();
    const Vec3 o_vel(0.2, -0.1, 0.4);  // the origin moves too (an earlier path vertex moved)
    Hit hit;
    hit.shape = 0;
    hit.triangle = tri;
    Vec3T<Dual<4>> oD;
    for (int i = 0; i < 3; ++i) oD[i] = Dual<4>(o[i], Eigen::Vector4d(0, 0, 0, o_vel[i]));
    const auto si = make_interaction(view, hit, oD, d);
    for (int k = 0; k < 4; ++k) {
      auto at = [&](double h) {
        Scene moved = displaced_scene(scene, params, k, h);
        const PrimalView pv{&moved};
        const Vec3 oh = k == 3 ? Vec3(o + h * o_vel) : o;  // parameter 3 also moves the origin
        const auto s = make_interaction(pv, hit, oh, d);
        Eigen::Matrix<double, 12, 1> out;
        out << s.p, s.ng, s.ns, s.t, s.b1, s.b2;
        return out;
      };
      const Eigen::Matrix<double, 12, 1> fd = central(at, 1e-6);
      Eigen::Matrix<double, 12, 1> ad;
      for (int i = 0; i < 3; ++i) {
        ad[i] = si.p[i].derivatives()[k];
        ad[3 + i] = si.ng[i].derivatives()[k];
        ad[6 + i] = si.ns[i].derivatives()[k];
      }
      ad[9] = si.t.derivatives()[k];
      ad[10] = si.b1.derivatives()[k];
      ad[11] = si.b2.derivatives()[k];
      EXPECT_LT((ad - fd).norm(), 1e-6 * (1 + fd.norm()))
          << "param " << specs[k] << "\nad " << ad.transpose() << "\nfd " << fd.transpose();
    }
  }
}

// make_interaction works in doubles at a constant hit (DualView::constant_hit: a shape that does
// not move, an origin without derivatives). A hit on that unmoving shape from a moving origin (an
// earlier vertex moved) still carries the origin's motion along the fixed direction (central
// differences, as above); from a fixed origin it is the primal interaction exactly, with zero
// derivatives, and its shading frame (made in doubles) is the dual computation's up to rounding.
TEST(InteriorTerm, AHitOnUnmovingGeometryMovesWithItsOriginOnly) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> U(-1, 1);
  TriangleMesh mesh = test::icosphere(1);
  mesh.normals = vertex_normals(mesh);
  Scene scene = one_shape_scene(mesh);
  Shape other = scene.shapes[0];
  other.id = "other";
  for (auto& p : other.mesh.positions) p += Vec3(5, 0, 0);
  scene.shapes.push_back(other);
  const std::vector<ParameterSpec> params = {parse_parameter("other:translate:0,1,0", scene)};
  const SceneVelocities vel = compute_velocities(scene, params);
  ASSERT_FALSE(vel.moving[0]);
  const DualView<1> view{&scene, &vel};
  const PrimalView pv{&scene};
  for (int trial = 0; trial < 10; ++trial) {
    const int tri = int(rng() % mesh.triangles.size());
    const auto& t = mesh.triangles[size_t(tri)];
    const Vec3 target = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
    const Vec3 o = target + 3.0 * Vec3(U(rng), U(rng), 2.0).normalized();
    const Vec3 d = (target - o).normalized();
    Hit hit;
    hit.shape = 0;
    hit.triangle = tri;
    const Vec3 o_vel(U(rng), U(rng), U(rng));
    Vec3T<Dual<1>> oD;
    for (int i = 0; i < 3; ++i) oD[i] = Dual<1>(o[i], Eigen::Matrix<double, 1, 1>(o_vel[i]));
    const auto si = make_interaction(view, hit, oD, d);
    const auto at = [&](double h) { return Vec3(make_interaction(pv, hit, Vec3(o + h * o_vel), d).p); };
    const Vec3 fd = central(at, 1e-6);
    Vec3 ad;
    for (int i = 0; i < 3; ++i) ad[i] = si.p[i].derivatives()[0];
    EXPECT_GT(fd.norm(), 0.1);
    EXPECT_LT((ad - fd).norm(), 1e-6 * (1 + fd.norm())) << "ad " << ad.transpose() << "\nfd " << fd.transpose();

    const auto fixed = make_interaction(view, hit, lift<Dual<1>>(o), d);
    const auto primal = make_interaction(pv, hit, o, d);
    EXPECT_EQ(value(fixed.p), primal.p);
    EXPECT_EQ(value(fixed.ns), primal.ns);
    EXPECT_EQ(value(fixed.t), primal.t);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(fixed.p[i].derivatives()[0], 0.0);
      EXPECT_EQ(fixed.ng[i].derivatives()[0], 0.0);
      EXPECT_EQ(fixed.ns[i].derivatives()[0], 0.0);
    }
    // Its shading frame, made in doubles (fixed.constant), is the dual computation's, seen from
    // the ray's viewer and from a grazing one (the shading-normal adaptation bends it).
    ASSERT_TRUE(fixed.constant);
    auto as_dual = fixed;
    as_dual.constant = false;
    PathContext ctx;
    ctx.scene = &scene;
    const Vec3 ng = value(fixed.ng);
    for (const Vec3& wo : {Vec3(-d), Vec3((ng.unitOrthogonal() + 1e-4 * ng).normalized())}) {
      const auto a = make_shading_point(ctx, fixed, wo), b = make_shading_point(ctx, as_dual, wo);
      // Equal up to rounding: Eigen sums a double vector's squared norm in SIMD order.
      EXPECT_LT((value(a.frame.n) - value(b.frame.n)).norm(), 1e-14);
      EXPECT_LT((value(a.frame.s) - value(b.frame.s)).norm(), 1e-14);
      EXPECT_LT((value(a.frame.t) - value(b.frame.t)).norm(), 1e-14);
      EXPECT_LT((a.frame_value.n - b.frame_value.n).norm(), 1e-14);
      for (int i = 0; i < 3; ++i) EXPECT_EQ(a.frame.n[i].derivatives()[0], 0.0);
    }
  }
}

namespace {

/// DualView<N> without constant_hit: make_interaction and trace_path take the all-dual path.
template <int N>
struct AllDualView {
  using Real = Dual<N>;
  const Scene* scene;
  DualView<N> view;
  Vec3T<Real> position(int shape, int v) const { return view.position(shape, v); }
  Vec3T<Real> normal(int shape, int v) const { return view.normal(shape, v); }
  bool moving(int shape) const { return view.moving(shape); }
};

}  // namespace

// Whole paths on spot-mirror (Spot moving; the mirror, a GGX conductor, and the floor not): the
// radiance and its derivatives of trace_path with the constant-interaction shortcuts (frames and
// BSDF values in doubles at hits with zero derivatives) equal the all-dual computation's, path by
// path with the same random numbers, up to rounding.
TEST(InteriorTerm, ConstantInteractionsChangeNoPath) {
  Scene scene = load_scene(test::data_file("scenes/spot-mirror.xml"), {{"res", "16"}});
  const auto params = parse_parameters({"spot:translate:0,1,0", "spot:rotate:0,0,1"}, scene);
  const SceneVelocities vel = compute_velocities(scene, params);
  const RayTracer tracer(scene);
  const LightSetup lights(scene);
  const PathContext ctx = lights.context(scene, tracer);
  const DualView<2> fast{&scene, &vel};
  const AllDualView<2> slow{&scene, fast};
  const Camera& cam = scene.camera;
  int constant_hits = 0, with_derivative = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      for (int s = 0; s < 4; ++s) {
        const uint64_t pixel = uint64_t(y) * uint64_t(cam.width) + uint64_t(x);
        Sampler sa(3, pixel, uint64_t(s)), sb(3, pixel, uint64_t(s));
        const Vec2 u = sa.next2();
        sb.next2();
        const Vec3 d = cam.direction(x + u.x(), y + u.y());
        const Hit hit = tracer.intersect(cam.origin(), d);
        if (hit.valid() && !vel.moving[size_t(hit.shape)]) ++constant_hits;
        PathStats st;
        const auto a = trace_path(ctx, fast, {lift<Dual<2>>(cam.origin()), d, hit}, sa, st);
        const auto b = trace_path(ctx, slow, {lift<Dual<2>>(cam.origin()), d, hit}, sb, st);
        for (int c = 0; c < 3; ++c) {
          const double scale = 1e-12 * (1.0 + std::abs(b[c].value()) + b[c].derivatives().norm());
          EXPECT_NEAR(a[c].value(), b[c].value(), scale) << "pixel " << x << "," << y;
          EXPECT_LT((a[c].derivatives() - b[c].derivatives()).norm(), scale) << "pixel " << x << "," << y;
          with_derivative += b[c].derivatives().norm() > 0;
        }
      }
  // Both kinds of path occur: camera rays that meet the mirror or the floor, and derivatives.
  EXPECT_GT(constant_hits, 100);
  EXPECT_GT(with_derivative, 100);
}

// GGX and diffuse cosine-weighted values and the cosine, as functions of a moving shading normal
// with fixed world directions, against central differences (double, step 1e-6).
TEST(InteriorTerm, BSDFValuesAndCosinesUnderAMovingFrameMatchCentralDifferences) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-1, 1);
  for (double alpha : {0.05, 0.1, 0.4}) {
    for (int trial = 0; trial < 20; ++trial) {
      BSDFDesc b;
      b.type = trial % 2 ? BSDFDesc::Type::RoughConductor : BSDFDesc::Type::Diffuse;
      b.alpha = alpha;
      b.reflectance = Color(0.3, 0.6, 0.9);
      const Vec3 n0 = Vec3(0.1 * U(rng), 0.1 * U(rng), 1).normalized();
      const Vec3 dn(U(rng), U(rng), U(rng));
      const Vec3 wi = Vec3(U(rng), U(rng), 0.6 + 0.4 * std::abs(U(rng))).normalized();
      const Vec3 wo = Vec3(U(rng), U(rng), 0.6 + 0.4 * std::abs(U(rng))).normalized();
      auto value_at = [&](double h) {
        const Frame f(Vec3(n0 + h * dn).normalized());
        const Color c = bsdf_eval<double>(b, f.to_local(wi), f.to_local(wo));
        return Eigen::Vector4d(c[0], c[1], c[2], f.to_local(wi).z());
      };
      Vec3T<Dual<1>> nD;
      for (int i = 0; i < 3; ++i) nD[i] = Dual<1>(n0[i], Eigen::Matrix<double, 1, 1>(dn[i]));
      using std::sqrt;
      nD = nD / sqrt(nD.squaredNorm());
      const FrameT<Dual<1>> fD(nD);
      const Vec3T<Dual<1>> wiL = fD.to_local(lift<Dual<1>>(wi)), woL = fD.to_local(lift<Dual<1>>(wo));
      const ColorT<Dual<1>> cD = bsdf_eval<Dual<1>>(b, wiL, woL);
      const Eigen::Vector4d ad(cD[0].derivatives()[0], cD[1].derivatives()[0], cD[2].derivatives()[0],
                               wiL.z().derivatives()[0]);
      const Eigen::Vector4d fd = central(value_at, 1e-6);
      EXPECT_LT((ad - fd).norm(), 1e-5 * (1 + fd.norm())) << "alpha " << alpha << " type " << int(b.type);
    }
  }
}

// Detachment is structural: sampled directions, pdfs and MIS weights are doubles whatever the
// scalar type of the geometry, so they cannot carry a derivative (docs/architecture.md §4).
TEST(InteriorTerm, SampledDirectionsPdfsAndMisWeightsAreDetachedTypes) {
  static_assert(std::is_same_v<decltype(BSDFSample::wi), Vec3>);
  static_assert(std::is_same_v<decltype(BSDFSample::pdf), double>);
  static_assert(std::is_same_v<decltype(EnvironmentLight::Sample::dir), Vec3>);
  static_assert(std::is_same_v<decltype(AreaLights::Sample::pdf_area), double>);
  static_assert(std::is_same_v<decltype(power_heuristic(1.0, 1.0)), double>);
  static_assert(std::is_same_v<decltype(ShadingPoint<Dual<2>>::frame_value), Frame>);
  // ...and the value of a dual computation equals the double computation to rounding (1e-9
  // relative), so the sampling decisions taken from detached values are the primal's decisions.
  // A rough conductor: diffuse directions of derivative-carrying paths come from another density
  // (kDerivativeDiffuseUniformShare, bsdf.h), so there the decisions differ by design.
  Scene scene = test::furnace_scene(0.8, 1.0, 8, 4);
  scene.bsdfs[0].type = BSDFDesc::Type::RoughConductor;
  scene.bsdfs[0].alpha = 0.3;
  scene.bsdfs[0].specular_reflectance = Color::Constant(0.8);
  const auto params = std::vector<ParameterSpec>{parse_parameter("sphere:translate:0,1,0", scene)};
  RenderOptions o;
  o.progress = false;
  o.seed = 4;
  const RenderResult g = Estimator(scene, EstimatorConfig::gradient(params)).run(o);
  const RenderResult p = Estimator(scene, EstimatorConfig::primal()).run(o);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(g.film.mean(c, x, y), p.film.mean(c, x, y), 1e-9 * p.film.mean(c, x, y));
  // With a diffuse BSDF the dual paths draw from the mixture and the primal paths from the cosine
  // density: the same seed gives different images (were both on one density, every pixel would
  // agree to rounding as above).
  const Scene diffuse_scene = test::furnace_scene(0.8, 1.0, 8, 4);
  const RenderResult gd = Estimator(diffuse_scene, EstimatorConfig::gradient(params)).run(o);
  const RenderResult pd = Estimator(diffuse_scene, EstimatorConfig::primal()).run(o);
  int differ = 0;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) differ += std::abs(gd.film.mean(1, x, y) - pd.film.mean(1, x, y)) > 1e-6;
  EXPECT_GT(differ, 0);
}

// An unmoving scene has exactly zero interior term: a shape that moves but is never hit by any
// path contributes exactly 0.0 to every derivative channel of every pixel (no spurious derivative
// from detached quantities). Its silhouette, seen from the sphere, does move: that is the
// boundary term's business, so it is off here.
TEST(InteriorTerm, UnmovingSceneHasExactlyZeroDerivative) {
  Scene scene = test::furnace_scene(0.8, 1.0, 8, 4);
  // A second shape that moves but is never seen nor hit: far behind the camera, facing away.
  Shape far;
  far.id = "far";
  far.type = "obj";
  far.mesh = test::icosphere(0, Vec3(0, 0, 500), 0.1);
  far.bsdf = 0;
  scene.shapes.push_back(far);
  scene.environment.type = Environment::Type::Constant;
  const auto params = std::vector<ParameterSpec>{parse_parameter("far:translate:1,0,0", scene)};
  RenderOptions o;
  o.progress = false;
  const RenderResult g = Estimator(scene, EstimatorConfig::gradient(params, Method::None)).run(o);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      for (int c = 3; c < 6; ++c) EXPECT_EQ(g.film.mean(c, x, y), 0.0);
}

}  // namespace qsil
