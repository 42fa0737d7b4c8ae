/// @file scene_loader_test.cpp
/// load_scene(): the Mitsuba 3 XML subset, its error messages (`FILE:LINE: message`), transforms,
/// and the bundled scenes, including the geometric property that makes spot-mirror the paper's
/// setup (Spot visible only in the mirror).

#include "qsil/bsdf.h"
#include "qsil/error.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"
#include "ray_hits.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>

namespace qsil {
namespace {

using ::testing::HasSubstr;

std::string data(const std::string& name) { return std::string(QSIL_TEST_DATA_DIR) + "/scenes/" + name; }
std::string bundled(const std::string& name) { return std::string(QSIL_SOURCE_DIR) + "/scenes/" + name; }

/// The message of the qsil::Error that loading `file` throws ("" if none is thrown).
std::string load_error(const std::string& file, const std::map<std::string, std::string>& defs = {}) {
  try {
    load_scene(file, defs);
  } catch (const Error& e) { return e.what(); }
  return "";
}

const Shape& shape(const Scene& s, const std::string& id) {
  const int i = s.find_shape(id);
  EXPECT_GE(i, 0) << "no shape " << id;
  return s.shapes.at(std::max(i, 0));
}

bool has_vertex(const TriangleMesh& m, const Vec3& p) {
  return std::any_of(m.positions.begin(), m.positions.end(), [&](const Vec3& q) { return (q - p).norm() < 1e-12; });
}

/// Slab test: does the ray o + t d, t > 0, meet the box? (test::ray_hits_box from o.)
bool ray_hits_box(const Vec3& o, const Vec3& d, const Box3& b) { return test::ray_hits_box(d, b.lo - o, b.hi - o); }


// ---------------------------------------------------------------------------------------------
// Features
// ---------------------------------------------------------------------------------------------

TEST(SceneLoaderTest, DefaultsSubstitutionAndOverrides) {
  const Scene s = load_scene(data("features.xml"));
  EXPECT_EQ(s.camera.width, 32);
  EXPECT_EQ(s.camera.height, 16);
  EXPECT_EQ(s.camera.spp, 8);
  EXPECT_EQ(s.max_depth, 5);
  EXPECT_EQ(s.camera.fov_axis, "y");
  EXPECT_DOUBLE_EQ(s.camera.fov_deg, 45);
  EXPECT_DOUBLE_EQ(s.camera.near_clip, 0.5);
  EXPECT_DOUBLE_EQ(s.bsdfs[shape(s, "tet_ref").bsdf].reflectance[0], 0.25);

  std::vector<std::string> warnings;
  const Scene o = load_scene(data("features.xml"), {{"res", "64"}, {"albedo", "0.75"}, {"unused", "1"}}, &warnings);
  EXPECT_EQ(o.camera.width, 64);
  EXPECT_DOUBLE_EQ(o.bsdfs[shape(o, "tet_ref").bsdf].reflectance[1], 0.75);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("$unused"));
}

TEST(SceneLoaderTest, RefsTwosidedEmittersAndDefaultBsdf) {
  const Scene s = load_scene(data("features.xml"));
  ASSERT_EQ(s.shapes.size(), 5u);
  EXPECT_EQ(s.environment.type, Environment::Type::Constant);
  EXPECT_TRUE(((s.environment.radiance - Color(0.1, 0.2, 0.3)).abs() < 1e-12).all());

  const BSDFDesc& gray = s.bsdfs[shape(s, "tet_ref").bsdf];
  EXPECT_EQ(gray.type, BSDFDesc::Type::Diffuse);
  EXPECT_EQ(gray.id, "gray");
  EXPECT_FALSE(gray.twosided);

  const BSDFDesc& two = s.bsdfs[shape(s, "tet_flat").bsdf];
  EXPECT_EQ(two.type, BSDFDesc::Type::RoughConductor);
  EXPECT_TRUE(two.twosided);
  EXPECT_DOUBLE_EQ(two.alpha, 0.3);
  EXPECT_DOUBLE_EQ(two.specular_reflectance[2], 0.7);

  const Shape& lamp = shape(s, "lamp");
  EXPECT_TRUE(lamp.is_emitter);
  EXPECT_TRUE(((lamp.radiance - Color(10, 20, 30)).abs() < 1e-12).all());
  EXPECT_TRUE(s.bsdfs[lamp.bsdf].twosided);  // twosided around a <ref>
  EXPECT_DOUBLE_EQ(s.bsdfs[lamp.bsdf].reflectance[0], 0.25);
  EXPECT_FALSE(shape(s, "tet_ref").is_emitter);

  const BSDFDesc& def = s.bsdfs[shape(s, "tet_flipped").bsdf];  // Mitsuba's default BSDF
  EXPECT_EQ(def.type, BSDFDesc::Type::Diffuse);
  EXPECT_DOUBLE_EQ(def.reflectance[0], 0.5);
  EXPECT_FALSE(def.twosided);
  EXPECT_THAT(shape(s, "lamp").source, HasSubstr("features.xml:"));
}

TEST(SceneLoaderTest, ObjNormalsFaceNormalsAndFlip) {
  const Scene s = load_scene(data("features.xml"));
  const Shape& tet = shape(s, "tet_ref");
  EXPECT_EQ(tet.mesh.num_vertices(), 4);
  EXPECT_EQ(tet.mesh.num_triangles(), 4);
  EXPECT_EQ(tet.mesh.normals.size(), 4u);
  EXPECT_FALSE(tet.face_normals);
  // Outward: the origin corner's normal points away from the tetrahedron, along -(1,1,1).
  auto origin_index = [](const TriangleMesh& m) {
    for (int v = 0; v < m.num_vertices(); ++v)
      if (m.positions[v] == Vec3::Zero()) return v;
    return -1;
  };
  ASSERT_GE(origin_index(tet.mesh), 0);
  EXPECT_NEAR(tet.mesh.normals[origin_index(tet.mesh)].dot(Vec3(1, 1, 1)), -std::sqrt(3.0), 1e-12);

  const Shape& flat = shape(s, "tet_flat");
  EXPECT_TRUE(flat.face_normals);
  EXPECT_TRUE(flat.mesh.normals.empty());

  // flip_normals reverses the winding (the face x = 0 now faces +x) and the normals.
  const Shape& flipped = shape(s, "tet_flipped");
  EXPECT_NEAR(flipped.mesh.normals[origin_index(flipped.mesh)].dot(Vec3(1, 1, 1)), std::sqrt(3.0), 1e-12);
  const Vec3 c0 = tet.mesh.face_cross(0), c1 = flipped.mesh.face_cross(0);
  EXPECT_NEAR((c0 + c1).norm(), 0, 1e-12);
}

// Welding joins vertices at equal positions (== on each coordinate, so -0.0 and 0.0 are one
// position), numbers vertices in the order first met, and leaves distinct positions apart;
// without welding, each distinct (position, normal) index pair is a vertex.
TEST(SceneLoaderTest, ObjWeldingJoinsEqualPositionsInFirstMetOrder) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "_weld.obj");
  {
    std::ofstream out(p);
    // Two triangles sharing the edge (0,0,0)-(1,0,0), written twice (once as -0.0), plus a point
    // 1e-12 away from (0,1,0) that must stay a vertex of its own.
    out << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -0.0 -0.0 0\nv 1 0 -0.0\nv 0 -1 0\nv 0 1.000000000001 0\n"
           "f 1 2 3\nf 4 6 5\nf 7 1 2\n";
  }
  const TriangleMesh welded = load_obj(p);
  ASSERT_EQ(welded.num_triangles(), 3);
  EXPECT_EQ(welded.num_vertices(), 5);
  // Vertex indices two triangles share.
  auto shared = [&](int a, int b) {
    int n = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) n += welded.triangles[size_t(a)][i] == welded.triangles[size_t(b)][j];
    return n;
  };
  EXPECT_EQ(shared(0, 1), 2);  // the edge, once written with -0.0
  EXPECT_EQ(shared(0, 2), 2);  // the same edge; (0, 1 + 1e-12, 0) is not (0, 1, 0)
  EXPECT_EQ(shared(1, 2), 2);
  // Numbered in the order first met: the first triangle's vertices are 0, 1, 2.
  EXPECT_EQ(welded.triangles[0].minCoeff(), 0);
  EXPECT_EQ(welded.triangles[0].maxCoeff(), 2);
  const TriangleMesh apart = load_obj(p, false);
  EXPECT_EQ(apart.num_vertices(), 7);
  std::filesystem::remove(p);
}

