#pragma once
// Geometric kernels shared by the form-factor estimators (internal to geometry/).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

#include "geometry/mesh/mesh.hpp"

namespace lambert::ff {

/// An orthonormal frame (t, b, n) for unit n (Duff et al. 2017, branchless).
inline void orthonormal_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

/// The cosine-distributed direction (density cos θ / π about n, frame (t, b, n)) of (u, v)
/// in [0,1)²: radius √u, angle 2π v on the unit disk, lifted to the hemisphere.
inline Eigen::Vector3d cosine_direction(const Eigen::Vector3d& n, const Eigen::Vector3d& t,
                                        const Eigen::Vector3d& b, double u, double v) {
  const double r = std::sqrt(u), phi = 2.0 * M_PI * v;
  const double z = std::sqrt(std::max(0.0, 1.0 - u));
  return r * std::cos(phi) * t + r * std::sin(phi) * b + z * n;
}

/// A patch's corners and frame, copied out of the mesh for cache-friendly pair loops.
struct PatchGeom {
  std::array<Eigen::Vector3d, 4> p;
  int n = 3;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double area = 0.0;
  double diameter = 0.0;
};

/// Copies corners and frame of every patch.
std::vector<PatchGeom> patch_geometry(const PatchMesh& mesh);

/// True when the two patches can exchange energy: some corner of each lies strictly in
/// front of the other's plane (by more than `eps`, scene units).
bool can_exchange(const PatchGeom& a, const PatchGeom& b, double eps);

/// Maps (u, v) in [0,1)^2 to a point on the patch and returns the area density's inverse,
/// the weight J with ∫ f dA = E[f(x) J] for (u, v) uniform on the unit square.
/// Triangles: the parallelogram folded onto the triangle (2-to-1, so J = A);
/// quads: bilinear (J = |dx/du x dx/dv|, constant A for parallelograms).
inline Eigen::Vector3d sample_patch(const PatchGeom& g, double u, double v, double& jacobian) {
  if (g.n == 3) {
    if (u + v > 1.0) {
      u = 1.0 - u;
      v = 1.0 - v;
    }
    jacobian = g.area;
    return g.p[0] + u * (g.p[1] - g.p[0]) + v * (g.p[2] - g.p[0]);
  }
  const Eigen::Vector3d du = (1 - v) * (g.p[1] - g.p[0]) + v * (g.p[2] - g.p[3]);
  const Eigen::Vector3d dv = (1 - u) * (g.p[3] - g.p[0]) + u * (g.p[2] - g.p[1]);
  jacobian = du.cross(dv).norm();
  return (1 - u) * (1 - v) * g.p[0] + u * (1 - v) * g.p[1] + u * v * g.p[2] + (1 - u) * v * g.p[3];
}

/// Like sample_patch but smooth in (u, v), for quadrature: triangles use the collapsed
/// (Duffy) map x = p0 + u (p1 - p0) + u v (p2 - p1), J = 2 A u; quads are bilinear.
inline Eigen::Vector3d quadrature_point(const PatchGeom& g, double u, double v,
                                        double& jacobian) {
  if (g.n == 3) {
    jacobian = 2.0 * g.area * u;
    return g.p[0] + u * (g.p[1] - g.p[0]) + u * v * (g.p[2] - g.p[1]);
  }
  return sample_patch(g, u, v, jacobian);
}

/// Most corners a patch keeps when clipped by a plane (clip_to_horizon): its corners in front
/// plus one point per edge the plane crosses. A plane crosses a planar convex quad on 2 edges
/// at most (5 corners), but a warped quad on all 4 when it passes within the warp of the
/// quad's plane (2 corners in front + 4 crossings): the OBJ loader keeps quads off their plane
/// by up to 1e-4 of their extent as quads, and a point of a neighbouring, nearly coplanar face
/// sees them that way (a hexagon, whose contour sum is still the factor of the loop).
constexpr int kMaxClippedCorners = 6;
/// The corners of a clipped patch, relative to the clipping point.
using ClippedCorners = std::array<Eigen::Vector3d, kMaxClippedCorners>;

/// The corners of patch g relative to x, clipped to the half-space in front of x
/// (n_x · r >= 0); writes them to `out` and returns their count (< 3: nothing).
int clip_to_horizon(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, const PatchGeom& g,
                    ClippedCorners& out);

/// Point-to-polygon form factor (Lambert's contour formula, exact):
///   F_{dx->P} = -(1/2π) Σ_k θ_k  n_x · (r_k × r_{k+1}) / |r_k × r_{k+1}|
/// with r_k = p_k - x and θ_k the angle between r_k and r_{k+1}. The polygon is first
/// clipped to the half-space in front of x (n_x · (y - x) > 0) so that the horizon is
/// respected, and is 0 when x lies behind the polygon's plane (only its front receives).
double point_to_patch(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, const PatchGeom& g);

/// The signed sum Σ_k θ_k n_x · (r_k × r_{k+1}) / |r_k × r_{k+1}| over one closed loop r[0..m)
/// (relative to x): -1/(2π) times it is the loop's factor, and loops add (holes wound
/// the other way subtract).
double contour_sum(const Eigen::Vector3d& nx, const Eigen::Vector3d* r, int m);

/// The contour sum of point_to_patch over a polygon already clipped to x's horizon, given
/// by its corners r[0..m) relative to x.
double contour_factor(const Eigen::Vector3d& nx, const Eigen::Vector3d* r, int m);

/// Highest Gauss-Legendre order available.
constexpr int kMaxGaussOrder = 32;

/// Gauss-Legendre nodes and weights on [0, 1] for orders 1..kMaxGaussOrder (thread-safe).
struct GaussRule {
  const double* x;
  const double* w;
  int n;
};
GaussRule gauss_legendre(int order);

}  // namespace lambert::ff
