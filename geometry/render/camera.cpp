#include "geometry/render/camera.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "core/error.hpp"

namespace lambert {

Eigen::Vector3d Camera::ray_direction(double px, double py) const {
  const Eigen::Vector3d forward = (look_at - eye).normalized();
  const Eigen::Vector3d right = forward.cross(up).normalized();
  const Eigen::Vector3d true_up = right.cross(forward);
  const double half_h = std::tan(0.5 * vfov_degrees * M_PI / 180.0);
  const double half_w = half_h * static_cast<double>(width) / static_cast<double>(height);
  const double sx = (2.0 * px / width - 1.0) * half_w;
  const double sy = (1.0 - 2.0 * py / height) * half_h;
  return forward + sx * right + sy * true_up;
}

std::string camera_problem(const Camera& c) {
  const Eigen::Vector3d forward = c.look_at - c.eye;
  if (!(forward.norm() > 0) || !std::isfinite(forward.norm()))
    return "look_at must differ from eye (by a finite distance)";
  if (!(forward.normalized().cross(c.up.normalized()).norm() > 1e-6))
    return "up must not be zero or parallel to the view direction (look_at - eye)";
  return "";
}

Camera cornell_camera() {
  Camera c;
  c.eye = Eigen::Vector3d(278, 273, -800);
  c.look_at = Eigen::Vector3d(278, 273, 0);
  c.up = Eigen::Vector3d(0, 1, 0);
  c.vfov_degrees = 2.0 * std::atan(12.5 / 35.0) * 180.0 / M_PI;
  c.defined = true;
  return c;
}

Camera framing_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Camera c;
  const Eigen::Vector3d center = 0.5 * (lo + hi);
  const double radius = std::max(1e-12, 0.5 * (hi - lo).norm());
  c.vfov_degrees = 40.0;
  const double dist = radius / std::tan(0.5 * c.vfov_degrees * M_PI / 180.0) * 1.1;
  c.eye = center - Eigen::Vector3d(0, 0, dist);
  c.look_at = center;
  c.defined = true;
  return c;
}

namespace {

// The box framed from azimuth and elevation (degrees) about the `up` axis, from its front.
Camera orbit_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int up,
                    double azimuth_degrees, double elevation_degrees) {
  Camera c = framing_camera(lo, hi);
  const Eigen::Vector3d center = 0.5 * (lo + hi);
  const double dist = (c.eye - center).norm();
  const Eigen::Vector3d u = up == 2 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d front = up == 2 ? -Eigen::Vector3d::UnitY() : -Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d side = u.cross(front);  // front rotated 90° about u
  const double azimuth = azimuth_degrees * M_PI / 180.0;
  const double elevation = elevation_degrees * M_PI / 180.0;
  const Eigen::Vector3d dir =
      std::cos(elevation) * (std::cos(azimuth) * front + std::sin(azimuth) * side) +
      std::sin(elevation) * u;
  c.eye = center + dist * dir;
  // From straight above the up axis is the view direction: the picture's up is then the
  // back of the scene (its front at the bottom).
  c.up = elevation_degrees >= 90.0 ? Eigen::Vector3d(-front) : u;
  c.automatic = true;
  return c;
}

}  // namespace

Camera three_quarter_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int up) {
  return orbit_camera(lo, hi, up, 35.0, 30.0);
}

Camera room_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int up) {
  const Eigen::Vector3d center = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const Eigen::Vector3d u = up == 2 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d front = up == 2 ? -Eigen::Vector3d::UnitY() : -Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d corner = half.cwiseProduct(front + u.cross(front));  // horizontal
  Camera c;
  c.eye = center + 0.8 * corner + 0.15 * half.cwiseProduct(u);
  c.look_at = center - 0.5 * corner - 0.2 * half.cwiseProduct(u);
  c.up = u;
  c.vfov_degrees = 70.0;
  c.defined = true;
  c.automatic = true;
  return c;
}

Camera view_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int up,
                   const std::string& view) {
  if (view == "front") return orbit_camera(lo, hi, up, 0.0, 0.0);
  if (view == "top") return orbit_camera(lo, hi, up, 0.0, 90.0);
  LAMBERT_CHECK(view == "three-quarter", "view_camera: unknown view " + view);
  return three_quarter_camera(lo, hi, up);
}

}  // namespace lambert
