/// @file camera_test.cpp
/// Camera::direction and Camera::tan_half_fov against Mitsuba 3's perspective conventions:
/// camera space looks along +z, +x is the image's left, +y its top; (0,0) is the top-left corner;
/// fov_axis converts as Mitsuba's parse_fov().

#include "qsil/scene.h"

#include <gtest/gtest.h>

#include <cmath>

namespace qsil {
namespace {

double deg(double radians) { return radians * 180.0 / kPi; }
double angle_between(const Vec3& a, const Vec3& b) { return deg(std::atan2(a.cross(b).norm(), a.dot(b))); }

Camera make_camera(int w, int h, double fov, const std::string& axis) {
  Camera c;
  c.width = w;
  c.height = h;
  c.fov_deg = fov;
  c.fov_axis = axis;
  return c;
}

TEST(CameraTest, CentreLooksAlongPlusZAndCornersAreUpLeft) {
  const Camera c = make_camera(200, 100, 60, "x");
  const Vec3 centre = c.direction(100, 50);
  EXPECT_NEAR((centre - Vec3(0, 0, 1)).norm(), 0, 1e-12);
  const Vec3 top_left = c.direction(0, 0);
  EXPECT_GT(top_left.x(), 0);  // +x is the image's left
  EXPECT_GT(top_left.y(), 0);  // +y is up, row 0 is the top
  const Vec3 bottom_right = c.direction(200, 100);
  EXPECT_LT(bottom_right.x(), 0);
  EXPECT_LT(bottom_right.y(), 0);
  EXPECT_NEAR(c.direction(37, 11).norm(), 1.0, 1e-12);
}

TEST(CameraTest, FovAxisX) {
  const Camera c = make_camera(200, 100, 60, "x");
  EXPECT_NEAR(angle_between(c.direction(0, 50), Vec3(0, 0, 1)), 30.0, 1e-9);
  EXPECT_NEAR(angle_between(c.direction(200, 50), Vec3(0, 0, 1)), 30.0, 1e-9);
  const Vec2 t = c.tan_half_fov();
  EXPECT_NEAR(t.x(), std::tan(kPi / 6), 1e-12);
  EXPECT_NEAR(t.y(), std::tan(kPi / 6) / 2.0, 1e-12);  // square pixels: tan_y = tan_x / aspect
}

TEST(CameraTest, FovAxisY) {
  const Camera c = make_camera(200, 100, 60, "y");
  EXPECT_NEAR(angle_between(c.direction(100, 0), Vec3(0, 0, 1)), 30.0, 1e-9);
  EXPECT_NEAR(c.tan_half_fov().x(), 2.0 * std::tan(kPi / 6), 1e-12);
}

TEST(CameraTest, FovAxisDiagonal) {
  const Camera c = make_camera(300, 100, 50, "diagonal");
  EXPECT_NEAR(angle_between(c.direction(0, 0), Vec3(0, 0, 1)), 25.0, 1e-9);
  EXPECT_NEAR(angle_between(c.direction(300, 100), Vec3(0, 0, 1)), 25.0, 1e-9);
}

TEST(CameraTest, FovAxisSmallerAndLarger) {
  // Landscape: the smaller axis is y, the larger x.
  const Camera ls = make_camera(200, 100, 40, "smaller");
  EXPECT_NEAR(angle_between(ls.direction(100, 0), Vec3(0, 0, 1)), 20.0, 1e-9);
  const Camera ll = make_camera(200, 100, 40, "larger");
  EXPECT_NEAR(angle_between(ll.direction(0, 50), Vec3(0, 0, 1)), 20.0, 1e-9);
  // Portrait: the smaller axis is x, the larger y.
  const Camera ps = make_camera(100, 200, 40, "smaller");
  EXPECT_NEAR(angle_between(ps.direction(0, 100), Vec3(0, 0, 1)), 20.0, 1e-9);
  const Camera pl = make_camera(100, 200, 40, "larger");
  EXPECT_NEAR(angle_between(pl.direction(50, 0), Vec3(0, 0, 1)), 20.0, 1e-9);
}

TEST(CameraTest, ToWorldRotatesAndIgnoresTranslation) {
  Camera c = make_camera(64, 64, 30, "x");
  // Camera turned to look along world -x: columns [left, up, dir, origin].
  c.to_world.block<3, 1>(0, 0) = Vec3(0, 0, -1);
  c.to_world.block<3, 1>(0, 1) = Vec3(0, 1, 0);
  c.to_world.block<3, 1>(0, 2) = Vec3(-1, 0, 0);
  c.to_world.block<3, 1>(0, 3) = Vec3(5, 6, 7);
  EXPECT_NEAR((c.direction(32, 32) - Vec3(-1, 0, 0)).norm(), 0, 1e-12);
  EXPECT_LT(c.direction(0, 32).z(), 0);  // image-left is the camera's left column
  EXPECT_EQ(c.origin(), Vec3(5, 6, 7));
}

TEST(CameraTest, LookatFromSceneFile) {
  // features.xml: lookat origin (0,0,5) target (0,0,0) up +y, fov 45 along y, 32x16.
  const Scene s = load_scene(std::string(QSIL_TEST_DATA_DIR) + "/scenes/features.xml");
  const Camera& c = s.camera;
  EXPECT_EQ(c.origin(), Vec3(0, 0, 5));
  const Vec3 centre = c.direction(c.width / 2.0, c.height / 2.0);
  EXPECT_NEAR((centre - Vec3(0, 0, -1)).norm(), 0, 1e-12);  // the centre looks at the target
  const Vec3 up(0, 1, 0), dir(0, 0, -1), left = up.cross(dir);
  const Vec3 tl = c.direction(0, 0);
  EXPECT_GT(tl.dot(up), 0);
  EXPECT_GT(tl.dot(left), 0);
  EXPECT_LT(left.x(), 0);  // looking down -z with +y up, the image's left is world -x
  EXPECT_NEAR(angle_between(c.direction(c.width / 2.0, 0), dir), 22.5, 1e-9);
}

}  // namespace
}  // namespace qsil
