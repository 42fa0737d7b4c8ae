#pragma once
/// @file xml_plugin.h
/// Internal helper of the scene loader: the parameters and nested elements of one Mitsuba plugin
/// element (`<bsdf type="diffuse">`, `<shape type="obj">`, ...), checked strictly as pbrt-v4
/// does: a parameter the plugin does not know, a duplicate, or a value of the wrong type is a
/// `FILE:LINE:` error.

#include "xml_source.h"

#include "qsil/math.h"

#include <optional>
#include <set>
#include <string>
#include <vector>

namespace qsil::xml {

class Plugin {
 public:
  /// Collects the children of `node`, a plugin element of kind node.name() and type `type`.
  /// Property elements (<float>, <rgb>, <transform>, ...) must carry a name in `params`;
  /// nested elements must have a tag in `nested` (e.g. "bsdf", "ref", "emitter").
  Plugin(const Source& src, pugi::xml_node node, const std::set<std::string>& params,
         const std::set<std::string>& nested = {});

  pugi::xml_node node() const { return node_; }
  const std::string& type() const { return type_; }
  std::string id() const { return node_.attribute("id").value(); }
  /// Nested plugin elements and <ref> elements, in document order.
  const std::vector<pugi::xml_node>& nested() const { return nested_; }

  bool has(const std::string& name) const;
  /// The property element of a parameter (for locations); must exist.
  pugi::xml_node at(const std::string& name) const;

  double get_float(const std::string& name, double def) const;                    ///< <float> or <integer>
  long long get_integer(const std::string& name, long long def) const;            ///< <integer>
  bool get_bool(const std::string& name, bool def) const;                         ///< <boolean>
  std::string get_string(const std::string& name, const std::string& def) const;  ///< <string>
  /// <rgb value="r, g, b"> (or one value), <float>, or a constant <spectrum value="v">.
  Color get_color(const std::string& name, const Color& def) const;
  /// <transform name=...>: the local-to-world matrix, or nullopt when absent.
  std::optional<Mat4> get_transform(const std::string& name) const;

  /// Throws "FILE:LINE: message" at this plugin's element.
  [[noreturn]] void fail(const std::string& message) const { src_.fail(node_, message); }

 private:
  pugi::xml_node require(const std::string& name, std::initializer_list<const char*> tags) const;

  const Source& src_;
  pugi::xml_node node_;
  std::string type_;
  std::vector<std::pair<std::string, pugi::xml_node>> params_;
  std::vector<pugi::xml_node> nested_;
};

}  // namespace qsil::xml
