#include "geometry/formfactors/visibility.hpp"

#include <algorithm>
#include <limits>

#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/quadrature.hpp"

namespace lambert::ff {
namespace {

// Solid angle of the spherical triangle of unit vectors a, b, c (Van Oosterom & Strackee
// 1983, stable for small triangles).
double solid_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double num = std::abs(a.dot(b.cross(c)));
  const double den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
  return 2.0 * std::atan2(num, den);
}

// Largest n · w over the spherical polygon of unit vectors w[0..m): at a vertex, at the
// top of an edge's great arc, or 1 when n points inside the polygon.
double max_cosine(const Eigen::Vector3d& n, const Eigen::Vector3d* w, int m) {
  double best = -1.0;
  bool inside = true;
  for (int k = 0; k < m; ++k) {
    const Eigen::Vector3d& a = w[k];
    const Eigen::Vector3d& b = w[(k + 1) % m];
    best = std::max(best, n.dot(a));
    const Eigen::Vector3d c = a.cross(b);
    const double cn = c.norm();
    if (cn <= 0.0) continue;
    const Eigen::Vector3d g = c / cn;  // pole of the edge's great circle
    inside = inside && n.dot(g) <= 0.0;
    const Eigen::Vector3d p = n - n.dot(g) * g;  // n projected onto the great circle's plane
    if (a.cross(p).dot(g) >= 0.0 && p.cross(b).dot(g) >= 0.0) best = std::max(best, p.norm());
  }
  // b's front faces x, so its corners run clockwise as seen from x and the inside of every
  // edge is where n · (w_k x w_k+1) < 0 (the sign convention of the contour formula).
  return inside ? 1.0 : std::min(1.0, best);
}

// A direction uniform in the solid angle of the spherical triangle (a, b, c) (Arvo 1995).
// The angle α at a enters only through its cosine and sine: cos α from the edge planes'
// normals, sin α from |(a x b) x (a x c)| = |a · (b x c)| (a is unit), and the sine and
// cosine of u1 · area - α by the angle-difference formulas from those of u1 · area (at most
// 2π: a fraction of a turn, cos_sin_turn), without acos, sin or cos (a third of the
// sampler's time in libm before).
Eigen::Vector3d arvo(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     double area, double u1, double u2) {
  const Eigen::Vector3d nab = a.cross(b), nac = a.cross(c);
  const double norms = std::max(nab.norm() * nac.norm(), 1e-300);
  const double cos_alpha = std::clamp(nab.dot(nac) / norms, -1.0, 1.0);
  const double sin_alpha = std::min(1.0, std::abs(a.dot(b.cross(c))) / norms);
  double cu, su;  // cos and sin of u1 · area
  cos_sin_turn(std::clamp(u1 * area / (2.0 * M_PI), 0.0, 1.0), cu, su);
  const double s = su * cos_alpha - cu * sin_alpha, t = cu * cos_alpha + su * sin_alpha;
  const double u = t - cos_alpha, v = s + sin_alpha * a.dot(b);
  const double den = (v * s + u * t) * sin_alpha;
  const double q =
      den != 0.0 ? std::clamp(((v * t - u * s) * cos_alpha - v) / den, -1.0, 1.0) : 1.0;
  const Eigen::Vector3d c_perp = c - c.dot(a) * a;
  const double cpn = c_perp.norm();
  const Eigen::Vector3d c_hat =
      cpn > 0.0 ? (q * a + std::sqrt(1.0 - q * q) * c_perp / cpn).eval() : a;
  const double z = std::clamp(1.0 - u2 * (1.0 - c_hat.dot(b)), -1.0, 1.0);
  const Eigen::Vector3d h_perp = c_hat - c_hat.dot(b) * b;
  const double hpn = h_perp.norm();
  return hpn > 0.0 ? (z * b + std::sqrt(1.0 - z * z) * h_perp / hpn).eval() : b;
}

}  // namespace

double clipped_factor(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, const PatchGeom& b) {
  ClippedCorners r;
  const int m = clip_to_horizon(x, nx, b, r);
  return m < 3 ? 0.0 : contour_factor(nx, r.data(), m);
}

