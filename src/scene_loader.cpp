/// @file scene_loader.cpp
/// load_scene(): the Mitsuba 3 XML subset of qsil (docs/architecture.md §2, §8).
///
/// Supported plugins (Mitsuba 3 names, defaults and units):
///
/// | element    | types                                  | parameters                                      |
/// | ---------- | -------------------------------------- | ----------------------------------------------- |
/// | sensor     | perspective                            | fov (deg), fov_axis, focal_length, near_clip,    |
/// |            |                                        | far_clip (ignored), to_world (rigid)            |
/// | film       | hdrfilm                                | width, height (768x576), rfilter box            |
/// | sampler    | independent (others: as independent)   | sample_count (4), seed (ignored)                |
/// | shape      | obj, rectangle                         | filename, to_world, face_normals, flip_normals  |
/// | bsdf       | diffuse, roughconductor, twosided      | reflectance; distribution=ggx, alpha,           |
/// |            |                                        | specular_reflectance, material=none             |
/// | emitter    | area (in a shape), envmap, constant    | radiance; filename, scale, to_world (rotation)  |
/// | integrator | path                                   | max_depth (-1), rr_depth (ignored), hide_emitters=false |
///
/// Anything else is an error naming the file and line: qsil renders what the XML says or
/// refuses it, never something close to it (pbrt-v4's strictness).

#include "qsil/error.h"
#include "qsil/image.h"
#include "qsil/scene.h"

#include "xml_plugin.h"
#include "xml_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <set>

namespace qsil {

namespace {

using xml::Plugin;
using xml::Source;

std::string join(std::initializer_list<const char*> names) {
  std::string s;
  for (const char* n : names) s += std::string(s.empty() ? "" : ", ") + n;
  return s;
}

/// Throws "unsupported plugin 'X' (supported: ...)" unless the element's type is in `supported`.
void check_type(const Source& src, pugi::xml_node node, std::initializer_list<const char*> supported) {
  const std::string type = node.attribute("type").value();
  if (type.empty()) src.fail(node, "<" + std::string(node.name()) + "> needs a 'type' attribute");
  for (const char* s : supported)
    if (type == s) return;
  src.fail(node, "unsupported plugin '" + type + "' for <" + node.name() + "> (supported: " + join(supported) + ")");
}

bool is_affine(const Mat4& m) { return m(3, 0) == 0 && m(3, 1) == 0 && m(3, 2) == 0 && m(3, 3) == 1; }

/// Rᵀ R = I within a tolerance meant for matrices written with ~6 significant digits.
bool is_orthogonal(const Mat3& r) { return ((r.transpose() * r - Mat3::Identity()).cwiseAbs().maxCoeff()) < 1e-5; }

void check_color(const Plugin& p, const std::string& name, const Color& c) {
  if (!(c >= 0).all()) p.fail("'" + name + "' must be non-negative");
}

/// Loads one shape or the whole scene; keeps the state that crosses elements (ids, refs).
class Loader {
 public:
  Loader(const Source& src, Scene& scene, std::vector<std::string>* warnings)
      : src_(src), scene_(scene), warnings_(warnings) {}

  void load();

 private:
  void warn(pugi::xml_node node, const std::string& message) {
    if (warnings_) warnings_->push_back(src_.where(node) + ": " + message);
  }
  void register_id(pugi::xml_node node);

  int add_bsdf(pugi::xml_node node);
  BSDFDesc parse_bsdf(pugi::xml_node node, bool nested_in_twosided);
  int resolve_ref(pugi::xml_node ref);
  int default_bsdf();

  void parse_shape(pugi::xml_node node);
  TriangleMesh rectangle_mesh() const;
  void place_mesh(const Plugin& p, Shape& shape, const Mat4& to_world, bool flip);
  void parse_area_emitter(pugi::xml_node node, Shape& shape);

  void parse_environment(pugi::xml_node node);
  void parse_sensor(pugi::xml_node node);
  void parse_film(pugi::xml_node node);
  void parse_sampler(pugi::xml_node node);
  void parse_integrator(pugi::xml_node node);

