#pragma once
/// @file environment_sun.h
/// The sun of an environment map: a small cone of directions holding a large share of the map's
/// power (a low sun in an HDRI sky). The light-aware edge importance [QSS 3.6] knows quad lights
/// and, through a bounding sphere, mesh emitters; an environment map enters it only through its
/// mean radiance, which spreads the sun's power over the whole sphere. Edges that cross the sun
/// as seen from a shading point (the outline of a sharp shadow) then get no more of the traversal
/// than any other, and the point on an edge is drawn without regard to it
/// (docs/architecture.md §5 "Importance", "The environment's sun").

#include "qsil/environment_light.h"
#include "qsil/math.h"

#include <optional>

namespace qsil {

/// A sun of an environment map, in the world frame.
struct EnvironmentSun {
  /// Unit world direction toward the sun (the direction one looks along to see it).
  Vec3 axis = Vec3::UnitZ();
  /// Radians: the cone about `axis` that holds every texel of the sun, texel extent included.
  double half_angle = 0;
  /// Luminance: the power of the map's texels whose centres lie in the cone, over its solid angle.
  double radiance = 0;
  /// That power over the whole map's power, in (0, 1].
  double share = 0;
};

/// A texel belongs to the sun when its luminance is at least kSunCoreRatio times the brightest
/// texel's and its centre lies within kSunSearchHalfAngle (20 degrees) of the brightest's.
inline constexpr double kSunCoreRatio = 0.01;
inline constexpr double kSunSearchHalfAngle = 20.0 * kPi / 180.0;
/// Largest half-angle of a sun (10 degrees): where the sun's texels reach further, the bright
/// region is sky or a large softbox, which the map's mean radiance already stands for.
inline constexpr double kSunMaxHalfAngle = 10.0 * kPi / 180.0;
/// The boundary term integrates along edges: an edge's arc of directions that crosses the sun
/// gathers about its mean radiance times its diameter, 2 half_angle, where one of the same map
/// without the sun gathers the mean radiance over the arc's length. A sun is a light of its own
/// where the first is at least kSunMinArcRatio times the mean radiance times pi (half a great
/// circle), by power: power inside the cone / solid angle x 2 half_angle >= ratio x power / 4.
inline constexpr double kSunMinArcRatio = 1.0;

/// The sun of `env`, or none: for a map (EnvironmentLight::width() > 0) whose brightest texel (the
/// first in row-major order among equals) has luminance > 0, the cone about the power-weighted mean
/// direction of the sun's texels (kSunCoreRatio, kSunSearchHalfAngle; texel centres) whose
/// half-angle is the largest angle to the centre of a sun texel plus that texel's angular radius
/// (half its diagonal in angle), kept where it is at most kSunMaxHalfAngle and passes
/// kSunMinArcRatio. Power: luminance times solid angle over the texels whose centres the cone
/// holds. None for a constant or absent environment. O(texels).
std::optional<EnvironmentSun> find_environment_sun(const EnvironmentLight& env);

}  // namespace qsil