// The vertex check reads every form of number strtod reads in an OBJ (a leading '+', exponents,
// CRLF line ends, tabs, an underflow to 0) and refuses, naming the line, what tinyobjloader would
// silently read as 0: a word, a second sign, an overflow to infinity, a missing coordinate.
TEST(SceneLoaderTest, ObjVertexCheckAcceptsNumbersAndNamesTheLineOfAnythingElse) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "_vcheck.obj");
  auto write = [&](const std::string& text) {
    std::ofstream out(p, std::ios::binary);
    out << text;
  };
  write("# ok\r\nv +1.5e0 0 0\r\nv\t0 +2 -0.0\r\n  v 0 0 1e-400\r\nvn 0 0 1\r\nf 1 2 3\r\n");
  const TriangleMesh m = load_obj(p);
  ASSERT_EQ(m.num_vertices(), 3);
  for (const Vec3& expected : {Vec3(1.5, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 0)})
    EXPECT_NE(std::find(m.positions.begin(), m.positions.end(), expected), m.positions.end()) << expected.transpose();
  for (const auto& [text, needle] : std::vector<std::pair<std::string, std::string>>{
           {"v 0 0 0\nv 1 0 0\nv 0 1 x\nf 1 2 3\n", ":3: vertex coordinate 'x' is not a number"},
           {"v 0 0 0\nv +-1 0 0\nv 0 1 0\nf 1 2 3\n", ":2: vertex coordinate '+-1' is not a number"},
           {"v 0 0 0\nv 1 0 0\nv 0 1 1e400\nf 1 2 3\n", ":3: non-finite coordinate '1e400'"},
           {"v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", ":2: vertex has 2 coordinate(s), expected 3"},
           {"v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3", ":3: non-finite coordinate 'nan'"}}) {
    write(text);
    try {
      load_obj(p);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(p.string() + needle), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove(p);
}

TEST(SceneLoaderTest, RectangleGeometry) {
  const Scene s = load_scene(data("features.xml"));
  // lamp: the [-1,1]^2 square scaled 0.5, rotated +90 deg about x (normal +z -> -y), at y = 3.
  const Shape& lamp = shape(s, "lamp");
  ASSERT_EQ(lamp.mesh.num_vertices(), 4);
  ASSERT_EQ(lamp.mesh.num_triangles(), 2);
  for (const Vec3& p : {Vec3(-0.5, 3, 0.5), Vec3(0.5, 3, 0.5), Vec3(0.5, 3, -0.5), Vec3(-0.5, 3, -0.5)})
    EXPECT_TRUE(has_vertex(lamp.mesh, p)) << p.transpose();
  double area = 0;
  for (int f = 0; f < 2; ++f) {
    area += lamp.mesh.area(f);
    EXPECT_NEAR((lamp.mesh.face_cross(f).normalized() - Vec3(0, -1, 0)).norm(), 0, 1e-12);
  }
  EXPECT_NEAR(area, 1.0, 1e-12);
  for (const Vec3& n : lamp.mesh.normals) EXPECT_NEAR((n - Vec3(0, -1, 0)).norm(), 0, 1e-12);

  // A mirroring to_world (scale z = -1): the normal is the inverse transpose of +z, -z, and the
  // winding follows it so that counter-clockwise stays the normal's side.
  const Shape& m = shape(s, "mirrored");
  for (const Vec3& n : m.mesh.normals) EXPECT_NEAR((n - Vec3(0, 0, -1)).norm(), 0, 1e-12);
  for (int f = 0; f < 2; ++f) EXPECT_LT(m.mesh.face_cross(f).z(), 0);
}

TEST(SceneLoaderTest, Transforms) {
  const Scene s = load_scene(data("transforms.xml"));
  // Where the corner (1, 1, 0) and the corner (1, -1, 0) of each rectangle go, by hand.
  auto expect_corners = [&](const std::string& id, const Vec3& a, const Vec3& b) {
    SCOPED_TRACE(id);
    EXPECT_TRUE(has_vertex(shape(s, id).mesh, a)) << a.transpose();
    EXPECT_TRUE(has_vertex(shape(s, id).mesh, b)) << b.transpose();
  };
  expect_corners("translate", Vec3(2, 3, 3), Vec3(2, 1, 3));
  expect_corners("translate_value", Vec3(2, 3, 3), Vec3(2, 1, 3));
  expect_corners("rotate", Vec3(-1, 1, 0), Vec3(1, 1, 0));       // (x, y) -> (-y, x)
  expect_corners("rotate_axis", Vec3(-1, 1, 0), Vec3(1, 1, 0));  // axis is normalised
  expect_corners("scale", Vec3(2, 3, 0), Vec3(2, -3, 0));
  expect_corners("scale_value", Vec3(2, 2, 0), Vec3(2, -2, 0));
  // Row-major matrix [0 -1 0 5; 1 0 0 6; 0 0 1 7]: (1,1,0) -> (4,7,7), (1,-1,0) -> (6,7,7).
  expect_corners("matrix", Vec3(4, 7, 7), Vec3(6, 7, 7));
  // scale x2, then rotate 90 about z, then translate x+10: M = T R S (each child pre-multiplies).
  // (1,1,0) -> (2,1,0) -> (-1,2,0) -> (9,2,0); (1,-1,0) -> (2,-1,0) -> (1,2,0) -> (11,2,0).
  expect_corners("composed", Vec3(9, 2, 0), Vec3(11, 2, 0));
  // lookat along +z with up +y: columns [left = up x dir = +x, up = +y, dir = +z, origin].
  expect_corners("lookat", Vec3(2, 3, 3), Vec3(2, 1, 3));
}

TEST(SceneLoaderTest, ZeroAreaTrianglesAreCountedWarnings) {
  std::vector<std::string> warnings;
  const Scene s = load_scene(data("degenerate.xml"), {}, &warnings);
  EXPECT_EQ(shape(s, "d").mesh.num_triangles(), 1);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("degenerate.xml:4:"));
  EXPECT_THAT(warnings[0], HasSubstr("1 zero-area triangle"));
}

