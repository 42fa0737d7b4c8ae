/// @file parameters.cpp
/// Parameter parsing, velocities and exact displacements; see qsil/parameters.h.

#include "qsil/parameters.h"

#include "qsil/error.h"
#include "qsil/vertex_normals.h"

#include <tbb/parallel_for.h>

#include <sstream>

namespace qsil {

namespace {
std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream is(s);
  while (std::getline(is, cur, sep)) out.push_back(cur);
  if (!s.empty() && s.back() == sep) out.emplace_back();
  return out;
}

Vec3 parse_vec3(const std::string& s, const std::string& text, const char* what) {
  const auto parts = split(s, ',');
  if (parts.size() != 3) throw Error("--param '" + text + "': " + what + " must be X,Y,Z");
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    try {
      size_t used = 0;
      v[i] = std::stod(parts[i], &used);
      if (used != parts[i].size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw Error("--param '" + text + "': " + what + " component '" + parts[i] + "' is not a number");
    }
    if (!std::isfinite(v[i])) throw Error("--param '" + text + "': " + what + " is not finite");
  }
  return v;
}

/// Rodrigues rotation of x about unit axis a through c by angle.
Vec3 rotate_about(const Vec3& x, const Vec3& a, const Vec3& c, double angle) {
  return c + Eigen::AngleAxisd(angle, a) * (x - c);
}

}  // namespace

ParameterSpec parse_parameter(const std::string& text, const Scene& scene) {
  ParameterSpec p;
  p.text = text;
  const auto parts = split(text, ':');
  if (parts.size() < 2) throw Error("--param '" + text + "': expected ID:translate|rotate|scale|vertex:...");
  p.shape_id = parts[0];
  p.shape = scene.find_shape(p.shape_id);
  if (p.shape < 0)
    throw Error("--param '" + text + "': no shape with id '" + p.shape_id + "' in " + scene.file.string());
  std::string kind = parts[1];
  std::string center;
  if (auto at = kind.find('@'); at != std::string::npos) {  // ID:scale@C
    center = kind.substr(at + 1);
    kind = kind.substr(0, at);
  }
  auto take_center = [&](std::string& arg) {
    if (auto at = arg.find('@'); at != std::string::npos) {
      center = arg.substr(at + 1);
      arg = arg.substr(0, at);
    }
  };
  if (kind == "translate" || kind == "rotate") {
    if (parts.size() != 3) throw Error("--param '" + text + "': expected ID:" + kind + ":X,Y,Z");
    std::string arg = parts[2];
    if (kind == "rotate") take_center(arg);
    p.kind = kind == "translate" ? ParameterSpec::Kind::Translate : ParameterSpec::Kind::Rotate;
    p.direction = parse_vec3(arg, text, kind == "translate" ? "direction" : "axis");
    if (!(p.direction.norm() > 0))
      throw Error("--param '" + text + "': zero " + (kind == "translate" ? "direction" : "axis"));
    if (p.kind == ParameterSpec::Kind::Rotate) p.direction.normalize();
  } else if (kind == "scale") {
    if (parts.size() != 2) throw Error("--param '" + text + "': expected ID:scale[@CX,CY,CZ]");
    p.kind = ParameterSpec::Kind::Scale;
  } else if (kind == "vertex") {
    if (parts.size() != 4) throw Error("--param '" + text + "': expected ID:vertex:INDEX:X,Y,Z");
    p.kind = ParameterSpec::Kind::Vertex;
    try {
      size_t used = 0;
      p.vertex = std::stoi(parts[2], &used);
      if (used != parts[2].size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw Error("--param '" + text + "': vertex index '" + parts[2] + "' is not an integer");
    }
    const int nv = scene.shapes[p.shape].mesh.num_vertices();
    if (p.vertex < 0 || p.vertex >= nv)
      throw Error("--param '" + text + "': vertex index " + parts[2] + " out of range [0, " + std::to_string(nv) + ")");
    p.direction = parse_vec3(parts[3], text, "direction");
    if (!(p.direction.norm() > 0)) throw Error("--param '" + text + "': zero direction");
  } else {
    throw Error("--param '" + text + "': unknown kind '" + kind + "' (supported: translate, rotate, scale, vertex)");
  }
  if (!center.empty()) {
    if (p.kind != ParameterSpec::Kind::Rotate && p.kind != ParameterSpec::Kind::Scale)
      throw Error("--param '" + text + "': a centre @CX,CY,CZ applies to rotate and scale only");
    p.center = parse_vec3(center, text, "centre");
    if (p.center.cwiseAbs().maxCoeff() > kMaxCoordinate)
      throw Error("--param '" + text + "': centre coordinate beyond the largest supported magnitude 1e12");
    p.has_center = true;
  } else {
    p.center = scene.shapes[p.shape].mesh.bounds().center();
  }
  return p;
}

bool SceneVelocities::any_moving() const {
  for (bool m : moving)
    if (m) return true;
  return false;
}

void check_parameter_count(size_t count) {
  if (count < 1 || count > size_t(kMaxParameters))
    throw Error("--param: 1 to " + std::to_string(kMaxParameters) + " parameters per run (got " +
                std::to_string(count) + ")");
}

std::vector<ParameterSpec> parse_parameters(const std::vector<std::string>& specs, const Scene& scene) {
  check_parameter_count(specs.size());
  std::vector<ParameterSpec> params;
  for (const auto& s : specs) params.push_back(parse_parameter(s, scene));
  return params;
}

Vec3 vertex_velocity(const ParameterSpec& param, int vertex, const Vec3& x) {
  switch (param.kind) {
    case ParameterSpec::Kind::Translate: return param.direction;
    case ParameterSpec::Kind::Rotate: return param.direction.cross(x - param.center);
    case ParameterSpec::Kind::Scale: return x - param.center;
    case ParameterSpec::Kind::Vertex: return vertex == param.vertex ? param.direction : Vec3::Zero();
  }
  return Vec3::Zero();
}

SceneVelocities compute_velocities(const Scene& scene, const std::vector<ParameterSpec>& params) {
  check_parameter_count(params.size());
  SceneVelocities v;
  v.num_params = int(params.size());
  v.position.resize(scene.shapes.size());
  v.normal.resize(scene.shapes.size());
  v.moving.assign(scene.shapes.size(), false);
  // The arrays are zeroed, filled and lifted in parallel (per vertex; a million-vertex mesh's
  // arrays are hundreds of MB, whose first touch is most of their cost).
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const size_t n = scene.shapes[s].mesh.positions.size();
    v.position[s].resize(n);  // uninitialised (a fixed-size Eigen matrix), zeroed below
    v.normal[s].resize(n);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
      v.position[s][i].setZero();
      v.normal[s][i].setZero();
    });
  }
  for (size_t k = 0; k < params.size(); ++k) {
    const ParameterSpec& p = params[k];
    const TriangleMesh& mesh = scene.shapes[p.shape].mesh;
    auto& vel = v.position[p.shape];
    tbb::parallel_for(0, mesh.num_vertices(),
                      [&](int i) { vel[size_t(i)].col(k) = vertex_velocity(p, i, mesh.positions[size_t(i)]); });
    v.moving[p.shape] = true;
  }
  // Normal velocities: forward-mode derivative of the area-weighted vertex normals.
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    if (!v.moving[s] || scene.shapes[s].face_normals) continue;
    const TriangleMesh& mesh = scene.shapes[s].mesh;
    std::vector<Vec3T<Dual<kMaxParameters>>> pos(mesh.positions.size());
    tbb::parallel_for(size_t(0), pos.size(),
                      [&](size_t i) { pos[i] = lift<kMaxParameters>(mesh.positions[i], v.position[s][i]); });
    const auto n = vertex_normals_t(mesh, pos);
    for (size_t i = 0; i < n.size(); ++i)
      for (int r = 0; r < 3; ++r) v.normal[s][i].row(r) = n[i][r].derivatives().transpose();
  }
  return v;
}

