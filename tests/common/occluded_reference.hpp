#pragma once
// High-accuracy reference values of occluded area-to-area view factors for tests.
//
// Everything here is independent of the engine's kernels: closed-form differential-element to
// rectangle factors (Howell's catalogue) are integrated over the emitter with tensor
// Gauss-Legendre rules on cells cut at every kink line, so that each cell's integrand is real
// analytic and the rule converges exponentially (orders 16..48 agree to ~1e-15).
// All G values are A_1 F_12 in length^2 units.
#include <algorithm>
#include <cmath>
#include <vector>

namespace lambert::ref {

constexpr double kPi = 3.14159265358979323846;

/// Axis-aligned rectangle [x0, x1] x [y0, y1] in a plane of constant z (or constant x).
struct Rect {
  double x0, x1, y0, y1;
};

/// Area of a rectangle; 0 when degenerate.
inline double rect_area(const Rect& r) {
  return std::max(0.0, r.x1 - r.x0) * std::max(0.0, r.y1 - r.y0);
}

/// Gauss-Legendre rule of `n` points (1 <= n <= 64) on [-1, 1]: nodes are the roots of the
/// Legendre polynomial P_n found by Newton's method from Tricomi's initial guess
/// cos(pi (i - 1/4) / (n + 1/2)), P_n and P_n' by the three-term recurrence; weights are
/// 2 / ((1 - x^2) P_n'(x)^2). Exact for polynomials of degree 2n - 1.
struct GaussRule {
  std::vector<double> x, w;
  explicit GaussRule(int n) : x(n), w(n) {
    for (int i = 0; i < (n + 1) / 2; ++i) {
      double t = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 1;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1, p1 = t;
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2 * k - 1) * t * p1 - (k - 1) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = n * (t * p1 - p0) / (t * t - 1);  // P_n'(t)
        const double dt = p1 / dp;
        t -= dt;
        if (std::abs(dt) < 1e-17) break;
      }
      x[i] = -t;
      x[n - 1 - i] = t;
      w[i] = w[n - 1 - i] = 2 / ((1 - t * t) * dp * dp);
    }
  }
};

/// Sorted break points of [lo, hi]: the ends, every cut strictly inside, and uniform
/// subdivision of each piece so none is longer than `max_len` (keeps the nearest complex
/// singularity of the integrand at least ~max_len away relative to the piece length).
inline std::vector<double> breaks(double lo, double hi, const std::vector<double>& cuts,
                                  double max_len) {
  std::vector<double> b{lo, hi};
  for (double c : cuts)
    if (c > lo && c < hi) b.push_back(c);
  std::sort(b.begin(), b.end());
  std::vector<double> out{lo};
  for (size_t i = 1; i < b.size(); ++i) {
    const double len = b[i] - b[i - 1];
    if (len <= 0) continue;
    const int m = std::max(1, static_cast<int>(std::ceil(len / max_len - 1e-9)));
    for (int j = 1; j <= m; ++j) out.push_back(j == m ? b[i] : b[i - 1] + len * j / m);
  }
  return out;
}

/// Tensor Gauss rule over the cells [xs[i], xs[i+1]] x [ys[j], ys[j+1]] of a grid:
/// sum over cells of the order x order product rule applied to f(x, y).
template <class F>
double integrate_grid(const std::vector<double>& xs, const std::vector<double>& ys,
                      const GaussRule& g, F&& f) {
  double total = 0;
  const size_t n = g.x.size();
  for (size_t i = 0; i + 1 < xs.size(); ++i) {
    const double xm = 0.5 * (xs[i] + xs[i + 1]), xr = 0.5 * (xs[i + 1] - xs[i]);
    for (size_t j = 0; j + 1 < ys.size(); ++j) {
      const double ym = 0.5 * (ys[j] + ys[j + 1]), yr = 0.5 * (ys[j + 1] - ys[j]);
      double cell = 0;
      for (size_t p = 0; p < n; ++p)
        for (size_t q = 0; q < n; ++q)
          cell += g.w[p] * g.w[q] * f(xm + xr * g.x[p], ym + yr * g.x[q]);
      total += cell * xr * yr;
    }
  }
  return total;
}

