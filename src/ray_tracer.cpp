/// @file ray_tracer.cpp
/// Embree 3 wrapper: the only file that includes Embree (docs/architecture.md §1).

#include "qsil/ray_tracer.h"

#include "qsil/check.h"
#include "qsil/error.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <tuple>
#include <utility>

namespace qsil {

namespace {
/// Intersection context extended with what to ignore (Embree 3 context filter).
struct FilterContext {
  RTCIntersectContext context;
  const IgnoreSet* ignore;
  const std::vector<char>* one_sided;  ///< per geometry: its BSDF is not twosided
};

void ignore_filter(const RTCFilterFunctionNArguments* args) {
  const auto* ctx = reinterpret_cast<const FilterContext*>(args->context);
  if (!ctx->ignore || ctx->ignore->empty()) return;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned geom = RTCHitN_geomID(args->hit, args->N, i);
    const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
    if (ctx->ignore->contains(int(geom), int(prim))) {
      args->valid[i] = 0;
      continue;
    }
    if (ctx->ignore->through_back_faces && (*ctx->one_sided)[geom]) {
      // Embree's Ng is (v1 - v0) x (v2 - v0): the counter-clockwise, outward normal (tested).
      const float d = RTCHitN_Ng_x(args->hit, args->N, i) * RTCRayN_dir_x(args->ray, args->N, i) +
                      RTCHitN_Ng_y(args->hit, args->N, i) * RTCRayN_dir_y(args->ray, args->N, i) +
                      RTCHitN_Ng_z(args->hit, args->N, i) * RTCRayN_dir_z(args->ray, args->N, i);
      if (d > 0) args->valid[i] = 0;  // the ray meets the back side
    }
  }
}

void embree_error(void*, RTCError code, const char* str) {
  (void)code;
  (void)str;  // Errors are checked where they matter (device creation, commit).
}

/// Invalid rays refused by every tracer of the process.
std::atomic<uint64_t> g_invalid_rays{0};
}  // namespace

bool ray_is_valid(const Vec3& origin, const Vec3& dir, double tmax) {
  if (!origin.allFinite() || !dir.allFinite() || std::isnan(tmax)) return false;
  if (origin.cwiseAbs().maxCoeff() > kEmbreeLargestRayComponent) return false;
  if (dir.cwiseAbs().maxCoeff() > kEmbreeLargestRayComponent) return false;
  // The direction Embree sees is the float one: it must not round to zero.
  const bool nonzero = float(dir.x()) != 0.0f || float(dir.y()) != 0.0f || float(dir.z()) != 0.0f;
  return nonzero;
}

struct RayTracer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  mutable std::atomic<uint64_t> invalid_rays{0};
  /// Counts a refused ray (here and process-wide).
  void refuse() const {
    invalid_rays.fetch_add(1, std::memory_order_relaxed);
    g_invalid_rays.fetch_add(1, std::memory_order_relaxed);
  }
  std::vector<char> one_sided;       ///< per geometry (= shape index)
  /// Per geometry: vertex and triangle counts as built (update_meshes keeps them).
  std::vector<std::pair<size_t, size_t>> counts;
  Vec3 local_origin = Vec3::Zero();  ///< Embree's coordinates are world coordinates minus this
};

Vec3 embree_local_origin(const Scene& scene) {
  const Box3 b = scene.bounds();
  if (b.empty() || !b.lo.allFinite() || !b.hi.allFinite()) return Vec3::Zero();
  const Vec3 centre = b.center();
  const double diag = b.diagonal();
  if (!(diag > 0)) return centre;
  int e = 0;
  std::frexp(diag, &e);  // diag = m 2^e, m in [0.5, 1): 2^e is a power of two >= diag
  const double q = std::ldexp(1.0, e);
  Vec3 c;
  for (int k = 0; k < 3; ++k) c[k] = q * std::nearbyint(centre[k] / q);
  return c;
}

RayTracer::RayTracer(const Scene& scene) : RayTracer(scene, embree_local_origin(scene)) {}