  const Source& src_;
  Scene& scene_;
  std::vector<std::string>* warnings_;
  std::map<std::string, pugi::xml_node> ids_;  // every id seen, for duplicates
  std::map<std::string, int> bsdf_ids_;        // BSDF id -> index into scene_.bsdfs
  int default_bsdf_ = -1;
  pugi::xml_node sensor_, integrator_, environment_;
};

void Loader::register_id(pugi::xml_node node) {
  const std::string id = node.attribute("id").value();
  if (id.empty()) return;
  if (auto it = ids_.find(id); it != ids_.end())
    src_.fail(node, "duplicate id '" + id + "' (first at line " + std::to_string(src_.line(it->second)) + ")");
  ids_[id] = node;
}

// ---------------------------------------------------------------------------------------------
// BSDFs
// ---------------------------------------------------------------------------------------------

int Loader::add_bsdf(pugi::xml_node node) {
  register_id(node);
  scene_.bsdfs.push_back(parse_bsdf(node, false));
  const int index = int(scene_.bsdfs.size()) - 1;
  if (!scene_.bsdfs.back().id.empty()) bsdf_ids_[scene_.bsdfs.back().id] = index;
  return index;
}

BSDFDesc Loader::parse_bsdf(pugi::xml_node node, bool nested_in_twosided) {
  check_type(src_, node, {"diffuse", "roughconductor", "twosided"});
  const std::string type = node.attribute("type").value();
  BSDFDesc b;
  b.id = node.attribute("id").value();
  if (type == "twosided") {
    if (nested_in_twosided) src_.fail(node, "a twosided BSDF cannot wrap another twosided BSDF");
    Plugin p(src_, node, {}, {"bsdf", "ref"});
    if (p.nested().size() != 1) {
      p.fail(p.nested().empty() ? "twosided needs one nested <bsdf> or <ref>"
                                : "twosided with two different BSDFs (front/back) is not supported");
    }
    const pugi::xml_node inner = p.nested().front();
    if (std::string(inner.name()) == "ref") {
      b = scene_.bsdfs[resolve_ref(inner)];
      if (b.twosided) src_.fail(inner, "a twosided BSDF cannot wrap another twosided BSDF");
    } else {
      register_id(inner);
      b = parse_bsdf(inner, true);
    }
    b.twosided = true;
    b.id = node.attribute("id").value();
    return b;
  }
  if (type == "diffuse") {
    Plugin p(src_, node, {"reflectance"});
    b.type = BSDFDesc::Type::Diffuse;
    b.reflectance = p.get_color("reflectance", Color::Constant(0.5));
    check_color(p, "reflectance", b.reflectance);
    return b;
  }
  // roughconductor
  Plugin p(src_, node,
           {"distribution", "alpha", "alpha_u", "alpha_v", "specular_reflectance", "material", "sample_visible"});
  b.type = BSDFDesc::Type::RoughConductor;
  if (p.has("alpha_u") || p.has("alpha_v"))
    src_.fail(p.at(p.has("alpha_u") ? "alpha_u" : "alpha_v"),
              "anisotropic roughness (alpha_u/alpha_v) is not supported; use 'alpha'");
  // Mitsuba 3's default distribution is beckmann: require ggx explicitly so that a file renders
  // the same in both.
  const std::string dist = p.get_string("distribution", "beckmann");
  if (dist != "ggx") {
    src_.fail(p.has("distribution") ? p.at("distribution") : node,
              "roughconductor distribution '" + dist + "' is not supported (supported: ggx)" +
                  (p.has("distribution") ? ""
                                         : "; Mitsuba 3's default is beckmann, set "
                                           "<string name=\"distribution\" value=\"ggx\"/>"));
  }
  const std::string material = p.get_string("material", "none");
  if (material != "none")
    src_.fail(p.at("material"), "named conductor presets are not supported ('" + material +
                                    "'); use material=\"none\" and specular_reflectance");
  b.alpha = p.get_float("alpha", 0.1);
  if (!(b.alpha > 0)) src_.fail(p.at("alpha"), "roughconductor alpha must be > 0");
  b.specular_reflectance = p.get_color("specular_reflectance", Color::Constant(1.0));
  check_color(p, "specular_reflectance", b.specular_reflectance);
  p.get_bool("sample_visible", true);  // a sampling strategy only: checked, no effect
  return b;
}

int Loader::resolve_ref(pugi::xml_node ref) {
  xml::check_attributes(src_, ref, {"id", "name"}, {"id"});
  const std::string id = ref.attribute("id").value();
  if (auto it = bsdf_ids_.find(id); it != bsdf_ids_.end()) return it->second;
  if (ids_.count(id)) src_.fail(ref, "<ref id=\"" + id + "\"> does not name a BSDF");
  src_.fail(ref, "<ref> to unknown id '" + id + "'");
}

int Loader::default_bsdf() {
  // Mitsuba 3 gives a shape without a BSDF a one-sided diffuse BSDF with reflectance 0.5.
  if (default_bsdf_ < 0) {
    scene_.bsdfs.push_back(BSDFDesc{});
    default_bsdf_ = int(scene_.bsdfs.size()) - 1;
  }
  return default_bsdf_;
}

// ---------------------------------------------------------------------------------------------
// Shapes
// ---------------------------------------------------------------------------------------------

TriangleMesh Loader::rectangle_mesh() const {
  // Mitsuba's rectangle: the square [-1,1]^2 in the z = 0 plane with normal +z.
  TriangleMesh m;
  m.positions = {Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)};
  m.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  return m;
}

void Loader::place_mesh(const Plugin& p, Shape& shape, const Mat4& to_world, bool flip) {
  const pugi::xml_node where = p.has("to_world") ? p.at("to_world") : p.node();
  if (!is_affine(to_world)) src_.fail(where, "to_world must be affine (last row 0 0 0 1)");
  const Mat3 linear = to_world.block<3, 3>(0, 0);
  const double det = linear.determinant();
  if (!(std::abs(det) > 0) || !std::isfinite(det)) src_.fail(where, "to_world is singular");
  TriangleMesh& mesh = shape.mesh;
  for (auto& x : mesh.positions) {
    x = linear * x + to_world.block<3, 1>(0, 3);
    if (!x.allFinite()) src_.fail(where, "to_world produces a non-finite vertex position");
    // Beyond kMaxCoordinate, Embree's float arithmetic overflows (qsil/scene.h).
    if (const double m = x.cwiseAbs().maxCoeff(); m > kMaxCoordinate) {
      char value[32];
      std::snprintf(value, sizeof value, "%.6g", m);
      src_.fail(where, std::string("to_world moves a vertex to coordinate magnitude ") + value +
                           ", beyond the largest supported magnitude 1e12");
    }
  }
  // A mirroring to_world (det < 0) reverses the winding; undo it so that counter-clockwise stays
  // the side the transformed normals point to (docs/architecture.md §3). flip_normals reverses it on purpose.
  if ((det < 0) != flip)
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  // Transformed triangles can become degenerate (e.g. a tiny scale): drop and count them.
  std::vector<Eigen::Vector3i> kept;
  for (int f = 0; f < mesh.num_triangles(); ++f)
    if (mesh.area(f) > 0) kept.push_back(mesh.triangles[f]);
  if (kept.empty()) src_.fail(where, "every triangle of the shape has zero area after to_world");
  if (kept.size() != mesh.triangles.size()) {
    warn(p.node(),
         "dropped " + std::to_string(mesh.triangles.size() - kept.size()) + " zero-area triangle(s) after to_world");
    mesh.triangles = std::move(kept);
  }
}

void Loader::parse_shape(pugi::xml_node node) {
  check_type(src_, node, {"obj", "rectangle"});
  register_id(node);
  Shape shape;
  shape.id = node.attribute("id").value();
  shape.type = node.attribute("type").value();
  shape.source = src_.where(node);
  const std::set<std::string> nested = {"bsdf", "ref", "emitter"};
  std::optional<Plugin> plugin;
  if (shape.type == "obj") {
    plugin.emplace(src_, node, std::set<std::string>{"filename", "to_world", "face_normals", "flip_normals"}, nested);
  } else {
    plugin.emplace(src_, node, std::set<std::string>{"to_world", "flip_normals"}, nested);
  }
  const Plugin& p = *plugin;
  const Mat4 to_world = p.get_transform("to_world").value_or(Mat4::Identity());
  const bool flip = p.get_bool("flip_normals", false);

  if (shape.type == "obj") {
    if (!p.has("filename")) p.fail("obj shape needs <string name=\"filename\" .../>");
    const std::string filename = p.get_string("filename", "");
    const std::filesystem::path path = src_.resolve(filename);
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) src_.fail(p.at("filename"), "file not found: " + path.string());
    std::vector<std::string> obj_warnings;
    try {
      shape.mesh = load_obj(path, /*weld=*/true, &obj_warnings);
    } catch (const Error& e) { src_.fail(p.at("filename"), e.what()); }
    for (const auto& w : obj_warnings) warn(p.at("filename"), w);
    place_mesh(p, shape, to_world, flip);
    // Mitsuba computes vertex normals of an OBJ without normals after applying to_world; qsil
    // welds, so its normals are always these (area-weighted) ones.
    shape.face_normals = p.get_bool("face_normals", false);
    if (shape.face_normals)
      shape.mesh.normals.clear();
    else
      shape.mesh.normals = vertex_normals(shape.mesh);
  } else {
    shape.mesh = rectangle_mesh();
    place_mesh(p, shape, to_world, flip);
    // Planar: every vertex normal is the face normal, the inverse transpose of +z.
    Vec3 n = (to_world.block<3, 3>(0, 0).inverse().transpose() * Vec3(0, 0, 1)).normalized();
    if (flip) n = -n;
    shape.mesh.normals.assign(shape.mesh.positions.size(), n);
  }

