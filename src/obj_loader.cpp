/// @file obj_loader.cpp
/// Wavefront OBJ loading through tinyobjloader (the only file that includes it), with welding by
/// position and area-weighted vertex normals. See load_obj() in qsil/scene.h.

#include "qsil/error.h"
#include "qsil/scene.h"
#include "qsil/vertex_normals.h"

// Coordinates in double (docs/architecture.md §3): float parsing flips near-flat edges on bob and teapot.
#define TINYOBJLOADER_USE_DOUBLE
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>

#include <tbb/parallel_sort.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <string_view>
#include <system_error>
#include <unordered_map>

namespace qsil {

std::vector<Vec3> vertex_normals(const TriangleMesh& mesh) { return vertex_normals_t<double>(mesh, mesh.positions); }

namespace {

/// Hash of a (position index, normal index) pair.
struct IndexPairHash {
  size_t operator()(const std::pair<int, int>& k) const {
    return std::hash<std::uint64_t>{}((std::uint64_t(std::uint32_t(k.first)) << 32) | std::uint32_t(k.second));
  }
};
/// tinyobjloader reads a literal `nan` or `inf` coordinate, or a word, as 0 and a missing one as 0;
/// scan the `v` lines of the file first (a read of its own; tinyobjloader's is the other) so that a
/// bad coordinate is an error naming its line and value, never a silently wrong mesh. Coordinates
/// beyond kMaxCoordinate are refused too (scene.h says why). A token is a number when strtod's
/// grammar (without hexadecimal forms) consumes all of it: std::from_chars, after an optional
/// leading '+'. Lines are split on '\n'; blanks are space, tab and '\r'.
void check_vertices(const std::filesystem::path& path, const std::string& name) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(name + ": cannot read the file");
  std::string buffer;
  for (int number = 1; std::getline(file, buffer); ++number) {
    const std::string_view line = buffer;
    size_t i = 0;
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i >= line.size() || line[i] != 'v') continue;
    ++i;  // `v` alone or `v` followed by blanks: a vertex line
    if (i < line.size() && !blank(line[i])) continue;
    const auto where = [&] { return name + ":" + std::to_string(number) + ": "; };
    int k = 0;
    for (; k < 3; ++k) {
      while (i < line.size() && blank(line[i])) ++i;
      if (i >= line.size()) break;
      const size_t start = i;
      while (i < line.size() && !blank(line[i])) ++i;
      const std::string_view token = line.substr(start, i - start);
      std::string_view digits = token;
      if (digits.size() > 1 && digits[0] == '+' && digits[1] != '+' && digits[1] != '-') digits.remove_prefix(1);
      double x = 0;
      const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), x);
      // Out of range: strtod's overflow (inf, refused below) or underflow (0, accepted).
      const bool range = ec == std::errc::result_out_of_range;
      if ((ec != std::errc() && !range) || ptr != digits.data() + digits.size())
        throw Error(where() + "vertex coordinate '" + std::string(token) + "' is not a number");
      if (range) x = std::strtod(std::string(digits).c_str(), nullptr);
      if (!std::isfinite(x)) throw Error(where() + "non-finite coordinate '" + std::string(token) + "' in a vertex");
      if (std::abs(x) > kMaxCoordinate)
        throw Error(where() + "vertex coordinate " + std::string(token) +
                    " exceeds the largest supported magnitude 1e12 (ray "
                    "tracing is in float)");
    }
    if (k < 3) throw Error(where() + "vertex has " + std::to_string(k) + " coordinate(s), expected 3");
  }
}

}  // namespace

