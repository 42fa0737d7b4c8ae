#pragma once
/// @file wireframe.h
/// A tiny line rasteriser for `qsil candidates` ([QSS] Fig. 8): world-space segments projected
/// through a pinhole Camera (Camera::project: looks along +z of to_world, +x left, +y up; film
/// coordinates (0,0) top-left), clipped against the near plane, drawn with a DDA into an 8-bit
/// RGB canvas. No text: labels are drawn by the Python chart scripts.

#include "qsil/scene.h"

#include <array>
#include <filesystem>
#include <vector>

namespace qsil {

using Rgb = std::array<unsigned char, 3>;

/// An RGB canvas seen through a camera.
class WireframeCanvas {
 public:
  /// Canvas of camera.width x camera.height pixels filled with `background`.
  WireframeCanvas(const Camera& camera, const Rgb& background);
  /// Draws the segment a-b (world), `thickness` pixels wide (1..5); the part behind the camera's
  /// near plane is clipped.
  void line(const Vec3& a, const Vec3& b, const Rgb& color, int thickness = 1);
  /// Draws a filled disc of `radius` pixels at the projection of p (if in front of the camera).
  void dot(const Vec3& p, const Rgb& color, int radius);
  /// Film position (pixels) of a world point in front of the camera; false behind it.
  bool project(const Vec3& p, Vec2& film) const;
  /// Writes the canvas as PNG (atomically).
  void write(const std::filesystem::path& path) const;

 private:
  void plot(int x, int y, const Rgb& c, int thickness);
  Camera cam_;
  std::vector<unsigned char> rgb_;
};

/// A camera with the scene camera's image size and field of view that looks at the centre of
/// the scene's bounding box from the side of the scene camera (raised by 30 degrees), at a
/// distance where the bounding sphere fits: an overview for scenes whose camera misses objects
/// (spot-mirror sees Spot only in the mirror).
Camera overview_camera(const Scene& scene);

}  // namespace qsil