  // Nested BSDF (inline or <ref>) and area emitter.
  for (pugi::xml_node child : p.nested()) {
    const std::string tag = child.name();
    if (tag == "emitter") {
      parse_area_emitter(child, shape);
      continue;
    }
    if (shape.bsdf >= 0) src_.fail(child, "shape has more than one BSDF");
    shape.bsdf = tag == "ref" ? resolve_ref(child) : add_bsdf(child);
  }
  if (shape.bsdf < 0) shape.bsdf = default_bsdf();
  scene_.shapes.push_back(std::move(shape));
}

void Loader::parse_area_emitter(pugi::xml_node node, Shape& shape) {
  const std::string type = node.attribute("type").value();
  if (type == "envmap" || type == "constant")
    src_.fail(node, "a '" + type + "' emitter must be a child of <scene>, not of a <shape>");
  check_type(src_, node, {"area"});
  if (shape.is_emitter) src_.fail(node, "shape has more than one emitter");
  register_id(node);
  Plugin p(src_, node, {"radiance"});
  shape.is_emitter = true;
  shape.radiance = p.get_color("radiance", Color::Constant(1.0));
  check_color(p, "radiance", shape.radiance);
}

// ---------------------------------------------------------------------------------------------
// Environment
// ---------------------------------------------------------------------------------------------