// ---------------------------------------------------------------------------------------------
// Errors: each one line, naming file and line
// ---------------------------------------------------------------------------------------------

struct ErrorCase {
  const char* file;
  const char* location;  // "file:LINE:"
  const char* message;
};

class SceneLoaderErrorTest : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(SceneLoaderErrorTest, MessageNamesFileAndLine) {
  const ErrorCase& c = GetParam();
  const std::string msg = load_error(data(c.file));
  EXPECT_THAT(msg, HasSubstr(c.location));
  EXPECT_THAT(msg, HasSubstr(c.message));
  EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
}

// One case per line (a table: the formatter leaves it as written).
// clang-format off
INSTANTIATE_TEST_SUITE_P(
    Cases, SceneLoaderErrorTest,
    ::testing::Values(
        ErrorCase{"bad_plugin.xml", "bad_plugin.xml:3:", "unsupported plugin 'sphere' for <shape> (supported: obj, rectangle)"},
        ErrorCase{"bad_param.xml", "bad_param.xml:4:", "unknown parameter 'roughness' for plugin 'diffuse'"},
        ErrorCase{"bad_malformed.xml", "bad_malformed.xml:4:", "malformed XML"},
        ErrorCase{"bad_missing_obj.xml", "bad_missing_obj.xml:4:", "file not found: "},
        ErrorCase{"bad_noface_obj.xml", "bad_noface_obj.xml:4:", "OBJ has no faces"},
        ErrorCase{"bad_nan_obj.xml", "bad_nan_obj.xml:4:", "non-finite coordinate"},
        ErrorCase{"bad_nan_transform.xml", "bad_nan_transform.xml:5:", "non-finite translate y 'nan'"},
        ErrorCase{"bad_huge_obj.xml", "bad_huge_obj.xml:4:", "huge.obj:2: vertex coordinate 1e30 exceeds the largest supported magnitude 1e12"},
        ErrorCase{"bad_garbage_obj.xml", "bad_garbage_obj.xml:4:", "garbage.obj:3: vertex coordinate 'abc' is not a number"},
        ErrorCase{"bad_huge_transform.xml", "bad_huge_transform.xml:5:", "to_world moves a vertex to coordinate magnitude 1e+20"},
        ErrorCase{"bad_far_camera.xml", "bad_far_camera.xml:3:", "sensor position coordinate magnitude 2e+13"},
        ErrorCase{"bad_inf_rgb.xml", "bad_inf_rgb.xml:4:", "non-finite 'reflectance' 'inf'"},
        ErrorCase{"bad_missing_envmap.xml", "bad_missing_envmap.xml:4:", "file not found: "},
        ErrorCase{"bad_conductor_preset.xml", "bad_conductor_preset.xml:5:", "named conductor presets are not supported"},
        ErrorCase{"bad_beckmann.xml", "bad_beckmann.xml:3:", "distribution 'beckmann' is not supported"},
        ErrorCase{"bad_anisotropic.xml", "bad_anisotropic.xml:5:", "anisotropic roughness"},
        ErrorCase{"bad_unknown_var.xml", "bad_unknown_var.xml:4:", "undefined parameter '$size'"},
        ErrorCase{"bad_unknown_tag.xml", "bad_unknown_tag.xml:3:", "unsupported element <texture>"},
        ErrorCase{"bad_ref.xml", "bad_ref.xml:4:", "<ref> to unknown id 'nowhere'"},
        ErrorCase{"bad_two_envs.xml", "bad_two_envs.xml:4:", "more than one environment emitter"},
        ErrorCase{"bad_hide_emitters.xml", "bad_hide_emitters.xml:4:", "hide_emitters"},
        ErrorCase{"bad_no_sensor.xml", "bad_no_sensor.xml:1:", "no <sensor>"},
        ErrorCase{"bad_camera_scale.xml", "bad_camera_scale.xml:3:", "must be rigid"},
        ErrorCase{"bad_empty.xml", "bad_empty.xml:1:", "no shapes and no emitter"},
        ErrorCase{"bad_duplicate_id.xml", "bad_duplicate_id.xml:4:", "duplicate id 'a' (first at line 3)"},
        ErrorCase{"bad_param_type.xml", "bad_param_type.xml:5:", "parameter 'alpha' of plugin 'roughconductor' must be <float> or <integer>, not <string>"},
        ErrorCase{"does_not_exist.xml", "does_not_exist.xml", "file not found"}),
    [](const auto& info) {
      std::string n = info.param.file;
      n = n.substr(0, n.find('.'));
      return n;
    });
