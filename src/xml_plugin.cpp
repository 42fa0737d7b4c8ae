/// @file xml_plugin.cpp
/// Strict parameter access for one Mitsuba plugin element. See xml_plugin.h.

#include "xml_plugin.h"

#include <algorithm>

namespace qsil::xml {

namespace {

const std::set<std::string> kPropertyTags = {"float",    "integer",   "boolean", "string", "rgb",
                                             "spectrum", "transform", "point",   "vector"};
// Mitsuba 3 object tags: known to Mitsuba, so a clearer message than "unknown element".
const std::set<std::string> kObjectTags = {"bsdf",    "emitter", "shape", "sensor", "film",       "sampler", "rfilter",
                                           "texture", "medium",  "phase", "volume", "integrator", "ref"};

std::string join(const std::set<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "none" : s;
}

}  // namespace

Plugin::Plugin(const Source& src, pugi::xml_node node, const std::set<std::string>& params,
               const std::set<std::string>& nested)
    : src_(src), node_(node), type_(node.attribute("type").value()) {
  check_attributes(src, node, {"type", "id", "name"}, {"type"});
  for (pugi::xml_node child : node.children()) {
    if (child.type() != pugi::node_element) continue;
    const std::string tag = child.name();
    if (kPropertyTags.count(tag)) {
      const std::string name = child.attribute("name").value();
      if (name.empty()) src.fail(child, "<" + tag + "> needs a 'name' attribute");
      if (!params.count(name)) {
        src.fail(child,
                 "unknown parameter '" + name + "' for plugin '" + type_ + "' (supported: " + join(params) + ")");
      }
      for (const auto& [n, prev] : params_) {
        if (n == name)
          src.fail(child,
                   "parameter '" + name + "' given twice (first at line " + std::to_string(src.line(prev)) + ")");
      }
      params_.emplace_back(name, child);
    } else if (nested.count(tag)) {
      nested_.push_back(child);
    } else if (kObjectTags.count(tag)) {
      src.fail(child, "<" + tag + "> is not supported inside <" + std::string(node.name()) + " type=\"" + type_ +
                          "\"> (supported: " + join(nested) + ")");
    } else {
      src.fail(child, "unsupported element <" + tag + "> in <" + std::string(node.name()) + ">");
    }
  }
}

bool Plugin::has(const std::string& name) const {
  return std::any_of(params_.begin(), params_.end(), [&](const auto& p) { return p.first == name; });
}

pugi::xml_node Plugin::at(const std::string& name) const {
  for (const auto& [n, node] : params_)
    if (n == name) return node;
  return node_;
}

pugi::xml_node Plugin::require(const std::string& name, std::initializer_list<const char*> tags) const {
  const pugi::xml_node node = at(name);
  const std::string tag = node.name();
  std::string expected;
  for (const char* t : tags) {
    if (tag == t) {
      if (tag != "transform") check_attributes(src_, node, {"name", "value"}, {"value"});
      return node;
    }
    expected += std::string(expected.empty() ? "" : " or ") + "<" + t + ">";
  }
  src_.fail(node, "parameter '" + name + "' of plugin '" + type_ + "' must be " + expected + ", not <" + tag + ">");
}

double Plugin::get_float(const std::string& name, double def) const {
  if (!has(name)) return def;
  const pugi::xml_node n = require(name, {"float", "integer"});
  return parse_double(src_, n, n.attribute("value").value(), "'" + name + "'");
}

long long Plugin::get_integer(const std::string& name, long long def) const {
  if (!has(name)) return def;
  const pugi::xml_node n = require(name, {"integer"});
  return parse_integer(src_, n, n.attribute("value").value(), "'" + name + "'");
}

bool Plugin::get_bool(const std::string& name, bool def) const {
  if (!has(name)) return def;
  const pugi::xml_node n = require(name, {"boolean"});
  std::string v = n.attribute("value").value();
  std::transform(v.begin(), v.end(), v.begin(), [](unsigned char c) { return std::tolower(c); });
  if (v == "true") return true;
  if (v == "false") return false;
  src_.fail(n, "boolean '" + name + "' must be \"true\" or \"false\", not \"" + n.attribute("value").value() + "\"");
}

std::string Plugin::get_string(const std::string& name, const std::string& def) const {
  if (!has(name)) return def;
  return require(name, {"string"}).attribute("value").value();
}

Color Plugin::get_color(const std::string& name, const Color& def) const {
  if (!has(name)) return def;
  const pugi::xml_node n = require(name, {"rgb", "float", "spectrum"});
  const std::string tag = n.name();
  const std::string text = n.attribute("value").value();
  if (tag == "rgb") {
    const auto v = parse_numbers(src_, n, text, 3, true, "'" + name + "'");
    return Color(v[0], v[1], v[2]);
  }
  if (tag == "spectrum" && split_list(text).size() != 1)
    src_.fail(n, "only a constant <spectrum> (one value) is supported for '" + name + "'");
  return Color::Constant(parse_double(src_, n, text, "'" + name + "'"));
}

std::optional<Mat4> Plugin::get_transform(const std::string& name) const {
  if (!has(name)) return std::nullopt;
  const pugi::xml_node n = require(name, {"transform"});
  check_attributes(src_, n, {"name"});
  return parse_transform(src_, n);
}

}  // namespace qsil::xml