/// The R, G, B planes of an EXR as an Image with channels {R, G, B}. Texels must be finite.
/// Negative texels (HDR captures carry small negative noise, e.g. down to -0.004 in
/// courtyard.exr) are clamped to 0, since radiance is non-negative and the map's sampling pdf must
/// be; `significant` counts those below -1% of the mean absolute texel value.
Image rgb_texels(const Source& src, pugi::xml_node where, const Image& img, const std::string& file,
                 long long& significant) {
  Image out;
  out.width = img.width;
  out.height = img.height;
  out.channel_names = {"R", "G", "B"};
  for (const char* c : {"R", "G", "B"}) {
    const int i = img.channel_index(c);
    if (i < 0) src.fail(where, file + ": env map has no channel '" + c + "' (needs R, G, B)");
    out.planes.push_back(img.planes[i]);
  }
  if (out.width <= 0 || out.height <= 0) src.fail(where, file + ": env map is empty");
  double mean_abs = 0;
  for (int c = 0; c < 3; ++c) {
    for (std::size_t k = 0; k < out.planes[c].size(); ++k) {
      const float v = out.planes[c][k];
      if (!std::isfinite(v)) {
        src.fail(where, file + ": env map texel (" + std::to_string(k % out.width) + ", " +
                            std::to_string(k / out.width) + ") channel " + out.channel_names[c] + " is not finite");
      }
      mean_abs += std::abs(v);
    }
  }
  mean_abs /= 3.0 * double(out.width) * double(out.height);
  significant = 0;
  for (auto& plane : out.planes) {
    for (float& v : plane) {
      if (v < 0) {
        if (v < -0.01 * mean_abs) ++significant;
        v = 0;
      }
    }
  }
  return out;
}