RayTracer::RayTracer(const Scene& scene, const Vec3& local_origin) : impl_(std::make_unique<Impl>()) {
  Impl& impl = *impl_;
  impl.local_origin = local_origin;
  impl.device = rtcNewDevice(nullptr);
  if (!impl.device) throw Error("Embree: cannot create device");
  rtcSetDeviceErrorFunction(impl.device, embree_error, nullptr);
  impl.scene = rtcNewScene(impl.device);
  rtcSetSceneFlags(impl.scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
  rtcSetSceneBuildQuality(impl.scene, RTC_BUILD_QUALITY_HIGH);
  impl.one_sided.assign(scene.shapes.size(), 1);
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const int b = scene.shapes[s].bsdf;
    if (b >= 0 && b < int(scene.bsdfs.size()) && scene.bsdfs[size_t(b)].twosided) impl.one_sided[s] = 0;
    const TriangleMesh& mesh = scene.shapes[s].mesh;
    const auto& pos = mesh.positions;
    RTCGeometry geom = rtcNewGeometry(impl.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), pos.size()));
    for (size_t i = 0; i < pos.size(); ++i)
      for (int k = 0; k < 3; ++k) vb[3 * i + k] = float(pos[i][k] - local_origin[k]);
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(unsigned), mesh.triangles.size()));
    for (size_t f = 0; f < mesh.triangles.size(); ++f)
      for (int k = 0; k < 3; ++k) ib[3 * f + k] = unsigned(mesh.triangles[f][k]);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(impl.scene, geom, unsigned(s));
    rtcReleaseGeometry(geom);
    impl.counts.emplace_back(pos.size(), mesh.triangles.size());
  }
  rtcCommitScene(impl.scene);
  if (rtcGetDeviceError(impl.device) != RTC_ERROR_NONE) throw Error("Embree: scene build failed");
}

bool RayTracer::update_meshes(const Scene& scene) {
  Impl& impl = *impl_;
  if (scene.shapes.size() != impl.counts.size()) return false;
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const TriangleMesh& mesh = scene.shapes[s].mesh;
    if (mesh.positions.size() != impl.counts[s].first || mesh.triangles.size() != impl.counts[s].second)
      return false;
  }
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    RTCGeometry geom = rtcGetGeometry(impl.scene, unsigned(s));
    auto* vb = static_cast<float*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_VERTEX, 0));
    const auto& pos = scene.shapes[s].mesh.positions;
    for (size_t i = 0; i < pos.size(); ++i)
      for (int k = 0; k < 3; ++k) vb[3 * i + k] = float(pos[i][k] - impl.local_origin[k]);
    rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
    auto* ib = static_cast<unsigned*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_INDEX, 0));
    const auto& tri = scene.shapes[s].mesh.triangles;
    for (size_t f = 0; f < tri.size(); ++f)
      for (int k = 0; k < 3; ++k) ib[3 * f + k] = unsigned(tri[f][k]);
    rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0);
    rtcCommitGeometry(geom);
  }
  rtcCommitScene(impl.scene);
  if (rtcGetDeviceError(impl.device) != RTC_ERROR_NONE) throw Error("Embree: scene update failed");
  return true;
}

RayTracer::~RayTracer() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

uint64_t RayTracer::invalid_rays() const { return impl_->invalid_rays.load(std::memory_order_relaxed); }

uint64_t RayTracer::total_invalid_rays() { return g_invalid_rays.load(std::memory_order_relaxed); }

const Vec3& RayTracer::local_origin() const { return impl_->local_origin; }

namespace {
/// The Embree ray of a ray that passed ray_is_valid (checked again in debug builds: Embree aborts
/// on invalid rays).
void embree_ray(const Vec3& origin, const Vec3& dir, double tmax, RTCRay& ray) {
  QSIL_DCHECK_MSG(ray_is_valid(origin, dir, tmax), "ray " << origin.transpose() << " -> " << dir.transpose());
  ray.org_x = float(origin.x());
  ray.org_y = float(origin.y());
  ray.org_z = float(origin.z());
  ray.dir_x = float(dir.x());
  ray.dir_y = float(dir.y());
  ray.dir_z = float(dir.z());
  ray.tnear = 0.0f;
  ray.tfar = std::isfinite(tmax) ? float(tmax) : std::numeric_limits<float>::infinity();
  ray.mask = 0xFFFFFFFFu;
  ray.flags = 0;
  ray.time = 0.0f;
}

/// The intersection context that filters what `ignore` names (no filter when it names nothing).
void filter_context(const IgnoreSet& ignore, const std::vector<char>& one_sided, FilterContext& ctx) {
  rtcInitIntersectContext(&ctx.context);
  ctx.context.filter = ignore.empty() ? nullptr : ignore_filter;
  ctx.ignore = &ignore;
  ctx.one_sided = &one_sided;
}
}  // namespace