// clang-format on

TEST(SceneLoaderTest, MitsubaCameraDefaults) {
  std::vector<std::string> warnings;
  const Scene s = load_scene(data("default_camera.xml"), {}, &warnings);
  EXPECT_EQ(s.camera.width, 768);
  EXPECT_EQ(s.camera.height, 576);
  EXPECT_EQ(s.camera.spp, 4);
  EXPECT_EQ(s.max_depth, -1);
  // No fov: a 50 mm lens on 36 x 24 mm film, as a diagonal field of view (Mitsuba's parse_fov).
  EXPECT_EQ(s.camera.fov_axis, "diagonal");
  EXPECT_NEAR(s.camera.fov_deg, 2 * std::atan(std::hypot(36.0, 24.0) / 100.0) * 180 / kPi, 1e-12);
  EXPECT_EQ(s.camera.to_world, Mat4::Identity());
  EXPECT_TRUE(s.shapes.empty());  // allowed: there is an emitter
}

TEST(SceneLoaderTest, MissingFileNamesThePath) {
  EXPECT_THAT(load_error(data("bad_missing_obj.xml")), HasSubstr("does_not_exist.obj"));
  EXPECT_THAT(load_error(data("bad_missing_envmap.xml")), HasSubstr("no_such_map.exr"));
}

