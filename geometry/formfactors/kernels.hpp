#pragma once
// Geometric kernels shared by the form-factor estimators (internal to geometry/).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

#include "geometry/mesh/mesh.hpp"
#include "geometry/polygon.hpp"

namespace lambert::ff {

/// An orthonormal frame (t, b, n) for unit n (Duff et al. 2017, branchless).
inline void orthonormal_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

/// (cos 2πv, sin 2πv) for v in [0, 1] without libm (glibc's sincos was 5 % of a gather
/// fill): θ = 2πv = q π/2 + x with q the nearest quarter turn and x = 2π (v - q/4) in
/// [-π/4, π/4] (v - q/4 is exact, Sterbenz), then Taylor polynomials in x² to x^15 and x^16,
/// whose truncation (x^17/17!, x^18/18!) is under 5e-17 there. Within 3 ulps of the correctly
/// rounded values (CosSinTurn.MatchesLongDouble); c² + s² = 1 to the same.
inline void cos_sin_turn(double v, double& c, double& s) {
  const int q = static_cast<int>(4.0 * v + 0.5);  // v >= 0: truncation rounds
  const double x = (v - 0.25 * q) * (2.0 * M_PI), x2 = x * x;
  // Taylor coefficients in x², highest first: sin x / x to x^14/15!, cos x to x^16/16!.
  constexpr double kSin[] = {-1.0 / 1307674368000, 1.0 / 6227020800, -1.0 / 39916800, 1.0 / 362880,
                             -1.0 / 5040,          1.0 / 120,        -1.0 / 6,        1.0};
  constexpr double kCos[] = {1.0 / 20922789888000,
                             -1.0 / 87178291200,
                             1.0 / 479001600,
                             -1.0 / 3628800,
                             1.0 / 40320,
                             -1.0 / 720,
                             1.0 / 24,
                             -1.0 / 2,
                             1.0};
  double sn = 0.0, cs = 0.0;
  for (const double k : kSin) sn = sn * x2 + k;
  for (const double k : kCos) cs = cs * x2 + k;
  sn *= x;
  const int quadrant = q & 3;  // θ = quadrant quarter turns + x
  c = quadrant == 0 ? cs : quadrant == 1 ? -sn : quadrant == 2 ? -cs : sn;
  s = quadrant == 0 ? sn : quadrant == 1 ? cs : quadrant == 2 ? -sn : -cs;
}

/// The cosine-distributed direction (density cos θ / π about n, frame (t, b, n)) of (u, v)
/// in [0,1)²: radius √u, angle 2π v on the unit disk, lifted to the hemisphere.
inline Eigen::Vector3d cosine_direction(const Eigen::Vector3d& n, const Eigen::Vector3d& t,
                                        const Eigen::Vector3d& b, double u, double v) {
  const double r = std::sqrt(u);
  const double z = std::sqrt(std::max(0.0, 1.0 - u));
  double c, s;
  cos_sin_turn(v, c, s);
  return (r * c) * t + (r * s) * b + z * n;
}

/// A patch's corners and frame, copied out of the mesh for cache-friendly pair loops.
struct PatchGeom {
  std::array<Eigen::Vector3d, 4> p;
  int n = 3;
  /// A quad whose opposite sides are equal vectors (patch_geometry: to 1e-12 of its
  /// diameter): sample_patch maps it linearly, with J = area (a rectangle of a meshed wall).
  /// False wherever a PatchGeom is built otherwise (cells, pieces): the bilinear map.
  bool parallelogram = false;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double area = 0.0;
  double diameter = 0.0;
  double warp = 0.0;  ///< quad_warp: how far rays' ends on this patch are lifted beyond the offset
};

/// geometry/polygon.hpp's quad_warp of a quad patch; 0 for triangles.
inline double quad_warp(const std::array<Eigen::Vector3d, 4>& p, int n,
                        const Eigen::Vector3d& normal) {
  return n == 4 ? lambert::quad_warp(p[0], p[1], p[2], p[3], normal) : 0.0;
}

/// How far a ray's end on patch g is lifted along its normal: the rays' offset (scene units)
/// plus the patch's warp. Planar patches: exactly `offset`.
inline double end_lift(const PatchGeom& g, double offset) { return offset + g.warp; }

/// Copies corners and frame of every patch.
std::vector<PatchGeom> patch_geometry(const PatchMesh& mesh);

/// True when the two patches can exchange energy: some corner of each lies strictly in
/// front of the other's plane (by more than `eps`, scene units).
bool can_exchange(const PatchGeom& a, const PatchGeom& b, double eps);

/// Maps (u, v) in [0,1)^2 to a point on the patch and returns the area density's inverse,
/// the weight J with ∫ f dA = E[f(x) J] for (u, v) uniform on the unit square.
/// Triangles: the parallelogram folded onto the triangle (2-to-1, so J = A);
/// quads: bilinear (J = |dx/du x dx/dv|, constant A for parallelograms: PatchGeom::parallelogram
/// takes it so, 14 % of an `mc` fill's time before).
inline Eigen::Vector3d sample_patch(const PatchGeom& g, double u, double v, double& jacobian) {
  if (g.parallelogram) {  // the bilinear map with its constant J, without a cross product
    jacobian = g.area;
    return g.p[0] + u * (g.p[1] - g.p[0]) + v * (g.p[3] - g.p[0]);
  }
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

/// Edges with (r_a · r_b)² >= kContourSeriesMin |r_a × r_b|² (seen under θ <= atan(1/4) =
/// 14°: every edge of a patch more than ~4 of its sizes away) take contour_edge_term's
/// series instead of atan2.
constexpr double kContourSeriesMin = 16.0;

/// Σ_{k=0}^{12} (-s)^k / (2k + 1) = atan(√s) / √s for 0 <= s <= 1/16, by Estrin's scheme
/// (latency of 5 multiply-adds instead of Horner's 12). The series alternates with falling
/// terms, so the truncation error is below the first term left out, s^13 / 27 <= 16^-13 / 27
/// = 8.3e-18, against a value >= atan(1/4) · 4 = 0.98: under 1e-17 relative, far below one
/// rounding (1.1e-16); its own rounding is a few ulps (every partial sum is a product with
/// s^k <= 1/16 added to a term of order 1).
inline double atan_ratio_series(double s) {
  const double s2 = s * s, s4 = s2 * s2, s8 = s4 * s4;
  const double p01 = 1.0 - s * (1.0 / 3), p23 = 1.0 / 5 - s * (1.0 / 7),
               p45 = 1.0 / 9 - s * (1.0 / 11), p67 = 1.0 / 13 - s * (1.0 / 15),
               p89 = 1.0 / 17 - s * (1.0 / 19), p1011 = 1.0 / 21 - s * (1.0 / 23);
  const double q0 = p01 + s2 * p23, q1 = p45 + s2 * p67, q2 = p89 + s2 * p1011;
  return (q0 + s4 * q1) + s8 * (q2 + s4 * (1.0 / 25));
}

/// atan(k / 16) for k = 0..16, correctly rounded (the table of atan2_upper).
inline constexpr double kAtanSixteenths[17] = {0.0,
                                               0.06241880999595735,
                                               0.12435499454676144,
                                               0.18534794999569476,
                                               0.24497866312686414,
                                               0.3028848683749714,
                                               0.35877067027057225,
                                               0.4124104415973873,
                                               0.4636476090008061,
                                               0.5123894603107377,
                                               0.5585993153435624,
                                               0.6022873461349642,
                                               0.6435011087932844,
                                               0.6823165548747481,
                                               0.7188299996216245,
                                               0.7531512809621944,
                                               0.7853981633974483};

/// atan2(y, x) for y > 0 (an angle in (0, π]) without libm, for contour_edge_term's near
/// edges (glibc's atan2 was a quarter of a CAD heat sink's form-factor time). With a =
/// min(y, |x|) / max(y, |x|) in [0, 1]: below 3/32, atan(a) = a atan_ratio_series(a²);
/// above, atan(a) = atan(c) + atan(v), c = k/16 the nearest sixteenth (k >= 2),
/// v = (a - c) / (1 + a c) with |v| <= 1/32; then π/2 - atan(a) when y > |x|, and π minus
/// that when x < 0. Error (u = 2^-53): a rounds by u (<= 1.28u of atan(a)); the series on
/// s <= 1/64 by <= 4.1u (one rounding per Estrin level, the rest weighted by s² <= 1e-4);
/// a - c is exact (Sterbenz), v rounds by <= 3u, so atan(v) by <= 8.1u, and |atan(v)| <=
/// 0.335 atan(a) (a >= 3/32), which makes atan(a) good to 5.2u (6.4u below 3/32); the two
/// reflections add 1.5u each: <= 9.4u in all (ContourKernel.Atan2UpperMatchesLongDouble).
/// Cost: two divisions and a degree-12 polynomial (~3x faster than glibc's atan2).
inline double atan2_upper(double y, double x) {
  const double ax = std::abs(x);
  const bool steep = y > ax;
  const double a = steep ? ax / y : y / ax;
  double t;
  if (a < 3.0 / 32) {
    t = a * atan_ratio_series(a * a);
  } else {
    const int k = static_cast<int>(16.0 * a + 0.5);
    const double c = k * (1.0 / 16), v = (a - c) / (1.0 + a * c);
    t = kAtanSixteenths[k] + v * atan_ratio_series(v * v);
  }
  if (steep) t = M_PI_2 - t;
  return x < 0.0 ? M_PI - t : t;
}

/// One edge's term of the contour sum, θ n · c / |c| with c = r_a × r_b and θ the angle
/// between r_a and r_b (0 for a degenerate edge, c = 0); dimensionless.
///
/// Edges seen under θ <= 14° (kContourSeriesMin: most of a meshed room's, few of a CAD
/// mesh's near sliver pairs, whose long edges are seen under larger angles) are evaluated
/// without atan2 or a square root: with d = r_a · r_b > 0 and t = |c| / d = tan θ,
/// θ / |c| = atan(t) / (t d) = atan_ratio_series(t²) / d, exact to under 1e-17 relative
/// (see there), so the term is exact to a few ulps as atan2's form is (both share the
/// rounding of c, which dominates when θ is small). Other edges (θ > 14°, near ones) take
/// atan2_upper(|c|, d) (<= 9.4u). Cost: one division and a degree-12 polynomial instead of a square
/// root, atan2 and a division (2.1x faster per contour sum measured on far patches). Pure,
/// thread-safe.
inline double contour_edge_term(const Eigen::Vector3d& nx, const Eigen::Vector3d& ra,
                                const Eigen::Vector3d& rb) {
  const Eigen::Vector3d c = ra.cross(rb);
  const double c2 = c.squaredNorm();
  if (!(c2 > 0.0)) return 0.0;
  const double d = ra.dot(rb);
  if (d > 0.0 && d * d >= kContourSeriesMin * c2) {
    const double q = 1.0 / d;
    return q * atan_ratio_series(c2 * q * q) * nx.dot(c);
  }
  const double cn = std::sqrt(c2);
  return atan2_upper(cn, d) * nx.dot(c) / cn;
}

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