/// Howell B-3: factor from a differential element to a parallel rectangle at distance h with
/// one corner straight above the element and sides X, Y:
///   F = 1/(2 pi) [A/sqrt(1+A^2) atan(B/sqrt(1+A^2)) + B/sqrt(1+B^2) atan(A/sqrt(1+B^2))],
/// A = X/h, B = Y/h. F is odd in X and in Y, so signed X, Y are allowed (superposition).
inline double parallel_corner_F(double X, double Y, double h) {
  const double a = X / h, b = Y / h, sa = std::sqrt(1 + a * a), sb = std::sqrt(1 + b * b);
  return (a / sa * std::atan(b / sa) + b / sb * std::atan(a / sb)) / (2 * kPi);
}

/// Factor from the element at (x, y, 0) with normal +z to the rectangle r in the plane z = h
/// (facing it): signed superposition of the four corner factors of B-3. Real analytic in
/// (x, y); its nearest complex singularities lie at x = r.x0, r.x1 +- i h (same in y).
inline double parallel_point_F(double x, double y, const Rect& r, double h) {
  if (r.x1 <= r.x0 || r.y1 <= r.y0) return 0;
  return parallel_corner_F(r.x1 - x, r.y1 - y, h) - parallel_corner_F(r.x0 - x, r.y1 - y, h) -
         parallel_corner_F(r.x1 - x, r.y0 - y, h) + parallel_corner_F(r.x0 - x, r.y0 - y, h);
}

/// Unoccluded G = A_a F_ab between rectangle a at z = 0 (facing +z) and b at z = h (facing
/// -z): the B-3 point factor integrated over a. The integrand is analytic on all of a, so the
/// only cuts are a subdivision into pieces no longer than h.
inline double parallel_rectangles_G_ref(const Rect& a, const Rect& b, double h, int order = 32) {
  const GaussRule g(order);
  return integrate_grid(breaks(a.x0, a.x1, {}, h), breaks(a.y0, a.y1, {}, h), g,
                        [&](double x, double y) { return parallel_point_F(x, y, b, h); });
}

/// G = A_e F_er for emitter e at z = 0 (facing +z), receiver r in the parallel plane at
/// distance h (facing e) and an opaque rectangle `blk` in the parallel plane at distance d from
/// e (0 < d < h), all axis aligned in one (x, y) frame. From the emitter point x the blocker's
/// shadow on the receiver plane is S(x) = x + k (p - x), k = h / d, a rectangle, so the
/// visible factor is F_pt(x -> r) - F_pt(x -> r n S(x)), r n S(x) being a rectangle. Its edges
/// are max/min of receiver edges c and shadow edges k p + (1 - k) x, which switch (kink) or
/// make r n S(x) empty exactly at x = (c - k p) / (1 - k), and likewise in y; cutting e at all
/// of these leaves cells on which the active edges are fixed and the integrand is analytic,
/// with complex singularities at distance >= min(d, h) (pieces are subdivided to that length).
/// The reciprocal computation is parallel_blocked_G_general(r, e, h, blk, h - d, order).
inline double parallel_blocked_G_general(const Rect& e, const Rect& r, double h, const Rect& blk,
                                         double d, int order) {
  const double k = h / d;
  std::vector<double> cx, cy;
  for (double p : {blk.x0, blk.x1})
    for (double c : {r.x0, r.x1}) cx.push_back((c - k * p) / (1 - k));
  for (double p : {blk.y0, blk.y1})
    for (double c : {r.y0, r.y1}) cy.push_back((c - k * p) / (1 - k));
  const double len = std::min(d, h);
  const GaussRule g(order);
  return integrate_grid(
      breaks(e.x0, e.x1, cx, len), breaks(e.y0, e.y1, cy, len), g, [&](double x, double y) {
        const Rect s{
            std::max(r.x0, k * blk.x0 + (1 - k) * x), std::min(r.x1, k * blk.x1 + (1 - k) * x),
            std::max(r.y0, k * blk.y0 + (1 - k) * y), std::min(r.y1, k * blk.y1 + (1 - k) * y)};
        return parallel_point_F(x, y, r, h) - parallel_point_F(x, y, s, h);
      });
}

/// Emitter a at z = 0 (facing +z), receiver b at z = h (facing -z), opaque blocker rectangle at
/// z = hb (0 < hb < h): G = A_a F_ab with occlusion; see parallel_blocked_G_general (d = hb).
inline double parallel_blocked_G(const Rect& a, const Rect& b, double h, const Rect& blocker,
                                 double hb, int order) {
  return parallel_blocked_G_general(a, b, h, blocker, hb, order);
}