// ---------------------------------------------------------------------------------------------
// Bundled scenes
// ---------------------------------------------------------------------------------------------

TEST(SceneLoaderTest, BundledScenesLoadWithoutWarnings) {
  for (const char* name : {"spot-mirror.xml", "shadow-quad.xml", "direct.xml", "two-mirrors.xml"}) {
    SCOPED_TRACE(name);
    std::vector<std::string> warnings;
    const Scene s = load_scene(bundled(name), {}, &warnings);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    EXPECT_EQ(s.camera.width, 256);
    EXPECT_EQ(s.camera.height, 256);
    EXPECT_EQ(s.camera.spp, 64);
    EXPECT_EQ(s.max_depth, 3);
    for (const Shape& sh : s.shapes) EXPECT_FALSE(sh.id.empty()) << "every shape needs an id";
    // -D overrides reach the film, the sampler and the integrator.
    const Scene o = load_scene(bundled(name), {{"res", "32"}, {"spp", "2"}, {"max_depth", "5"}});
    EXPECT_EQ(o.camera.width, 32);
    EXPECT_EQ(o.camera.spp, 2);
    EXPECT_EQ(o.max_depth, 5);
  }
}

// The paper's setup: the camera sees Spot only in the mirror. For every film position on a
// half-pixel grid (pixel corners and centres, so the whole box-filtered footprint) the direct ray
// misses Spot's bounding box; many pixels' mirror-reflected rays hit it.
TEST(SceneLoaderTest, SpotMirrorShowsSpotOnlyInTheMirror) {
  const Scene s = load_scene(bundled("spot-mirror.xml"));
  const Shape& spot = shape(s, "spot");
  const Shape& mirror = shape(s, "mirror");
  EXPECT_EQ(s.bsdfs[mirror.bsdf].type, BSDFDesc::Type::RoughConductor);
  EXPECT_DOUBLE_EQ(s.bsdfs[mirror.bsdf].alpha, 0.01);
  EXPECT_EQ(s.environment.type, Environment::Type::EnvMap);
  const Box3 box = spot.mesh.bounds();
  const Camera& cam = s.camera;
  const Vec3 o = cam.origin();
  const Vec3 n = mirror.mesh.face_cross(0).normalized();

  int direct_hits = 0;
  for (int j = 0; j <= 2 * cam.height; ++j)
    for (int i = 0; i <= 2 * cam.width; ++i) direct_hits += ray_hits_box(o, cam.direction(0.5 * i, 0.5 * j), box);
  EXPECT_EQ(direct_hits, 0);

  int on_mirror = 0, reflected_hits = 0;
  for (int j = 0; j < cam.height; ++j) {
    for (int i = 0; i < cam.width; ++i) {
      const Vec3 d = cam.direction(i + 0.5, j + 0.5);
      const auto hit = test::ray_hits_mesh(o, d, mirror.mesh);
      if (!hit || d.dot(n) >= 0) continue;
      ++on_mirror;
      const Vec3 r = reflect(-d, n);
      reflected_hits += ray_hits_box(o + hit->t * d, r, box);
    }
  }
  const int pixels = cam.width * cam.height;
  EXPECT_GE(on_mirror, 0.9 * pixels) << "the mirror should fill the view";
  EXPECT_GE(reflected_hits, 0.2 * pixels) << "Spot should fill a good part of the mirror";
}