void Loader::parse_environment(pugi::xml_node node) {
  const std::string type = node.attribute("type").value();
  if (type == "area") src_.fail(node, "an area emitter must be nested in a <shape>");
  check_type(src_, node, {"envmap", "constant"});
  if (environment_)
    src_.fail(node,
              "more than one environment emitter (first at line " + std::to_string(src_.line(environment_)) + ")");
  environment_ = node;
  register_id(node);
  Environment& env = scene_.environment;
  if (type == "constant") {
    Plugin p(src_, node, {"radiance"});
    env.type = Environment::Type::Constant;
    env.radiance = p.get_color("radiance", Color::Constant(1.0));
    check_color(p, "radiance", env.radiance);
    return;
  }
  Plugin p(src_, node, {"filename", "scale", "to_world"});
  env.type = Environment::Type::EnvMap;
  if (!p.has("filename")) p.fail("envmap needs <string name=\"filename\" .../>");
  const std::filesystem::path path = src_.resolve(p.get_string("filename", ""));
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) src_.fail(p.at("filename"), "file not found: " + path.string());
  env.filename = path.string();
  env.scale = p.get_float("scale", 1.0);
  if (!(env.scale >= 0)) src_.fail(p.at("scale"), "envmap scale must be >= 0");
  if (const auto m = p.get_transform("to_world")) {
    const Mat3 r = m->block<3, 3>(0, 0);
    if (!is_affine(*m) || !is_orthogonal(r) || !(r.determinant() > 0))
      src_.fail(p.at("to_world"), "envmap to_world must be a rotation (no scale, shear or mirroring)");
    if (m->block<3, 1>(0, 3).norm() != 0)
      warn(p.at("to_world"), "envmap to_world translation has no effect (the map is at infinity)");
    env.to_world = r;
  }
  Image img;
  try {
    img = read_exr(path);
  } catch (const Error& e) { src_.fail(p.at("filename"), e.what()); }
  long long significant = 0;
  env.texels = rgb_texels(src_, p.at("filename"), img, path.string(), significant);
  if (significant > 0) {
    warn(p.at("filename"),
         "clamped " + std::to_string(significant) + " negative env map texel value(s) below -1% of the mean to 0");
  }
}

// ---------------------------------------------------------------------------------------------
// Sensor, film, sampler, integrator
// ---------------------------------------------------------------------------------------------

void Loader::parse_sensor(pugi::xml_node node) {
  check_type(src_, node, {"perspective"});
  if (sensor_) src_.fail(node, "more than one <sensor> (first at line " + std::to_string(src_.line(sensor_)) + ")");
  sensor_ = node;
  register_id(node);
  Plugin p(src_, node, {"fov", "fov_axis", "focal_length", "near_clip", "far_clip", "to_world"}, {"film", "sampler"});
  Camera& cam = scene_.camera;
  for (pugi::xml_node child : p.nested()) {
    if (std::string(child.name()) == "film")
      parse_film(child);
    else
      parse_sampler(child);
  }
  // Field of view: as Mitsuba 3 parse_fov(): `fov` along `fov_axis`, or else a 35 mm camera's
  // diagonal field of view for `focal_length` (default "50mm").
  if (p.has("fov") && p.has("focal_length")) p.fail("give either 'fov' or 'focal_length', not both");
  if (p.has("fov")) {
    cam.fov_deg = p.get_float("fov", 0.0);
    cam.fov_axis = p.get_string("fov_axis", "x");
    for (auto& c : cam.fov_axis) c = char(std::tolower(static_cast<unsigned char>(c)));
    const std::set<std::string> axes = {"x", "y", "diagonal", "smaller", "larger"};
    if (!axes.count(cam.fov_axis))
      src_.fail(p.at("fov_axis"), "fov_axis '" + cam.fov_axis + "' is not one of x, y, diagonal, smaller, larger");
    if (!(cam.fov_deg > 0 && cam.fov_deg < 180)) src_.fail(p.at("fov"), "fov must be in (0, 180) degrees");
  } else {
    if (p.has("fov_axis")) src_.fail(p.at("fov_axis"), "fov_axis needs 'fov'");
    std::string f = p.get_string("focal_length", "50mm");
    if (f.size() > 2 && f.substr(f.size() - 2) == "mm") f = f.substr(0, f.size() - 2);
    const pugi::xml_node where = p.has("focal_length") ? p.at("focal_length") : node;
    const double focal = xml::parse_double(src_, where, f, "focal_length");
    if (!(focal > 0)) src_.fail(where, "focal_length must be > 0");
    cam.fov_deg = 2.0 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * focal)) * 180.0 / kPi;
    cam.fov_axis = "diagonal";
  }
  const double x_fov = 2.0 * std::atan(cam.tan_half_fov().x()) * 180.0 / kPi;
  if (!(x_fov > 0 && x_fov < 180)) p.fail("the horizontal field of view must be in (0, 180) degrees");

  cam.near_clip = p.get_float("near_clip", 1e-2);
  if (!(cam.near_clip > 0)) src_.fail(p.at("near_clip"), "near_clip must be > 0");
  if (p.has("far_clip")) {
    const double far = p.get_float("far_clip", 1e4);
    if (!(far > cam.near_clip)) src_.fail(p.at("far_clip"), "far_clip must exceed near_clip");
    warn(p.at("far_clip"), "far_clip is ignored (camera rays are unbounded)");
  }
  if (const auto m = p.get_transform("to_world")) {
    if (!is_affine(*m) || !is_orthogonal(m->block<3, 3>(0, 0)))
      src_.fail(p.at("to_world"),
                "sensor to_world must be rigid (rotation and translation): it "
                "contains scale or shear");
    // The camera position is a ray origin: within kMaxCoordinate like the geometry (qsil/scene.h).
    const Vec3 position = m->block<3, 1>(0, 3);
    if (!position.allFinite() || position.cwiseAbs().maxCoeff() > kMaxCoordinate) {
      char value[32];
      std::snprintf(value, sizeof value, "%.6g", position.cwiseAbs().maxCoeff());
      src_.fail(p.at("to_world"), std::string("sensor position coordinate magnitude ") + value +
                                      " is beyond the largest supported magnitude 1e12");
    }
    cam.to_world = *m;
  }
}