TriangleMesh load_obj(const std::filesystem::path& path, bool weld, std::vector<std::string>* warnings) {
  const std::string name = path.string();
  if (!std::filesystem::exists(path)) throw Error(name + ": file not found");
  check_vertices(path, name);
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(name, config)) {
    std::string msg = reader.Error();
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == '\r')) msg.pop_back();
    if (auto nl = msg.find('\n'); nl != std::string::npos) msg = msg.substr(0, nl);
    throw Error(name + ": cannot parse OBJ" + (msg.empty() ? "" : ": " + msg));
  }
  const auto& attrib = reader.GetAttrib();
  const auto& shapes = reader.GetShapes();
  const size_t nv = attrib.vertices.size() / 3;
  for (size_t i = 0; i < attrib.vertices.size(); ++i)
    if (!std::isfinite(attrib.vertices[i]))
      throw Error(name + ": vertex " + std::to_string(i / 3 + 1) + " has a non-finite coordinate");
  const bool has_normals = !attrib.normals.empty() && !weld;

  TriangleMesh mesh;
  // Welding: identical positions map to one vertex, so that faces on either side of a UV or
  // normal seam share their edge (the edge forest needs mesh adjacency). Without welding, each
  // distinct (position, normal) index pair becomes a vertex.
  // Vertices are numbered in the order first met. Welding: the file's vertices sorted by position
  // (in parallel; ties by index), so that each run of equal positions (==: -0.0 and 0.0 alike)
  // names its first vertex as every member's representative; a face corner then finds its mesh
  // vertex by the representative's index.
  std::vector<int> representative, welded;
  if (weld) {
    const auto& xs = attrib.vertices;
    auto less = [&](int a, int b) {
      for (int c = 0; c < 3; ++c) {
        const double u = xs[3 * size_t(a) + c], v = xs[3 * size_t(b) + c];
        if (u < v) return true;
        if (v < u) return false;
      }
      return a < b;
    };
    auto same = [&](int a, int b) {
      return xs[3 * size_t(a)] == xs[3 * size_t(b)] && xs[3 * size_t(a) + 1] == xs[3 * size_t(b) + 1] &&
             xs[3 * size_t(a) + 2] == xs[3 * size_t(b) + 2];
    };
    std::vector<int> order(nv);
    std::iota(order.begin(), order.end(), 0);
    tbb::parallel_sort(order.begin(), order.end(), less);
    representative.resize(nv);
    for (size_t k = 0; k < nv;) {
      size_t j = k;
      while (j < nv && same(order[j], order[k])) representative[size_t(order[j++])] = order[k];
      k = j;
    }
    welded.assign(nv, -1);
  }
  std::unordered_map<std::pair<int, int>, int, IndexPairHash> by_pair;
  if (!weld) by_pair.reserve(nv);
  auto vertex_of = [&](const tinyobj::index_t& idx) -> int {
    if (idx.vertex_index < 0 || size_t(idx.vertex_index) >= nv)
      throw Error(name + ": face refers to vertex " + std::to_string(idx.vertex_index + 1) + " of " +
                  std::to_string(nv));
    const Vec3 p(attrib.vertices[3 * idx.vertex_index], attrib.vertices[3 * idx.vertex_index + 1],
                 attrib.vertices[3 * idx.vertex_index + 2]);
    if (weld) {
      int& v = welded[size_t(representative[size_t(idx.vertex_index)])];
      if (v < 0) {
        v = mesh.num_vertices();
        mesh.positions.push_back(p);
      }
      return v;
    }
    const int nidx = has_normals ? idx.normal_index : -1;
    auto [it, inserted] = by_pair.try_emplace({idx.vertex_index, nidx}, mesh.num_vertices());
    if (inserted) {
      mesh.positions.push_back(p);
      if (has_normals) {
        Vec3 n = nidx >= 0 ? Vec3(attrib.normals[3 * nidx], attrib.normals[3 * nidx + 1], attrib.normals[3 * nidx + 2])
                           : Vec3::Zero();
        mesh.normals.push_back(n);
      }
    }
    return it->second;
  };
  size_t corners = 0;
  for (const auto& shape : shapes) corners += shape.mesh.indices.size();
  mesh.triangles.reserve(corners / 3);
  size_t degenerate = 0;
  for (const auto& shape : shapes) {
    const auto& ids = shape.mesh.indices;
    for (size_t f = 0; f + 2 < ids.size(); f += 3) {
      Eigen::Vector3i tri(vertex_of(ids[f]), vertex_of(ids[f + 1]), vertex_of(ids[f + 2]));
      mesh.triangles.push_back(tri);
      if (!(mesh.area(mesh.num_triangles() - 1) > 0)) {
        mesh.triangles.pop_back();
        ++degenerate;
      }
    }
  }
  if (mesh.triangles.empty() && degenerate == 0) throw Error(name + ": OBJ has no faces");
  if (mesh.triangles.empty()) throw Error(name + ": every face of the OBJ has zero area");
  if (degenerate > 0 && warnings)
    warnings->push_back(name + ": dropped " + std::to_string(degenerate) + " zero-area triangle(s)");
  // Vertices only referenced by dropped faces stay in the array; they are harmless (unreferenced).
  bool normals_ok = has_normals;
  for (auto& n : mesh.normals) {
    const double len = n.norm();
    if (!(len > 0) || !std::isfinite(len)) {
      normals_ok = false;
      break;
    }
    n /= len;
  }
  if (!normals_ok) mesh.normals = vertex_normals(mesh);
  return mesh;
}

}  // namespace qsil