Hit RayTracer::intersect(const Vec3& world_origin, const Vec3& dir, double tmax, const IgnoreSet& ignore) const {
  const Vec3 origin = world_origin - impl_->local_origin;  // Embree's coordinates
  if (!ray_is_valid(origin, dir, tmax)) {
    impl_->refuse();
    return Hit{};
  }
  FilterContext ctx;
  filter_context(ignore, impl_->one_sided, ctx);
  RTCRayHit rh;
  embree_ray(origin, dir, tmax, rh.ray);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &ctx.context, &rh);
  Hit hit;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.shape = int(rh.hit.geomID);
  hit.triangle = int(rh.hit.primID);
  hit.t = rh.ray.tfar;
  hit.u = rh.hit.u;
  hit.v = rh.hit.v;
  return hit;
}

bool RayTracer::occluded(const Vec3& world_origin, const Vec3& dir, double tmax, const IgnoreSet& ignore) const {
  const Vec3 origin = world_origin - impl_->local_origin;  // Embree's coordinates
  if (!ray_is_valid(origin, dir, tmax)) {
    impl_->refuse();
    return false;
  }
  FilterContext ctx;
  filter_context(ignore, impl_->one_sided, ctx);
  RTCRay ray;
  embree_ray(origin, dir, tmax, ray);
  rtcOccluded1(impl_->scene, &ctx.context, &ray);
  return ray.tfar < 0.0f;  // Embree sets tfar = -inf on a hit
}

Vec3 offset_ray_origin(const Vec3& p, const Vec3& ng, const Vec3& dir, double scale, const Vec3& local_origin) {
  const double len = ng.norm();
  if (!(len > 0)) return p;
  const double d = kRayOffsetRelative * std::max(scale, (p - local_origin).cwiseAbs().maxCoeff());
  const Vec3 n = ng / len;
  return n.dot(dir) >= 0 ? Vec3(p + d * n) : Vec3(p - d * n);
}

}  // namespace qsil

namespace qsil {

namespace {

/// One mesh of the broad phase: its triangles' boxes (double) and the centre Embree's float boxes are
/// taken around (collide_bounds rounds them outward).
struct CollideMesh {
  std::vector<Box3> boxes;  ///< per triangle, world frame, double
  double grow = 0.0;        ///< half the gap: Embree's boxes are grown by it on every side
  Vec3 centre = Vec3::Zero();
};

/// Writes into `out` a float box that contains the double box [l, h]: each bound rounded outward
/// by one float step beyond its float conversion (conservative for a user geometry's bounds).
void store_outward_bounds(const Vec3& l, const Vec3& h, RTCBounds* out) {
  auto lo = [](double x) { return std::nextafter(float(x), -std::numeric_limits<float>::infinity()); };
  auto hi = [](double x) { return std::nextafter(float(x), std::numeric_limits<float>::infinity()); };
  out->lower_x = lo(l.x());
  out->lower_y = lo(l.y());
  out->lower_z = lo(l.z());
  out->upper_x = hi(h.x());
  out->upper_y = hi(h.y());
  out->upper_z = hi(h.z());
}

void collide_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* m = static_cast<const CollideMesh*>(args->geometryUserPtr);
  const Box3& b = m->boxes[args->primID];
  const bool finite = b.lo.allFinite() && b.hi.allFinite() && !b.empty();
  const Vec3 l = finite ? Vec3(b.lo.array() - m->grow - m->centre.array()) : Vec3::Zero();
  const Vec3 h = finite ? Vec3(b.hi.array() + m->grow - m->centre.array()) : Vec3::Zero();
  store_outward_bounds(l, h, args->bounds_o);
}

struct CollideState {
  const std::vector<CollideMesh>* meshes = nullptr;
  double gap = 0.0;
  const std::function<void(const TrianglePair&)>* visit = nullptr;
};

/// Embree's callback (called from its worker threads, often with one pair): the canonical order
/// of each reported pair, the exact box test, then the visitor.
void collide_callback(void* user, RTCCollision* collisions, unsigned int count) {
  const auto* state = static_cast<const CollideState*>(user);
  const auto& meshes = *state->meshes;
  for (unsigned i = 0; i < count; ++i) {
    const TrianglePair p{int(collisions[i].geomID0), int(collisions[i].primID0), int(collisions[i].geomID1),
                         int(collisions[i].primID1)};
    if (!(std::pair(p.mesh0, p.triangle0) < std::pair(p.mesh1, p.triangle1))) continue;  // the other order, or itself
    const Box3& a = meshes[size_t(p.mesh0)].boxes[size_t(p.triangle0)];
    const Box3& b = meshes[size_t(p.mesh1)].boxes[size_t(p.triangle1)];
    if (a.within(b, state->gap)) (*state->visit)(p);
  }
}

}  // namespace

