// SPDX-License-Identifier: BSD-3-Clause
#include "penumbra/render/camera.h"

#include <gtest/gtest.h>

#include <cmath>

#include "penumbra/core/error.h"

namespace penumbra::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(Camera, CentreRayLooksAtTargetAndTopRowLooksUp) {
  const auto cam = Camera::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 40, 101, 51);
  const Ray c = cam.primary_ray(50, 25);
  EXPECT_NEAR(c.direction.z, -1.0, 1e-15);
  EXPECT_NEAR(length(c.direction), 1.0, 1e-15);
  EXPECT_GT(cam.primary_ray(50, 0).direction.y, 0.0);   // py = 0 is the top row
  EXPECT_LT(cam.primary_ray(50, 50).direction.y, 0.0);
  EXPECT_GT(cam.primary_ray(100, 25).direction.x, 0.0);  // right is +x when looking down -z
  // The top edge of the top row's pixels sits at half the vertical field of view.
  const Ray edge = cam.primary_ray(50, -0.5);
  EXPECT_NEAR(std::atan2(edge.direction.y, -edge.direction.z), 20 * kPi / 180, 1e-12);
}

TEST(Camera, OrbitFollowsCinemaAngles) {
  Bounds b;
  b.extend({-1, -2, -3});
  b.extend({3, 2, 1});
  for (double phi : {0.0, 90.0, 215.0})
    for (double theta : {-90.0, -30.0, 0.0, 60.0, 90.0}) {
      const auto cam = Camera::orbit(b, phi, theta, 30, 64, 48);
      const Vec3d off = normalize(cam.eye - b.center());
      EXPECT_NEAR(off.z, std::sin(theta * kPi / 180), 1e-12);
      if (std::fabs(theta) < 90) EXPECT_NEAR(std::atan2(off.y, off.x), std::remainder(phi, 360.0) * kPi / 180, 1e-12);
      EXPECT_NEAR(length(cam.target - b.center()), 0.0, 1e-15);
      // The bounding sphere fits: it subtends at most half the vertical fov (the narrower one).
      const double r = 0.5 * b.diagonal();
      EXPECT_LE(std::asin(r / length(cam.eye - cam.target)), 15 * kPi / 180 + 1e-12);
      EXPECT_NO_THROW(cam.primary_ray(0, 0));
      EXPECT_TRUE(std::isfinite(cam.primary_ray(3, 7).direction.x));
    }
}

TEST(Camera, OrbitScalesWithTheBounds) {
  // The same view of a mesh at any size: the eye's distance is a multiple of the diagonal.
  Bounds unit;
  unit.extend({-1, -2, 0.5});
  unit.extend({3, 1, 2});
  const Camera reference = Camera::orbit(unit, 30, 20, 35, 64, 48);
  for (double s : {1e-18, 1e-12, 1e6, 1e18}) {
    Bounds scaled;
    scaled.extend(unit.lo * s);
    scaled.extend(unit.hi * s);
    const Camera c = Camera::orbit(scaled, 30, 20, 35, 64, 48);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(c.eye[a] / s, reference.eye[a], 1e-12 * length(reference.eye)) << s;
      EXPECT_NEAR(c.target[a] / s, reference.target[a], 1e-12 * length(reference.eye)) << s;
    }
  }
}

TEST(Camera, RejectsBadArguments) {
  EXPECT_THROW(Camera::look_at({0, 0, 0}, {0, 0, 0}, {0, 1, 0}, 30, 8, 8), Error);
  EXPECT_THROW(Camera::look_at({0, 0, 1}, {0, 0, 0}, {0, 0, 1}, 30, 8, 8), Error);
  EXPECT_THROW(Camera::look_at({0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 0, 8, 8), Error);
  EXPECT_THROW(Camera::look_at({0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 30, 0, 8), Error);
  EXPECT_THROW(Camera::orbit(Bounds{}, 0, 0, 30, 8, 8), Error);
  Bounds b;
  b.extend({0, 0, 0});
  EXPECT_THROW(Camera::orbit(b, 0, 91, 30, 8, 8), Error);
}

}  // namespace
}  // namespace penumbra::render
