/// @file transform_parser.cpp
/// Mitsuba 3 `<transform>` elements: lookat, translate, rotate, scale and matrix, composed in
/// Mitsuba's order (each child pre-multiplies: M = child * M, so the first child acts first).
/// See parse_transform() in xml_source.h.

#include "qsil/scene.h"
#include "xml_source.h"

namespace qsil::xml {

namespace {

/// The three components of a Mitsuba vector element: either value="x, y, z" (or a single value
/// repeated) or the x/y/z attributes, each defaulting to `def`.
Vec3 xyz_of(const Source& src, pugi::xml_node node, double def, const std::string& what) {
  if (node.attribute("value")) {
    if (node.attribute("x") || node.attribute("y") || node.attribute("z"))
      src.fail(node, "<" + std::string(node.name()) + "> cannot mix 'value' with 'x'/'y'/'z'");
    const auto v = parse_numbers(src, node, node.attribute("value").value(), 3, true, what);
    return Vec3(v[0], v[1], v[2]);
  }
  Vec3 r = Vec3::Constant(def);
  const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    if (pugi::xml_attribute a = node.attribute(names[k]); a)
      r[k] = parse_double(src, node, a.value(), what + " " + names[k]);
  return r;
}

Vec3 named_vector(const Source& src, pugi::xml_node node, const char* name) {
  const auto v = parse_numbers(src, node, node.attribute(name).value(), 3, false, std::string("lookat ") + name);
  return Vec3(v[0], v[1], v[2]);
}

/// Mitsuba's Transform4f::look_at (qsil::look_at), with the checks that make it well defined.
Mat4 lookat(const Source& src, pugi::xml_node node) {
  check_attributes(src, node, {"origin", "target", "up"}, {"origin", "target"});
  const Vec3 origin = named_vector(src, node, "origin");
  const Vec3 target = named_vector(src, node, "target");
  const Vec3 to = target - origin;
  if (!(to.norm() > 0)) src.fail(node, "lookat: origin and target coincide");
  const Vec3 dir = to.normalized();
  // Without `up`, Mitsuba picks the first vector of coordinate_system(dir).
  Vec3 up = node.attribute("up") ? named_vector(src, node, "up") : Frame(dir).s;
  if (!(up.cross(dir).norm() > 1e-12 * up.norm()))
    src.fail(node, "lookat: 'up' is zero or parallel to the viewing direction");
  return look_at(origin, target, up);
}

Mat4 rotate(const Source& src, pugi::xml_node node) {
  check_attributes(src, node, {"x", "y", "z", "value", "axis", "angle"}, {"angle"});
  Vec3 axis;
  if (node.attribute("axis")) {
    if (node.attribute("value") || node.attribute("x") || node.attribute("y") || node.attribute("z"))
      src.fail(node, "<rotate> cannot mix 'axis' with 'value' or 'x'/'y'/'z'");
    const auto v = parse_numbers(src, node, node.attribute("axis").value(), 3, false, "rotate axis");
    axis = Vec3(v[0], v[1], v[2]);
  } else {
    axis = xyz_of(src, node, 0.0, "rotate axis");
  }
  if (!(axis.norm() > 0)) src.fail(node, "rotate: the axis is zero");
  const double angle = parse_double(src, node, node.attribute("angle").value(), "rotate angle");
  Mat4 m = Mat4::Identity();
  m.block<3, 3>(0, 0) = Eigen::AngleAxisd(angle * kPi / 180.0, axis.normalized()).toRotationMatrix();
  return m;
}

Mat4 matrix(const Source& src, pugi::xml_node node) {
  check_attributes(src, node, {"value"}, {"value"});
  const std::string text = node.attribute("value").value();
  const auto tokens = split_list(text);
  Mat4 m = Mat4::Identity();
  if (tokens.size() == 16) {
    const auto v = parse_numbers(src, node, text, 16, false, "matrix value");
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) m(i, j) = v[4 * i + j];  // row-major, as Mitsuba
  } else if (tokens.size() == 9) {
    const auto v = parse_numbers(src, node, text, 9, false, "matrix value");
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m(i, j) = v[3 * i + j];
  } else {
    src.fail(node, "matrix needs 16 (or 9) numbers, got " + std::to_string(tokens.size()));
  }
  return m;
}

}  // namespace

Mat4 parse_transform(const Source& src, pugi::xml_node transform) {
  Mat4 m = Mat4::Identity();
  for (pugi::xml_node child : transform.children()) {
    if (child.type() != pugi::node_element) continue;
    const std::string tag = child.name();
    Mat4 step = Mat4::Identity();
    if (tag == "lookat") {
      step = lookat(src, child);
    } else if (tag == "translate") {
      check_attributes(src, child, {"x", "y", "z", "value"});
      step.block<3, 1>(0, 3) = xyz_of(src, child, 0.0, "translate");
    } else if (tag == "scale") {
      check_attributes(src, child, {"x", "y", "z", "value"});
      step.block<3, 3>(0, 0) = xyz_of(src, child, 1.0, "scale").asDiagonal();
    } else if (tag == "rotate") {
      step = rotate(src, child);
    } else if (tag == "matrix") {
      step = matrix(src, child);
    } else {
      src.fail(child, "unsupported element <" + tag +
                          "> in <transform> (supported: lookat, translate, rotate, scale, matrix)");
    }
    m = step * m;
  }
  return m;
}

}  // namespace qsil::xml