/// F_ab = G / A_a for parallel_blocked_G.
inline double parallel_blocked_F(const Rect& a, const Rect& b, double h, const Rect& blocker,
                                 double hb, int order) {
  return parallel_blocked_G(a, b, h, blocker, hb, order) / rect_area(a);
}

/// Factor from the element at (x0, y0, 0), x0 > 0, normal +z, to the rectangle
/// y in [y1, y2], z in [z1, z2] (0 <= z1 <= z2) of the wall x = 0 (normal +x): Howell's
/// "plane element to a rectangle in a plane at 90 deg", derived directly. From
/// F = (1/pi) iint x0 z / r^4 dy dz, r^2 = x0^2 + (y - y0)^2 + z^2, the z integral gives
/// (1/2)[1/(x0^2+eta^2) - 1/(x0^2+Z^2+eta^2)] and the y integral atan's, so with
/// H(Y, Z) = x0 / s atan(Y / s), s = sqrt(x0^2 + Z^2):
///   F = 1/(2 pi) [H(Y2,z1) - H(Y2,z2) - H(Y1,z1) + H(Y1,z2)],  Y_i = y_i - y0
/// (H is odd in Y, so any position along y is allowed; z1 = 0 gives atan(Y/x0) terms).
inline double perpendicular_point_F(double x0, double y0, double y1, double y2, double z1,
                                    double z2) {
  auto hf = [x0](double y, double z) {
    const double s = std::sqrt(x0 * x0 + z * z);
    return x0 / s * std::atan(y / s);
  };
  const double ya = y1 - y0, yb = y2 - y0;
  return (hf(yb, z1) - hf(yb, z2) - hf(ya, z1) + hf(ya, z2)) / (2 * kPi);
}

/// Floor [0,1]^2 at z = 0 (facing +z), wall x = 0, (y, z) in [0,1]^2 (facing +x), sharing the
/// edge x = z = 0, with an opaque plate on the plane x = z from that edge to x = z = c
/// (0 <= c < 1), y in [0, 1]. The segment from (x0, y0, 0) to (0, y', z) meets x = z at height
/// z x0 / (x0 + z), so it is blocked iff z <= z_min(x0) = c x0 / (x0 - c) (all of it if
/// x0 <= c): the visible wall is y' in [0,1], z in [z_min, 1], nonempty only for
/// x0 > L = c / (1 - c) (so G = 0 for c >= 1/2). G = A_floor F = integral over x0 in [L, 1],
/// y0 in [0, 1] of perpendicular_point_F(x0, y0, 0, 1, z_min, 1). For x0 > L the integrand is
/// analytic (no kinks: z_min is analytic there, and H depends on s only through s^2, so the
/// pole of z_min at x0 = c is no branch point); its complex singularities lie at x0 = c(1 +- i),
/// at x0 ~ c +- i c^2 / |Y| (where s^2 = -Y^2), i.e. ~c^2 from L, near x0 = 0, and at
/// y0 = 0, 1 +- i s with |s| >= ~x0. Cells: x0 graded geometrically towards L (pieces
/// [L + t, L + 2t] down to t ~ min(L, c^2) / 2), y0 graded towards both edges down to ~x0 / 2
/// per x0 strip, so every singularity is at least about a cell length away from its cell.
/// c = 0 gives the unoccluded perpendicular squares to ~1e-15 (the strip x0 < 1e-15 dropped).
inline double perpendicular_fin_G(double c, int order) {
  const double lo = c / (1 - c), gap = c * c / (1 - c);  // gap = L - c
  if (lo >= 1) return 0;
  std::vector<double> xs{lo, 1};
  const double stop = std::max(0.5 * std::min(lo, gap), 1e-15);
  for (double t = 0.5 * (1 - lo); t > stop; t *= 0.5) xs.push_back(lo + t);
  std::sort(xs.begin(), xs.end());
  const GaussRule g(order);
  double total = 0;
  for (size_t i = 0; i + 1 < xs.size(); ++i) {
    std::vector<double> ys{0, 0.5, 1};
    for (double t = 0.25; t > 0.5 * xs[i]; t *= 0.5) ys.insert(ys.end(), {t, 1 - t});
    std::sort(ys.begin(), ys.end());
    total += integrate_grid({xs[i], xs[i + 1]}, ys, g, [&](double x, double y) {
      const double z_min = c * x / (x - c);
      return z_min >= 1 ? 0.0 : perpendicular_point_F(x, y, 0, 1, z_min, 1);
    });
  }
  return total;
}

}  // namespace lambert::ref
