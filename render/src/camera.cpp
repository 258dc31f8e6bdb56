// SPDX-License-Identifier: BSD-3-Clause
// render/src/camera.cpp -- perspective pinhole camera, look-at and Cinema orbits
#include "penumbra/render/camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "penumbra/core/error.h"

namespace penumbra::render {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

void check_view(const char* call, double fov_y_deg, int width, int height) {
  require(std::isfinite(fov_y_deg) && fov_y_deg > 0 && fov_y_deg < 180,
          std::string(call) + ": fov_y_deg = " + std::to_string(fov_y_deg) + "; expected 0 < fov < 180");
  require(width > 0 && height > 0, std::string(call) + ": image size " + std::to_string(width) + "x" +
                                       std::to_string(height) + "; expected positive width and height");
}

bool finite(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

Camera Camera::look_at(Vec3d eye, Vec3d target, Vec3d up, double fov_y_deg, int width, int height) {
  check_view("Camera::look_at", fov_y_deg, width, height);
  require(finite(eye) && finite(target) && finite(up), "Camera::look_at: eye, target and up must be finite");
  const Vec3d forward = target - eye;
  require(length(forward) > 0, "Camera::look_at: eye equals target; expected distinct points");
  require(length(cross(forward, up)) > 1e-12 * length(forward) * length(up),
          "Camera::look_at: up is zero or parallel to the view direction; expected a transverse up vector");
  Camera c;
  c.eye = eye;
  c.target = target;
  c.up = up;
  c.fov_y_deg = fov_y_deg;
  c.width = width;
  c.height = height;
  return c;
}

Camera Camera::orbit(const Bounds& bounds, double phi_deg, double theta_deg, double fov_y_deg, int width, int height) {
  check_view("Camera::orbit", fov_y_deg, width, height);
  require(!bounds.empty(), "Camera::orbit: bounds are empty; expected a mesh with points");
  require(std::isfinite(phi_deg) && std::isfinite(theta_deg) && theta_deg >= -90 && theta_deg <= 90,
          "Camera::orbit: theta = " + std::to_string(theta_deg) + "; expected finite phi and -90 <= theta <= 90");
  const double phi = phi_deg * kDegree, theta = theta_deg * kDegree;
  const Vec3d dir{std::cos(theta) * std::cos(phi), std::cos(theta) * std::sin(phi), std::sin(theta)};
  // The up vector is the derivative of dir with respect to theta: +z at the equator and still
  // well defined at the poles, where +z itself would be parallel to the view direction.
  const Vec3d up{-std::sin(theta) * std::cos(phi), -std::sin(theta) * std::sin(phi), std::cos(theta)};
  // The bounding sphere fits when its radius subtends at most half the narrower field of view.
  // Flat bounds (a single point) get a unit radius: any fixed length would be a world unit.
  const double diagonal = bounds.diagonal();
  const double radius = diagonal > 0 ? 0.5 * diagonal : 1.0;
  const double half_y = 0.5 * fov_y_deg * kDegree;
  const double half_x = std::atan(std::tan(half_y) * width / height);
  const double distance = radius / std::sin(std::min(half_x, half_y));
  return look_at(bounds.center() + dir * distance, bounds.center(), up, fov_y_deg, width, height);
}

Camera::Frame Camera::frame() const {
  Frame f;
  f.forward = normalize(target - eye);
  f.right = normalize(cross(f.forward, up));
  f.up = cross(f.right, f.forward);
  f.half_height = std::tan(0.5 * fov_y_deg * kDegree);
  f.half_width = f.half_height * width / height;
  return f;
}

Ray Camera::primary_ray(double px, double py) const { return primary_ray(frame(), px, py); }

Ray Camera::primary_ray(const Frame& f, double px, double py) const {
  const double x = (2.0 * (px + 0.5) / width - 1.0) * f.half_width;
  const double y = (1.0 - 2.0 * (py + 0.5) / height) * f.half_height;
  return {eye, normalize(f.forward + f.right * x + f.up * y)};
}

}  // namespace penumbra::render