void for_each_overlapping_triangle_pair(std::span<const TriangleMesh* const> meshes,
                                        const std::function<void(const TrianglePair&)>& visit, double* build_seconds,
                                        double gap) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!(gap >= 0.0) || !std::isfinite(gap))
    throw Error("overlapping triangle pairs: gap " + std::to_string(gap) + " is not a finite non-negative length");
  if (build_seconds) *build_seconds = 0;
  std::vector<CollideMesh> cm(meshes.size());
  Box3 all;
  size_t triangles = 0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    const TriangleMesh& mesh = *meshes[i];
    cm[i].boxes.resize(mesh.triangles.size());
    for (size_t f = 0; f < mesh.triangles.size(); ++f) {
      const Box3& b = cm[i].boxes[f] = mesh.triangle_bounds(int(f));
      if (b.lo.allFinite() && b.hi.allFinite()) all.expand(b);
    }
    triangles += mesh.triangles.size();
  }
  if (triangles < 2) return;
  const Vec3 centre = all.empty() ? Vec3::Zero() : all.center();
  // Two boxes within `gap` overlap once each is grown by half of it; 2^-40 of the largest
  // coordinate (that of `all`, the finite boxes' union) more covers the rounding of the grown
  // bounds in double (a few 2^-53 of it), so that Embree's float boxes (outward) report every
  // such pair. gap 0: the boxes themselves.
  const double grow = gap > 0.0 ? 0.5 * gap + std::ldexp(all.max_abs(), -40) : 0.0;
  for (CollideMesh& m : cm) {
    m.centre = centre;
    m.grow = grow;
  }
  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) throw Error("Embree: cannot create device");
  rtcSetDeviceErrorFunction(device, embree_error, nullptr);
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
  for (size_t i = 0; i < cm.size(); ++i) {
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geom, unsigned(cm[i].boxes.size()));
    rtcSetGeometryUserData(geom, &cm[i]);
    rtcSetGeometryBoundsFunction(geom, collide_bounds, nullptr);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene, geom, unsigned(i));
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(scene);
  if (build_seconds) *build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CollideState state;
  state.meshes = &cm;
  state.gap = gap;
  state.visit = &visit;
  rtcCollide(scene, scene, collide_callback, &state);
  const bool failed = rtcGetDeviceError(device) != RTC_ERROR_NONE;
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  if (failed) throw Error("Embree: collision query failed");
}

std::vector<TrianglePair> overlapping_triangle_pairs(std::span<const TriangleMesh* const> meshes, double gap) {
  std::mutex lock;
  std::vector<TrianglePair> pairs;
  for_each_overlapping_triangle_pair(
      meshes,
      [&](const TrianglePair& p) {
        std::lock_guard<std::mutex> guard(lock);
        pairs.push_back(p);
      },
      nullptr, gap);
  std::sort(pairs.begin(), pairs.end(), [](const TrianglePair& a, const TrianglePair& b) {
    return std::tie(a.mesh0, a.triangle0, a.mesh1, a.triangle1) < std::tie(b.mesh0, b.triangle0, b.mesh1, b.triangle1);
  });
  return pairs;
}

}  // namespace qsil