void Loader::parse_film(pugi::xml_node node) {
  check_type(src_, node, {"hdrfilm"});
  Plugin p(src_, node, {"width", "height", "pixel_format", "component_format", "file_format"}, {"rfilter"});
  Camera& cam = scene_.camera;
  const long long w = p.get_integer("width", 768), h = p.get_integer("height", 576);
  if (w <= 0 || w > 1 << 16) src_.fail(p.at("width"), "film width must be in [1, 65536]");
  if (h <= 0 || h > 1 << 16) src_.fail(p.at("height"), "film height must be in [1, 65536]");
  cam.width = int(w);
  cam.height = int(h);
  // Output formats: qsil always writes float RGB EXR; the values are checked, not used.
  p.get_string("pixel_format", "rgb");
  p.get_string("component_format", "float32");
  p.get_string("file_format", "openexr");
  if (p.nested().size() > 1) src_.fail(p.nested()[1], "more than one <rfilter>");
  if (p.nested().empty()) {
    warn(node,
         "film has no <rfilter>: Mitsuba 3 would use a gaussian filter, qsil uses a box "
         "filter (add <rfilter type=\"box\"/>)");
  } else {
    const pugi::xml_node rf = p.nested().front();
    check_type(src_, rf, {"box"});
    Plugin(src_, rf, {});
  }
}

void Loader::parse_sampler(pugi::xml_node node) {
  check_type(src_, node, {"independent", "stratified", "multijitter", "orthogonal", "ldsampler"});
  Plugin p(src_, node, {"sample_count", "seed"});
  if (p.type() != "independent") warn(node, "sampler '" + p.type() + "' is rendered with independent samples (PCG32)");
  const long long spp = p.get_integer("sample_count", 4);
  if (spp <= 0 || spp > (1LL << 31) - 1) src_.fail(p.at("sample_count"), "sample_count must be > 0");
  scene_.camera.spp = int(spp);
  if (p.has("seed")) {
    p.get_integer("seed", 0);
    warn(p.at("seed"), "sampler seed is ignored (use the command line's --seed)");
  }
}