/// Every scene of the stability study (scenes/stability/params.txt: name, parameter, question per
/// line) loads, with every mesh and map it names (some are test assets used in place), and its
/// parameter names a shape of it and is the one its XML header says it studies.
TEST(SceneLoaderTest, EveryStabilitySceneLoadsWithItsParameter) {
  std::ifstream list(bundled("stability/params.txt"));
  ASSERT_TRUE(list) << bundled("stability/params.txt");
  int scenes = 0;
  for (std::string line; std::getline(list, line);) {
    if (line.empty()) continue;
    const size_t tab1 = line.find('\t'), tab2 = line.find('\t', tab1 + 1);
    ASSERT_NE(tab2, std::string::npos) << line;
    const std::string name = line.substr(0, tab1), param = line.substr(tab1 + 1, tab2 - tab1 - 1);
    EXPECT_GT(line.size(), tab2 + 1) << name << ": no question";
    const std::string file = bundled("stability/" + name + ".xml");
    std::optional<Scene> scene;
    try {
      scene.emplace(load_scene(file, {{"res", "8"}}));
      EXPECT_EQ(parse_parameters({param}, *scene).size(), 1u) << name;
    } catch (const Error& e) {
      ADD_FAILURE() << name << ": " << e.what();
      continue;
    }
    std::ifstream xml(file);
    const std::string text((std::istreambuf_iterator<char>(xml)), std::istreambuf_iterator<char>());
    EXPECT_THAT(text, HasSubstr("Parameter studied: " + param)) << name;
    ++scenes;
  }
  EXPECT_GE(scenes, 14);  // the 13 of the first study and thin-metal
}

