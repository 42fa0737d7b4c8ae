#pragma once
/// @file parameters.h
/// Geometry parameters theta_k and their per-vertex velocities dx/dtheta_k at theta = 0
/// (docs/architecture.md §2-§3). A parameter moves the vertices of one shape:
/// - `ID:translate:X,Y,Z`          x(theta) = x + theta * d            (d in scene units per unit theta)
/// - `ID:rotate:X,Y,Z[@CX,CY,CZ]`  rotation by theta radians about unit axis a through c
///                                 (default c: the shape's bounding-box centre); dx = a x (x - c)
/// - `ID:scale[@CX,CY,CZ]`         x(theta) = c + (1 + theta)(x - c)   (relative, uniform)
/// - `ID:vertex:INDEX:X,Y,Z`       vertex INDEX (0-based) moves by theta * d
/// Shading normals are area-weighted vertex normals of the moving mesh, so their velocities are
/// the derivatives of those normals (computed in forward mode once per render).

#include "qsil/dual.h"
#include "qsil/scene.h"

#include <string>
#include <vector>

namespace qsil {

/// One parsed parameter specification.
struct ParameterSpec {
  enum class Kind { Translate, Rotate, Scale, Vertex };
  std::string text;  ///< as given on the command line
  std::string shape_id;
  int shape = -1;  ///< resolved shape index
  Kind kind = Kind::Translate;
  Vec3 direction = Vec3::Zero();  ///< translate/vertex direction, or rotation axis (unit)
  Vec3 center = Vec3::Zero();     ///< rotate/scale centre (world)
  bool has_center = false;
  int vertex = -1;
};

/// Parses a `--param` spec and resolves it against the scene. Throws qsil::Error
/// "--param 'TEXT': reason" for an unknown shape id, a vertex index out of range, a zero
/// direction/axis, a centre beyond kMaxCoordinate (scene.h), or a malformed spec.
ParameterSpec parse_parameter(const std::string& text, const Scene& scene);

/// Checks that a run has 1 to kMaxParameters (8) parameters: the one place that does. Throws
/// qsil::Error "--param: 1 to 8 parameters per run (got N)" otherwise.
void check_parameter_count(size_t count);

/// Parses every `--param` spec against the scene (check_parameter_count, then parse_parameter).
/// Throws qsil::Error.
std::vector<ParameterSpec> parse_parameters(const std::vector<std::string>& specs, const Scene& scene);

/// Per-vertex velocities of all parameters, packed per vertex as a 3 x kMaxParameters matrix
/// (column k = dx/dtheta_k; columns >= num_params are zero).
struct SceneVelocities {
  using Block = Eigen::Matrix<double, 3, kMaxParameters>;
  int num_params = 0;
  std::vector<std::vector<Block>> position;  ///< [shape][vertex]: dx/dtheta
  std::vector<std::vector<Block>> normal;    ///< [shape][vertex]: d(shading normal)/dtheta
  std::vector<bool> moving;                  ///< [shape]: any non-zero velocity
  bool any_moving() const;
};

/// dx/dtheta at theta = 0 of vertex `vertex` (position `x`, world) of the parameter's shape: the
/// direction (translate; vertex, for its own vertex, else 0), axis x (x - centre) (rotate) or
/// x - centre (scale); world units per unit of theta. Shared by compute_velocities and
/// default_fd_step.
Vec3 vertex_velocity(const ParameterSpec& param, int vertex, const Vec3& x);

/// Velocities at theta = 0 of the given parameters (check_parameter_count). Throws qsil::Error.
SceneVelocities compute_velocities(const Scene& scene, const std::vector<ParameterSpec>& params);

/// The scene's vertex positions with parameter `k` set to `theta` (exact motion: a rotation by
/// the angle theta, not its linearisation), all other parameters at 0. Used by finite differences.
std::vector<std::vector<Vec3>> displaced_positions(const Scene& scene, const std::vector<ParameterSpec>& params, int k,
                                                   double theta);

/// A copy of `scene` whose vertices (and area-weighted shading normals) are displaced as above.
Scene displaced_scene(const Scene& scene, const std::vector<ParameterSpec>& params, int k, double theta);

}  // namespace qsil
