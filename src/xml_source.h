#pragma once
/// @file xml_source.h
/// Internal helper of the scene loader (src/scene_loader.cpp): one parsed XML file with its
/// line numbers, `$name` substitution, and strict value parsing. Every failure throws qsil::Error
/// as `FILE:LINE: message` (docs/architecture.md §8). Only the scene loader's files include pugixml.

#include "qsil/math.h"

#include <pugixml.hpp>

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace qsil::xml {

/// A parsed XML document and the text it came from (for byte offset -> line conversion).
class Source {
 public:
  /// Reads and parses `file`. Throws "FILE: file not found" or "FILE:LINE: malformed XML: why".
  explicit Source(const std::filesystem::path& file);

  const std::filesystem::path& file() const { return file_; }
  pugi::xml_node root() const { return doc_.document_element(); }

  /// 1-based line of a node (0 when pugixml cannot tell).
  int line(pugi::xml_node node) const;
  /// "FILE:LINE" of a node, the prefix of every message about it.
  std::string where(pugi::xml_node node) const;
  /// Throws qsil::Error "FILE:LINE: message".
  [[noreturn]] void fail(pugi::xml_node node, const std::string& message) const;

  /// A path from the XML, relative to the XML file's folder unless absolute.
  std::filesystem::path resolve(const std::string& relative) const;

  /// Replaces every `$name` in every attribute value (except those of <default> elements) by
  /// params[name]. An undefined name throws "FILE:LINE: undefined parameter '$name'". Names that
  /// were used are added to `used`.
  void substitute(const std::map<std::string, std::string>& params, std::set<std::string>& used);

 private:
  int line_of_offset(std::ptrdiff_t offset) const;

  std::filesystem::path file_;
  std::string text_;
  std::vector<std::size_t> line_starts_;  // byte offset of the start of each line
  pugi::xml_document doc_;
};

/// Splits a list of numbers separated by commas and/or whitespace.
std::vector<std::string> split_list(const std::string& text);

/// Parses one finite floating-point number (the whole string). `what` names it in messages:
/// "FILE:LINE: cannot parse <what> 'text' as a number" or "...: non-finite <what> 'nan'".
double parse_double(const Source& src, pugi::xml_node node, const std::string& text, const std::string& what);
/// Parses a whole-string integer.
long long parse_integer(const Source& src, pugi::xml_node node, const std::string& text, const std::string& what);
/// Parses exactly `count` finite numbers (comma/space separated); with `allow_single`, one value
/// is repeated `count` times (Mitsuba's `<rgb value="0.5"/>`, `<scale value="2"/>`).
std::vector<double> parse_numbers(const Source& src, pugi::xml_node node, const std::string& text, std::size_t count,
                                  bool allow_single, const std::string& what);

/// Checks that `node` has only attributes from `allowed` and every one of `required`.
void check_attributes(const Source& src, pugi::xml_node node, const std::set<std::string>& allowed,
                      const std::set<std::string>& required = {});

/// Parses a <transform> element (children lookat, translate, rotate, scale, matrix; Mitsuba 3
/// order: each child pre-multiplies the matrix so far, M = child * M). Angles are in degrees.
/// Returns the 4x4 homogeneous matrix mapping local to world coordinates.
Mat4 parse_transform(const Source& src, pugi::xml_node transform);

}  // namespace qsil::xml