void Loader::parse_integrator(pugi::xml_node node) {
  check_type(src_, node, {"path"});
  if (integrator_)
    src_.fail(node, "more than one <integrator> (first at line " + std::to_string(src_.line(integrator_)) + ")");
  integrator_ = node;
  Plugin p(src_, node, {"max_depth", "rr_depth", "hide_emitters"});
  const long long depth = p.get_integer("max_depth", -1);
  if (depth < -1 || depth > 1 << 20) src_.fail(p.at("max_depth"), "max_depth must be -1 or >= 0");
  scene_.max_depth = int(depth);
  if (p.has("rr_depth")) {
    p.get_integer("rr_depth", 5);
    warn(p.at("rr_depth"), "rr_depth is ignored (qsil does not use Russian roulette)");
  }
  if (p.get_bool("hide_emitters", false)) src_.fail(p.at("hide_emitters"), "hide_emitters=true is not supported");
}

// ---------------------------------------------------------------------------------------------
// The scene
// ---------------------------------------------------------------------------------------------

void Loader::load() {
  const pugi::xml_node root = src_.root();
  if (std::string(root.name()) != "scene")
    src_.fail(root, "the root element must be <scene>, not <" + std::string(root.name()) + ">");
  xml::check_attributes(src_, root, {"version"}, {"version"});
  {
    const std::string version = root.attribute("version").value();
    const long long major = xml::parse_integer(src_, root, version.substr(0, version.find('.')), "version");
    if (major < 2)
      src_.fail(root, "scene version " + version +
                          " predates Mitsuba 2/3 (camelCase parameter "
                          "names); write it for version 3.x");
  }
  // Pass 1: top-level BSDFs, so that <ref> may point forward.
  for (pugi::xml_node child : root.children())
    if (child.type() == pugi::node_element && std::string(child.name()) == "bsdf") add_bsdf(child);
  // Pass 2: everything else, in document order.
  for (pugi::xml_node child : root.children()) {
    if (child.type() != pugi::node_element) continue;
    const std::string tag = child.name();
    if (tag == "default" || tag == "bsdf") continue;
    if (tag == "shape")
      parse_shape(child);
    else if (tag == "sensor")
      parse_sensor(child);
    else if (tag == "emitter")
      parse_environment(child);
    else if (tag == "integrator")
      parse_integrator(child);
    else
      src_.fail(child, "unsupported element <" + tag +
                           "> in <scene> (supported: default, sensor, shape, bsdf, emitter, integrator)");
  }
  if (!sensor_) src_.fail(root, "the scene has no <sensor>");
  const bool any_area =
      std::any_of(scene_.shapes.begin(), scene_.shapes.end(), [](const Shape& s) { return s.is_emitter; });
  if (scene_.shapes.empty() && scene_.environment.type == Environment::Type::None)
    src_.fail(root, "the scene has no shapes and no emitter");
  if (!any_area && scene_.environment.type == Environment::Type::None)
    warn(root, "the scene has no emitter: the image will be black");
}

}  // namespace

std::map<std::string, std::string> parse_defines(const std::vector<std::string>& defines) {
  std::map<std::string, std::string> out;
  for (const std::string& d : defines) {
    const auto eq = d.find('=');
    if (eq == std::string::npos || eq == 0) throw Error("-D '" + d + "': expected name=value");
    out[d.substr(0, eq)] = d.substr(eq + 1);
  }
  return out;
}

Scene load_scene(const std::filesystem::path& file, const std::map<std::string, std::string>& defaults,
                 std::vector<std::string>* warnings) {
  Source src(file);
  const pugi::xml_node root = src.root();

  // <default name value> entries (the first of a name wins, as in Mitsuba), then -D overrides.
  std::map<std::string, std::string> params;
  for (pugi::xml_node d : root.children("default")) {
    xml::check_attributes(src, d, {"name", "value"}, {"name", "value"});
    const std::string name = d.attribute("name").value();
    if (name.empty()) src.fail(d, "<default> needs a non-empty name");
    params.try_emplace(name, d.attribute("value").value());
  }
  for (const auto& [k, v] : defaults) params[k] = v;
  std::set<std::string> used;
  src.substitute(params, used);

  Scene scene;
  scene.file = file;
  Loader(src, scene, warnings).load();
  for (const auto& [k, v] : defaults) {
    if (!used.count(k) && warnings)
      warnings->push_back(file.string() + ": -D " + k + "=" + v + " has no effect: the scene does not use $" + k);
  }
  return scene;
}

}  // namespace qsil