// The inverse-rendering set-up of [QSS] 5.5: the camera sees the bunny directly from behind, and its
// face side in each of the two mirrors, from three sides. Pixel-centre rays of a 64 x 64 grid over
// the film that reach the bunny directly, or after one reflection in a mirror (whichever of bunny
// and mirrors the ray meets first), give each view at least 2.5 % of the grid; the mean directions
// along which the three views see the bunny lie more than 90 degrees apart; at least 2/3 of each
// mirror view's points lie on the far side of the bunny's box centre from the camera (z < centre),
// which the direct view cannot show; and the head (the vertices in the top quarter of the height)
// lies on that far side too, so the face is seen only in the mirrors. The mirrors' normals are the
// header's. A bunny behind the camera (no direct view), mirror views of one side, or a bunny facing
// the camera fail it.
TEST(SceneLoaderTest, TwoMirrorsShowTheBunnyFromThreeSides) {
  const Scene s = load_scene(bundled("two-mirrors.xml"));
  const TriangleMesh& bunny = shape(s, "bunny").mesh;
  const Camera& cam = s.camera;
  const Vec3 o = cam.origin();
  std::array<const TriangleMesh*, 2> mirrors{};
  std::array<Vec3, 2> normals{};
  int k = 0;
  for (const char* id : {"mirror-left", "mirror-right"}) {
    const Shape& mirror = shape(s, id);
    EXPECT_EQ(s.bsdfs[mirror.bsdf].type, BSDFDesc::Type::RoughConductor);
    EXPECT_DOUBLE_EQ(s.bsdfs[mirror.bsdf].alpha, 0.01);
    mirrors[size_t(k)] = &mirror.mesh;
    normals[size_t(k)] = mirror.mesh.face_cross(0).normalized();
    const Vec3 header_normal((k == 0 ? 1 : -1) * 0.592, 0.103, 0.800);
    EXPECT_LT((normals[size_t(k)] - header_normal).norm(), 2e-3) << id << ": " << normals[size_t(k)].transpose();
    ++k;
  }
  const Box3 box = bunny.bounds();
  const double centre_z = 0.5 * (box.lo.z() + box.hi.z());
  constexpr int kGrid = 64;
  std::array<Vec3, 3> mean_dir{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};  // direct, left, right
  std::array<int, 3> seen{0, 0, 0};
  std::array<int, 3> far_side{0, 0, 0};  // points with z < centre
  for (int j = 0; j < kGrid; ++j)
    for (int i = 0; i < kGrid; ++i) {
      const Vec3 d = cam.direction((i + 0.5) * cam.width / kGrid, (j + 0.5) * cam.height / kGrid);
      const auto direct = test::ray_hits_mesh(o, d, bunny);
      double t = direct ? direct->t : std::numeric_limits<double>::infinity();
      int view = direct ? 0 : -1;
      for (int m = 0; m < 2; ++m) {
        const auto hit = test::ray_hits_mesh(o, d, *mirrors[size_t(m)]);
        if (hit && hit->t < t) {
          t = hit->t;
          view = m + 1;
        }
      }
      if (view < 0) continue;
      Vec3 along = d;
      Vec3 point = o + t * d;
      if (view > 0) {
        const Vec3& n = normals[size_t(view - 1)];
        if (d.dot(n) >= 0) continue;
        along = reflect(-d, n);
        const Vec3 on_mirror = point;
        const auto reflected = test::ray_hits_mesh(on_mirror, along, bunny);
        if (!reflected) continue;
        point = on_mirror + reflected->t * along;
      }
      ++seen[size_t(view)];
      far_side[size_t(view)] += point.z() < centre_z;
      mean_dir[size_t(view)] += along;
    }
  const char* names[3] = {"direct", "mirror-left", "mirror-right"};
  for (int v = 0; v < 3; ++v) {
    EXPECT_GE(seen[size_t(v)], 0.025 * kGrid * kGrid) << names[v];
    if (v > 0) { EXPECT_GE(3 * far_side[size_t(v)], 2 * seen[size_t(v)]) << names[v]; }
    std::printf("two-mirrors: %s: %d of %d points on the far side\n", names[v], far_side[size_t(v)], seen[size_t(v)]);
  }
  Vec3 head = Vec3::Zero();
  int head_vertices = 0;
  for (const Vec3& x : bunny.positions)
    if (x.y() > box.lo.y() + 0.75 * (box.hi.y() - box.lo.y())) {
      head += x;
      ++head_vertices;
    }
  ASSERT_GT(head_vertices, 0);
  head /= head_vertices;
  EXPECT_LT(head.z(), centre_z - 0.1 * (box.hi.z() - box.lo.z())) << "the head should face away from the camera";
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) {
      const double angle =
          std::acos(std::clamp(mean_dir[size_t(a)].normalized().dot(mean_dir[size_t(b)].normalized()), -1.0, 1.0)) *
          180 / kPi;
      std::printf("two-mirrors: %s (%d of %d rays) and %s (%d) see the bunny from directions %.1f deg apart\n",
                  names[a], seen[size_t(a)], kGrid * kGrid, names[b], seen[size_t(b)], angle);
      EXPECT_GT(angle, 90.0) << names[a] << ", " << names[b];
    }
}

