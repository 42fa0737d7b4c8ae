/// @file xml_source.cpp
/// A parsed XML scene file with line numbers, `$name` substitution and strict number parsing.
/// See xml_source.h.

#include "xml_source.h"

#include "qsil/error.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace qsil::xml {

Source::Source(const std::filesystem::path& file) : file_(file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw Error(file.string() + ": file not found");
  std::ifstream in(file, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  if (!in && !in.eof()) throw Error(file.string() + ": cannot read file");
  text_ = ss.str();
  line_starts_.push_back(0);
  for (std::size_t i = 0; i < text_.size(); ++i)
    if (text_[i] == '\n') line_starts_.push_back(i + 1);
  // Parse from our own copy, as UTF-8, so that pugixml's offsets are byte offsets into text_.
  const pugi::xml_parse_result result =
      doc_.load_buffer(text_.data(), text_.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!result) {
    throw Error(file.string() + ":" + std::to_string(line_of_offset(result.offset)) +
                ": malformed XML: " + result.description());
  }
  if (!doc_.document_element()) throw Error(file.string() + ":1: malformed XML: no root element");
}

int Source::line_of_offset(std::ptrdiff_t offset) const {
  if (offset < 0) return 0;
  const auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), std::size_t(offset));
  return int(it - line_starts_.begin());
}

int Source::line(pugi::xml_node node) const { return line_of_offset(node.offset_debug()); }

std::string Source::where(pugi::xml_node node) const {
  const int l = line(node);
  return l > 0 ? file_.string() + ":" + std::to_string(l) : file_.string();
}

void Source::fail(pugi::xml_node node, const std::string& message) const { throw Error(where(node) + ": " + message); }

std::filesystem::path Source::resolve(const std::string& relative) const {
  const std::filesystem::path p(relative);
  if (p.is_absolute()) return p;
  return file_.parent_path() / p;
}

namespace {

bool is_name_char(char c, bool first) {
  return c == '_' || std::isalpha(static_cast<unsigned char>(c)) ||
         (!first && std::isdigit(static_cast<unsigned char>(c)));
}

void substitute_node(const Source& src, pugi::xml_node node, const std::map<std::string, std::string>& params,
                     std::set<std::string>& used) {
  if (node.type() != pugi::node_element) return;
  if (std::string(node.name()) != "default") {
    for (pugi::xml_attribute attr : node.attributes()) {
      const std::string value = attr.value();
      if (value.find('$') == std::string::npos) continue;
      std::string out;
      for (std::size_t i = 0; i < value.size();) {
        if (value[i] != '$') {
          out += value[i++];
          continue;
        }
        std::size_t j = i + 1;
        while (j < value.size() && is_name_char(value[j], j == i + 1)) ++j;
        const std::string name = value.substr(i + 1, j - i - 1);
        if (name.empty())
          src.fail(node, "'$' not followed by a parameter name in attribute " + std::string(attr.name()) + "=\"" +
                             value + "\"");
        const auto it = params.find(name);
        if (it == params.end())
          src.fail(node, "undefined parameter '$" + name + "' (no <default name=\"" + name + "\"> and no -D " + name +
                             "=...)");
        used.insert(name);
        out += it->second;
        i = j;
      }
      attr.set_value(out.c_str());
    }
  }
  for (pugi::xml_node child : node.children()) substitute_node(src, child, params, used);
}

}  // namespace

void Source::substitute(const std::map<std::string, std::string>& params, std::set<std::string>& used) {
  substitute_node(*this, root(), params, used);
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : text) {
    if (c == ',' || std::isspace(static_cast<unsigned char>(c))) {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

double parse_double(const Source& src, pugi::xml_node node, const std::string& text, const std::string& what) {
  const char* begin = text.c_str();
  while (std::isspace(static_cast<unsigned char>(*begin))) ++begin;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  const char* rest = end;
  while (rest && std::isspace(static_cast<unsigned char>(*rest))) ++rest;
  if (end == begin || *rest != '\0') src.fail(node, "cannot parse " + what + " '" + text + "' as a number");
  if (!std::isfinite(v) || (errno == ERANGE && std::abs(v) > 1.0))
    src.fail(node, "non-finite " + what + " '" + text + "'");
  return v;
}

long long parse_integer(const Source& src, pugi::xml_node node, const std::string& text, const std::string& what) {
  const char* begin = text.c_str();
  while (std::isspace(static_cast<unsigned char>(*begin))) ++begin;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(begin, &end, 10);
  const char* rest = end;
  while (rest && std::isspace(static_cast<unsigned char>(*rest))) ++rest;
  if (end == begin || *rest != '\0' || errno == ERANGE)
    src.fail(node, "cannot parse " + what + " '" + text + "' as an integer");
  return v;
}

std::vector<double> parse_numbers(const Source& src, pugi::xml_node node, const std::string& text, std::size_t count,
                                  bool allow_single, const std::string& what) {
  const std::vector<std::string> tokens = split_list(text);
  if (tokens.size() != count && !(allow_single && tokens.size() == 1)) {
    src.fail(node,
             what + " needs " + (allow_single ? "1 or " : "") + std::to_string(count) + " numbers, got '" + text + "'");
  }
  std::vector<double> v;
  for (const auto& t : tokens) v.push_back(parse_double(src, node, t, what));
  while (v.size() < count) v.push_back(v.front());
  return v;
}

void check_attributes(const Source& src, pugi::xml_node node, const std::set<std::string>& allowed,
                      const std::set<std::string>& required) {
  for (pugi::xml_attribute attr : node.attributes()) {
    if (!allowed.count(attr.name()))
      src.fail(node, "unexpected attribute '" + std::string(attr.name()) + "' in <" + node.name() + ">");
  }
  for (const auto& r : required) {
    if (!node.attribute(r.c_str())) {
      std::string msg = "<";
      msg.append(node.name()).append("> needs attribute '").append(r).append("'");
      src.fail(node, msg);
    }
  }
}

}  // namespace qsil::xml