KernelSampler::KernelSampler(const Eigen::Vector3d& x, const Eigen::Vector3d& nx,
                             const PatchGeom& b, bool with_factor)
    : x_(x), nx_(nx), nb_(b.normal), plane_(b.normal.dot(b.p[0])) {
  const double height = nb_.dot(x) - plane_;  // x's height above b's plane
  if (!(height > 0.0)) return;                // b's back faces x: nothing to receive
  ClippedCorners r;
  const int m = clip_to_horizon(x, nx, b, r);
  if (m < 3) return;
  // The contour sum costs about what the rest of the set-up does; hybrid's near pairs need
  // it only for the few pairs one of whose rays turns out unblocked.
  factor_ = std::numeric_limits<double>::quiet_NaN();
  if (with_factor) {
    factor_ = contour_factor(nx, r.data(), m);
    if (!(factor_ > 0.0)) return;
  }
  ClippedCorners w;
  for (int k = 0; k < m; ++k) w[k] = r[k].normalized();
  const double cos_max = max_cosine(nx, w.data(), m);
  // The fan's triangle areas, and the solid angle they subtend to first order (A cosθ / r²
  // at each centroid, cosθ = height / r): below kSmallSolidAngle, area sampling; above,
  // the exact solid angles (an atan2 each) for Arvo's sampling.
  std::array<double, kMaxClippedCorners - 2> measure{};
  double estimate = 0.0;
  for (int k = 0; k + 2 < m; ++k) {
    measure[k] = 0.5 * (r[k + 1] - r[0]).cross(r[k + 2] - r[0]).norm();
    const double rc = ((r[0] + r[k + 1] + r[k + 2]) / 3.0).norm();
    estimate += measure[k] * height / (rc * rc * rc);
  }
  area_mode_ = estimate < kSmallSolidAngle;
  double rmin = 0.0;
  if (area_mode_) {
    // K = cosθ_x cosθ_y / r² with cosθ_y = height / r and r >= distance to b. Area sampling
    // accepts with probability mean K / bound, mean K = π F(x -> b) / area. A sliver (a CAD
    // facet 100 mm long, 0.05 mm wide) subtends a small solid angle yet runs from near x to
    // many times as far, and K falls like 1/r³ along it: acceptance ~1e-4, 4096 tries per
    // ray and a give-up (issue 36). Below kMinAreaAcceptance its solid angle is sampled.
    rmin = std::max(distance_to_patch(x, b), height);
    if (!with_factor) {
      factor_ = contour_factor(nx, r.data(), m);
      if (!(factor_ > 0.0)) return;
    }
    double area = 0.0;
    for (int k = 0; k + 2 < m; ++k) area += measure[k];
    const double mean_k = M_PI * factor_ / area, bound = cos_max * height / (rmin * rmin * rmin);
    // Solid-angle sampling finds b's plane along every direction only when b is flat as
    // seen from x: each corner about `height` below x along n_b (not a warped quad's corners
    // on both sides of a point inside its warp).
    bool flat = true;
    for (int k = 0; k < m; ++k) flat = flat && -nb_.dot(r[k]) > 0.5 * height;
    area_mode_ = !(flat && mean_k < kMinAreaAcceptance * bound);
  }
  if (!area_mode_) {
    double total = 0.0;
    for (int k = 0; k + 2 < m; ++k) total += measure[k] = solid_angle(w[0], w[k + 1], w[k + 2]);
    if (!(total > 0.0)) return;
  }
  for (int k = 0; k < m; ++k) w_[k] = area_mode_ ? (x + r[k]).eval() : w[k];
  triangles_ = m - 2;
  for (int k = 0; k < triangles_; ++k) cdf_[k] = (k ? cdf_[k - 1] : 0.0) + measure[k];
  if (!(cdf_[triangles_ - 1] > 0.0)) {
    triangles_ = 0;
    return;
  }
  if (area_mode_) {
    bound_ = cos_max * height / (rmin * rmin * rmin);
  } else {
    bound_ = cos_max;
  }
}

Eigen::Vector3d KernelSampler::try_once(double u0, double u1, double u2, double& accept) const {
  const double pick = u0 * cdf_[triangles_ - 1];
  int t = 0;
  while (t + 1 < triangles_ && pick >= cdf_[t]) ++t;
  const Eigen::Vector3d &a = w_[0], &b = w_[t + 1], &c = w_[t + 2];
  if (area_mode_) {
    const double s = std::sqrt(u1);
    const Eigen::Vector3d y = (1.0 - s) * a + s * (1.0 - u2) * b + s * u2 * c;
    const Eigen::Vector3d d = y - x_;
    const double r2 = d.squaredNorm();
    accept = r2 > 0.0 ? nx_.dot(d) * -nb_.dot(d) / (r2 * r2) / bound_ : 0.0;
    return y;
  }
  const double area = cdf_[t] - (t ? cdf_[t - 1] : 0.0);
  const Eigen::Vector3d w = arvo(a, b, c, area, u1, u2);
  const double toward = -nb_.dot(w);
  accept = nx_.dot(w) / bound_;
  if (!(toward > 0.0)) {  // rounding at b's silhouette: step onto the plane from above
    accept = 0.0;
    return x_;
  }
  return x_ + (nb_.dot(x_) - plane_) / toward * w;
}

Eigen::Vector3d KernelSampler::sample(double u0, double u1, double u2, Rng& rng,
                                      bool& exhausted) const {
  exhausted = false;
  Eigen::Vector3d y = x_;
  for (int k = 0; k < kMaxTries; ++k) {
    double accept;
    y = try_once(u0, u1, u2, accept);
    if (rng.uniform() < accept) return y;
    u0 = rng.uniform();
    u1 = rng.uniform();
    u2 = rng.uniform();
  }
  exhausted = true;
  return y;
}

int count_visible(const Bvh& bvh, const Eigen::Vector3d& x, const Eigen::Vector3d& nx,
                  double x_lift, const PatchGeom& b, int rays, std::uint64_t stream, double offset,
                  int& exhausted) {
  const KernelSampler sampler(x, nx, b);
  if (sampler.empty()) return 0;
  const double y_lift = end_lift(b, offset);
  const Kronecker4 seq(stream);
  Rng rng(mix64(stream));
  int seen = 0;
  for (int r = 0; r < rays; ++r) {
    bool gave_up;
    const Eigen::Vector3d y =
        sampler.sample(seq.get(r, 0), seq.get(r, 1), seq.get(r, 2), rng, gave_up);
    exhausted += gave_up;
    seen += visible(bvh, x, nx, x_lift, y, b.normal, y_lift);
  }
  return seen;
}

}  // namespace lambert::ff