TEST(SceneLoaderTest, ShadowQuadGeometry) {
  const Scene s = load_scene(bundled("shadow-quad.xml"));
  const Shape& object = shape(s, "object");
  const Shape& floor = shape(s, "floor");
  const Shape& light = shape(s, "light");
  EXPECT_TRUE(light.is_emitter);
  EXPECT_FALSE(object.is_emitter);
  EXPECT_EQ(s.environment.type, Environment::Type::Constant);
  const Box3 ob = object.mesh.bounds(), fb = floor.mesh.bounds(), lb = light.mesh.bounds();
  EXPECT_GT(ob.lo.y(), fb.hi.y());  // on the floor, not through it
  EXPECT_LT(ob.lo.y(), fb.hi.y() + 1e-2);
  EXPECT_NEAR(ob.extent().y(), 1.16, 0.01);                           // about one unit tall
  EXPECT_GT(lb.lo.y(), ob.hi.y());                                    // the light is above the object
  EXPECT_NEAR(light.mesh.face_cross(0).normalized().y(), -1, 1e-12);  // facing down
  EXPECT_NEAR(floor.mesh.face_cross(0).normalized().y(), 1, 1e-12);   // facing up
  // The camera sees the object: its centre ray passes near it, its whole box projects inside.
  const Camera& cam = s.camera;
  EXPECT_TRUE(ray_hits_box(cam.origin(), cam.direction(cam.width / 2.0, cam.height / 2.0), ob));
}

TEST(SceneLoaderTest, DirectSceneSeesSpotWhole) {
  const Scene s = load_scene(bundled("direct.xml"));
  const Box3 box = shape(s, "spot").mesh.bounds();
  const Camera& cam = s.camera;
  EXPECT_TRUE(ray_hits_box(cam.origin(), cam.direction(cam.width / 2.0, cam.height / 2.0), box));
  // Every corner of Spot's box is inside the frustum.
  const Mat3 rot = cam.to_world.block<3, 3>(0, 0);
  const Vec2 t = cam.tan_half_fov();
  for (int k = 0; k < 8; ++k) {
    const Vec3 corner((k & 1) ? box.hi.x() : box.lo.x(), (k & 2) ? box.hi.y() : box.lo.y(),
                      (k & 4) ? box.hi.z() : box.lo.z());
    const Vec3 local = rot.transpose() * (corner - cam.origin());
    ASSERT_GT(local.z(), 0);
    EXPECT_LT(std::abs(local.x() / local.z()), t.x());
    EXPECT_LT(std::abs(local.y() / local.z()), t.y());
  }
  const Shape& backdrop = shape(s, "backdrop");
  EXPECT_NEAR(backdrop.mesh.face_cross(0).normalized().z(), 1, 1e-12);  // facing the camera
}

}  // namespace
}  // namespace qsil
