#pragma once
/// @file scene.h
/// The scene model: what qsil's scenes need and no more (docs/architecture.md §2). Loaded from the
/// Mitsuba 3 XML subset by load_scene() (src/scene_loader.cpp). All geometry is stored in world
/// space, in double precision, after applying each shape's to_world.

#include "qsil/image.h"
#include "qsil/math.h"

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace qsil {

/// Largest magnitude of a coordinate in a scene (scene units): load_obj() rejects vertex
/// coordinates beyond it, load_scene() vertices moved beyond it by to_world and a camera placed
/// beyond it, each with a one-line error naming the file, line and value. Why 1e12: Embree's
/// float triangle test forms products of three coordinate differences (Plücker T = 2 v0.(e1 x e2)),
/// |T| < 2 (3.5e12)^3 ~ 1e38 below float's 3.4e38 (1e13 would overflow), and Embree aborts on a
/// ray component beyond 1.844e18; qsil's own arithmetic is double. Bundled scenes stay within 1e4.
inline constexpr double kMaxCoordinate = 1e12;

/// A welded triangle mesh in world space.
/// - positions: V vertices, scene units.
/// - triangles: T index triples into positions; counter-clockwise winding seen from outside is the
///   outward normal (docs/architecture.md §3).
/// - normals: V unit shading normals (from the OBJ, or area-weighted vertex normals), or empty
///   when the shape uses face normals.
struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<Eigen::Vector3i> triangles;
  std::vector<Vec3> normals;

  int num_vertices() const { return int(positions.size()); }
  int num_triangles() const { return int(triangles.size()); }
  /// Unnormalised geometric normal (p1-p0)x(p2-p0) of triangle f; its length is twice the area.
  Vec3 face_cross(int f) const {
    const auto& t = triangles[f];
    return (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
  }
  double area(int f) const { return 0.5 * face_cross(f).norm(); }
  /// The point of triangle f at barycentrics (b1, b2) of its vertices 1 and 2 (Hit::u, Hit::v):
  /// (1 - b1 - b2) p0 + b1 p1 + b2 p2, world.
  Vec3 point(int f, double b1, double b2) const {
    const auto& t = triangles[size_t(f)];
    return (1.0 - b1 - b2) * positions[size_t(t[0])] + b1 * positions[size_t(t[1])] + b2 * positions[size_t(t[2])];
  }
  /// Axis-aligned box of triangle f's vertices.
  Box3 triangle_bounds(int f) const {
    Box3 b;
    for (int k = 0; k < 3; ++k) b.expand(positions[size_t(triangles[size_t(f)][k])]);
    return b;
  }
  Box3 bounds() const {
    Box3 b;
    for (const auto& p : positions) b.expand(p);
    return b;
  }
};

/// A BSDF of the Mitsuba 3 subset (docs/architecture.md; Mitsuba 3 plugin docs for parameter meaning).
/// - Diffuse: Lambertian, `reflectance` (default 0.5).
/// - RoughConductor: GGX microfacets with Smith shadowing, roughness `alpha` (default 0.1),
///   Fresnel factor 1 (Mitsuba's material="none"), scaled by `specular_reflectance` (default 1).
/// `twosided`: the BSDF is mirrored to the back side (Mitsuba's twosided wrapper); otherwise the
/// back side is black, as in Mitsuba 3.
struct BSDFDesc {
  enum class Type { Diffuse, RoughConductor };
  Type type = Type::Diffuse;
  Color reflectance = Color::Constant(0.5);
  double alpha = 0.1;
  Color specular_reflectance = Color::Constant(1.0);
  bool twosided = false;
  std::string id;
};

/// One shape: a triangle mesh with a BSDF and, optionally, an area emitter on its front side.
struct Shape {
  std::string id;      ///< XML id (parameters refer to it), may be empty
  std::string type;    ///< "obj" or "rectangle"
  std::string source;  ///< "scene.xml:LINE" for messages
  TriangleMesh mesh;
  bool face_normals = false;       ///< flat shading: every non-flat edge is a shading discontinuity
  int bsdf = -1;                   ///< index into Scene::bsdfs
  bool is_emitter = false;         ///< area emitter on the front (normal) side
  Color radiance = Color::Zero();  ///< emitted radiance when is_emitter
};

/// Environment lighting: none, a constant radiance, or a lat-long env map (Mitsuba 3 `envmap`:
/// direction d in the map's frame maps to u = atan2(d.x, -d.z)/(2 pi) wrapped to [0,1),
/// v = acos(d.y)/pi; the value is looked up piecewise-constant per texel and scaled by `scale`).
struct Environment {
  enum class Type { None, Constant, EnvMap };
  Type type = Type::None;
  Color radiance = Color::Zero();    ///< Constant: radiance
  std::string filename;              ///< EnvMap: resolved path
  double scale = 1.0;                ///< EnvMap: multiplier
  Mat3 to_world = Mat3::Identity();  ///< EnvMap: rotation part of to_world (local -> world)
  Image texels;                      ///< EnvMap: RGB texels (channels R,G,B)
};

/// Mitsuba 3's Transform4f::look_at as a camera-to-world matrix: columns [left, up', dir, origin]
/// with dir = normalize(target - origin), left = normalize(up x dir), up' = dir x left (world
/// frame). The caller guarantees target != origin and up not parallel to dir (the result has
/// NaN columns otherwise).
Mat4 look_at(const Vec3& origin, const Vec3& target, const Vec3& up);

/// Perspective pinhole camera (Mitsuba 3 `perspective`): looks along +z of its to_world frame,
/// with +x to the left and +y up in the image; box pixel filter.
struct Camera {
  Mat4 to_world = Mat4::Identity();  ///< camera-to-world, rigid (scale is rejected)
  double fov_deg = 46.7930;          ///< full field of view along fov_axis, degrees (the loader's
                                     ///< default is Mitsuba 3's: a 50 mm lens on the diagonal)
  std::string fov_axis = "x";        ///< x, y, diagonal, smaller, larger
  int width = 768;
  int height = 576;
  int spp = 4;              ///< sampler sample_count
  double near_clip = 1e-2;  ///< Mitsuba near_clip, scene units
  Vec3 origin() const { return to_world.block<3, 1>(0, 3); }
  /// tan of half the horizontal and vertical field of view.
  Vec2 tan_half_fov() const;
  /// World-space unit direction through film position (fx, fy) in pixels, (0,0) the top-left
  /// corner of the image, (width,height) the bottom-right: film -> world.
  Vec3 direction(double fx, double fy) const;
  /// Camera-space position of world point x (camera space looks along +z, +x is the image's
  /// left, +y its top; docs/architecture.md §3 "Frames").
  Vec3 to_camera(const Vec3& x) const;
  /// Film position (pixels, (0,0) top-left) of world point x, the inverse of direction(): world
  /// -> film. `depth` (optional) receives its camera-space z, > 0 in front of the camera. Points
  /// behind or at the camera's plane give meaningless (possibly non-finite) positions: callers
  /// clip first (depth > 0).
  Vec2 project(const Vec3& x, double* depth = nullptr) const;
};

/// A loaded scene. Shapes' geometry is in world space.
struct Scene {
  std::filesystem::path file;  ///< the XML file it came from
  std::vector<Shape> shapes;
  std::vector<BSDFDesc> bsdfs;
  Environment environment;
  Camera camera;
  int max_depth = -1;                           ///< Mitsuba path integrator: -1 = unbounded (capped, see integrators)
  Box3 bounds() const;                          ///< bounding box of all shapes
  int find_shape(const std::string& id) const;  ///< index, or -1
};

/// The `-D name=value` overrides of a command line as a map for load_scene(). Throws qsil::Error
/// "-D 'TEXT': expected name=value" for an entry without '=' or with an empty name; a later
/// entry for the same name wins.
std::map<std::string, std::string> parse_defines(const std::vector<std::string>& defines);

/// Loads a scene in the Mitsuba 3 XML subset (docs/architecture.md §2 "Scene").
/// `defaults` override `<default name value>` entries (the CLI's -D name=value).
/// Throws qsil::Error "scene.xml:LINE: message" for every unsupported or malformed input.
/// `warnings` receives counted, non-fatal warnings (one line each).
Scene load_scene(const std::filesystem::path& file, const std::map<std::string, std::string>& defaults = {},
                 std::vector<std::string>* warnings = nullptr);

/// Loads a Wavefront OBJ file as a welded TriangleMesh (positions welded by exact equality when
/// `weld` is true; polygons fan-triangulated; OBJ normals kept when present and weld is false,
/// otherwise area-weighted vertex normals). Zero-area triangles are dropped and counted in
/// `warnings`. Throws qsil::Error "PATH: message" (missing file, no faces) or "PATH:LINE: message"
/// for a vertex line whose first three coordinates are missing, not numbers, non-finite or larger
/// in magnitude than kMaxCoordinate.
TriangleMesh load_obj(const std::filesystem::path& path, bool weld = true,
                      std::vector<std::string>* warnings = nullptr);

/// Area-weighted vertex normals of a mesh (unit length; a vertex with zero total area gets +z).
std::vector<Vec3> vertex_normals(const TriangleMesh& mesh);

}  // namespace qsil