namespace qsil {

namespace {

/// One shape's grown triangle boxes, relative to the query's local origin (double), and the pad
/// of Embree's float boxes around them.
struct NearShape {
  std::vector<Box3> boxes;
  double pad = 0;
};

void near_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* m = static_cast<const NearShape*>(args->geometryUserPtr);
  const Box3& b = m->boxes[args->primID];
  RTCBounds* out = args->bounds_o;
  if (b.lo.allFinite() && b.hi.allFinite() && !b.empty()) {
    store_outward_bounds(b.lo.array() - m->pad, b.hi.array() + m->pad, out);
    return;
  }
  // An empty box for a non-finite triangle.
  out->lower_x = out->lower_y = out->lower_z = 0.0f;
  out->upper_x = out->upper_y = out->upper_z = -1.0f;
}

/// The query's ray in double and its visitor, behind Embree's context.
struct NearContext {
  RTCIntersectContext context;
  Vec3 origin, dir;
  double tmax;
  void (*visit)(void*, int, int);
  void* user;
};

/// Whether origin + t dir, t in [0, tmax], meets box b (slab test in double).
bool segment_meets_box(const Vec3& o, const Vec3& d, double tmax, const Box3& b) {
  if (b.empty()) return false;
  double t0 = 0, t1 = tmax;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (o[k] < b.lo[k] || o[k] > b.hi[k]) return false;
      continue;
    }
    double ta = (b.lo[k] - o[k]) / d[k], tb = (b.hi[k] - o[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

/// Embree's callback for a primitive of a leaf the ray reaches: the exact box test, then the
/// visitor. It never reports a hit, so Embree goes on along the whole ray.
void near_intersect(const RTCIntersectFunctionNArguments* args) {
  if (args->N != 1 || args->valid[0] != -1) return;
  const auto* m = static_cast<const NearShape*>(args->geometryUserPtr);
  const auto* ctx = reinterpret_cast<const NearContext*>(args->context);
  if (segment_meets_box(ctx->origin, ctx->dir, ctx->tmax, m->boxes[args->primID]))
    ctx->visit(ctx->user, int(args->geomID), int(args->primID));
}

}  // namespace

struct NearTriangleQuery::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<NearShape> shapes;
  Vec3 local_origin = Vec3::Zero();
  double reach = 0;
};

NearTriangleQuery::NearTriangleQuery(const Scene& scene, double reach) : impl_(std::make_unique<Impl>()) {
  if (!(reach >= 0) || !std::isfinite(reach))
    throw Error("near-triangle query: reach must be >= 0 and finite (got " + std::to_string(reach) + ")");
  Impl& impl = *impl_;
  impl.reach = reach;
  impl.local_origin = embree_local_origin(scene);
  impl.device = rtcNewDevice(nullptr);
  if (!impl.device) throw Error("Embree: cannot create device");
  rtcSetDeviceErrorFunction(impl.device, embree_error, nullptr);
  impl.scene = rtcNewScene(impl.device);
  rtcSetSceneFlags(impl.scene, RTC_SCENE_FLAG_ROBUST);
  impl.shapes.resize(scene.shapes.size());
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const TriangleMesh& mesh = scene.shapes[s].mesh;
    NearShape& ns = impl.shapes[s];
    ns.boxes.resize(mesh.triangles.size());
    for (size_t f = 0; f < mesh.triangles.size(); ++f) {
      Box3& b = ns.boxes[f];
      for (int k = 0; k < 3; ++k) b.expand(Vec3(mesh.positions[size_t(mesh.triangles[f][k])] - impl.local_origin));
      b.lo.array() -= reach;
      b.hi.array() += reach;
    }
  }
  // Embree traverses a float ray through float boxes; the exact test is on the double ray. The
  // float boxes are padded by 2^-12 of the scene's largest grown coordinate, which covers the
  // rounding of rays from up to ~1000 scene sizes away (a pad costs time, never a candidate).
  Box3 all;
  for (const NearShape& ns : impl.shapes)
    for (const Box3& b : ns.boxes)
      if (b.lo.allFinite() && b.hi.allFinite()) all.expand(b);
  const double pad = std::ldexp(all.max_abs(), -12);
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    NearShape& ns = impl.shapes[s];
    ns.pad = pad;
    RTCGeometry geom = rtcNewGeometry(impl.device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geom, unsigned(ns.boxes.size()));
    rtcSetGeometryUserData(geom, &ns);
    rtcSetGeometryBoundsFunction(geom, near_bounds, nullptr);
    rtcSetGeometryIntersectFunction(geom, near_intersect);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(impl.scene, geom, unsigned(s));
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(impl.scene);
  if (rtcGetDeviceError(impl.device) != RTC_ERROR_NONE) throw Error("Embree: near-triangle BVH build failed");
}

NearTriangleQuery::~NearTriangleQuery() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

double NearTriangleQuery::reach() const { return impl_->reach; }

void NearTriangleQuery::for_each(const Vec3& world_origin, const Vec3& dir, double tmax,
                                 void (*visit)(void*, int, int), void* user) const {
  const Vec3 origin = world_origin - impl_->local_origin;
  if (!ray_is_valid(origin, dir, tmax) || tmax < 0) return;
  NearContext ctx;
  rtcInitIntersectContext(&ctx.context);
  ctx.origin = origin;
  ctx.dir = dir;
  ctx.tmax = tmax;
  ctx.visit = visit;
  ctx.user = user;
  RTCRayHit rh;
  embree_ray(origin, dir, tmax, rh.ray);
  rh.ray.tfar = std::nextafter(rh.ray.tfar, std::numeric_limits<float>::infinity());  // never short of tmax
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &ctx.context, &rh);
}

}  // namespace qsil