std::vector<std::vector<Vec3>> displaced_positions(const Scene& scene, const std::vector<ParameterSpec>& params, int k,
                                                   double theta) {
  std::vector<std::vector<Vec3>> pos(scene.shapes.size());
  for (size_t s = 0; s < scene.shapes.size(); ++s) pos[s] = scene.shapes[s].mesh.positions;
  const ParameterSpec& p = params.at(k);
  auto& P = pos[p.shape];
  for (size_t i = 0; i < P.size(); ++i) {
    switch (p.kind) {
      case ParameterSpec::Kind::Translate: P[i] += theta * p.direction; break;
      case ParameterSpec::Kind::Rotate: P[i] = rotate_about(P[i], p.direction, p.center, theta); break;
      case ParameterSpec::Kind::Scale: P[i] = p.center + (1.0 + theta) * (P[i] - p.center); break;
      case ParameterSpec::Kind::Vertex:
        if (int(i) == p.vertex) P[i] += theta * p.direction;
        break;
    }
  }
  return pos;
}

Scene displaced_scene(const Scene& scene, const std::vector<ParameterSpec>& params, int k, double theta) {
  Scene out = scene;
  auto pos = displaced_positions(scene, params, k, theta);
  const int s = params.at(k).shape;
  out.shapes[s].mesh.positions = std::move(pos[s]);
  if (!out.shapes[s].face_normals) out.shapes[s].mesh.normals = vertex_normals(out.shapes[s].mesh);
  return out;
}

}  // namespace qsil
