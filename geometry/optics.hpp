#pragma once
// Perfect specular optics shared by the extended form factors and the ray-traced view pass:
// mirror reflection, Snell refraction and the Fresnel reflectance of a dielectric interface
// (unpolarised light, exact for a smooth interface between two non-absorbing media).
// Directions are unit vectors; `n` is the unit normal on the side the ray arrives from
// (d · n < 0). All functions are pure and thread-safe.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "geometry/scene.hpp"

namespace lambert {

/// Mirror reflection of direction d about the normal n: d − 2 (d · n) n.
inline Eigen::Vector3d reflect(const Eigen::Vector3d& d, const Eigen::Vector3d& n) {
  return d - 2.0 * d.dot(n) * n;
}

/// Fresnel reflectance of unpolarised light arriving at cos_i = −d · n > 0 from a medium of
/// index n1 at one of index n2, with eta = n1 / n2:
///   sin t = eta sin i (total internal reflection when > 1: R = 1),
///   r_s = (eta cos i − cos t) / (eta cos i + cos t), r_p = (cos i − eta cos t) / (cos i + eta cos t),
///   R = (r_s² + r_p²) / 2.
/// At normal incidence R = ((1 − eta) / (1 + eta))² = ((n2 − n1) / (n2 + n1))².
inline double fresnel_dielectric(double cos_i, double eta) {
  cos_i = std::clamp(cos_i, 0.0, 1.0);
  const double sin2_t = eta * eta * std::max(0.0, 1.0 - cos_i * cos_i);
  if (sin2_t >= 1.0) return 1.0;
  const double cos_t = std::sqrt(1.0 - sin2_t);
  const double rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const double rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

/// Snell refraction of d through the interface with normal n (on d's side) and eta = n1 / n2:
/// t = eta d + (eta cos i − cos t) n. Returns false on total internal reflection.
inline bool refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double eta,
                    Eigen::Vector3d& t) {
  const double cos_i = -d.dot(n);
  const double sin2_t = eta * eta * std::max(0.0, 1.0 - cos_i * cos_i);
  if (sin2_t >= 1.0) return false;
  t = (eta * d + (eta * cos_i - std::sqrt(1.0 - sin2_t)) * n).normalized();
  return true;
}

/// A dielectric interface met by direction d at a face of unit front normal `front`: the
/// normal on d's side, eta = n1 / n2 (entering through the front: 1 / ior; leaving through
/// the back: ior) and the Fresnel reflectance R there.
struct Interface {
  Eigen::Vector3d normal;
  double eta = 1.0;
  double reflectance = 0.0;
  bool entering = true;  ///< the ray arrives at the front side
};

/// The interface a ray of direction d meets at a dielectric face (see Interface).
inline Interface dielectric_interface(const Eigen::Vector3d& d, const Eigen::Vector3d& front,
                                      double ior) {
  Interface out;
  out.entering = d.dot(front) < 0.0;
  out.normal = out.entering ? front : Eigen::Vector3d(-front);
  out.eta = out.entering ? 1.0 / ior : ior;
  out.reflectance = fresnel_dielectric(-d.dot(out.normal), out.eta);
  return out;
}

}  // namespace lambert
