// The exact partial-shadow kernel (shadow.hpp) against closed forms and Monte Carlo.
#include "geometry/visibility/shadow.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "geometry/analytic.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

// Howell B-?: point factor from a point below one corner of a parallel rectangle a x b at
// height c: (1/2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))], X = a/c, Y = b/c.
double corner_factor(double a, double b, double c) {
  const double X = a / c, Y = b / c;
  const double sx = std::sqrt(1 + X * X), sy = std::sqrt(1 + Y * Y);
  return (X / sx * std::atan(Y / sx) + Y / sy * std::atan(X / sy)) / (2 * M_PI);
}

// Segment-triangle intersection (Moller-Trumbore), strictly inside the segment.
bool hits(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Polygon3& tri) {
  const Eigen::Vector3d e1 = tri[1] - tri[0], e2 = tri[2] - tri[0];
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return false;
  const Eigen::Vector3d s = o - tri[0];
  const double u = s.dot(p) / det;
  if (u < 0 || u > 1) return false;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) / det;
  if (v < 0 || u + v > 1) return false;
  const double t = e2.dot(q) / det;
  return t > 0 && t < 1;
}

struct McEstimate {
  double mean = 0, stderr_ = 0;
};

// Plain Monte Carlo of F = ∫_E V cosθx cosθy / (π r²) dA_y over a triangle or parallelogram
// emitter (uniform y), visibility against the blockers' fan triangles.
McEstimate monte_carlo(const Eigen::Vector3d& x, const Eigen::Vector3d& n, const Polygon3& emitter,
                       const std::vector<Polygon3>& blockers, int samples, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  const Eigen::Vector3d ne = newell_normal(emitter).normalized();
  const double area = polygon_area(emitter);
  std::vector<Polygon3> tris;
  for (const auto& b : blockers)
    for (size_t k = 1; k + 1 < b.size(); ++k) tris.push_back({b[0], b[k], b[k + 1]});
  double sum = 0, sum2 = 0;
  for (int i = 0; i < samples; ++i) {
    const double u = U(rng), v = U(rng);
    const Eigen::Vector3d y = emitter[0] + u * (emitter[1] - emitter[0]) + v * (emitter[3] - emitter[0]);
    const Eigen::Vector3d r = y - x;
    const double r2 = r.squaredNorm();
    const double cx = n.dot(r) / std::sqrt(r2), cy = -ne.dot(r) / std::sqrt(r2);
    double f = 0;
    if (cx > 0 && cy > 0) {
      bool blocked = false;
      for (const auto& t : tris) blocked = blocked || hits(x, r, t);
      if (!blocked) f = area * cx * cy / (M_PI * r2);
    }
    sum += f;
    sum2 += f * f;
  }
  const double mean = sum / samples;
  return {mean, std::sqrt(std::max(0.0, sum2 / samples - mean * mean) / (samples - 1))};
}

const Eigen::Vector3d kUp(0, 0, 1);

TEST(ShadowKernel, UnoccludedEqualsTheClosedForm) {
  // A point below a corner of a 2 x 1 rectangle at height 1.5 (facing down): Howell's
  // closed form, to rounding (the contour sum of 4 edges; 1e-14 relative).
  const Polygon3 rect{{0, 0, 1.5}, {0, 1, 1.5}, {2, 1, 1.5}, {2, 0, 1.5}};
  const double exact = corner_factor(2, 1, 1.5);
  EXPECT_NEAR(shadowed_point_factor({0, 0, 0}, kUp, rect, {}), exact, 1e-14 * exact);
  // A blocker beside the view pyramid, above x, behind the emitter or behind x's horizon
  // changes nothing.
  const std::vector<Polygon3> aside{{{3, 3, 1}, {4, 3, 1}, {4, 4, 1}},
                                    {{0, 0, 2}, {2, 0, 2}, {2, 1, 2}},
                                    {{-1, -1, -0.5}, {3, -1, -0.5}, {3, 2, -0.5}}};
  EXPECT_NEAR(shadowed_point_factor({0, 0, 0}, kUp, rect, aside), exact, 1e-14 * exact);
  // Behind the emitter's plane: 0.
  EXPECT_EQ(shadowed_point_factor({0, 0, 2}, kUp, rect, {}), 0.0);
}

TEST(ShadowKernel, UmbraIsExactlyZeroAndFullLightIsTheContourValue) {
  const PartialShadowGeometry g = partial_shadow_geometry();
  // Under the blocker's centre, the light is wholly hidden (umbra: x in [1.7, 2.7] etc.).
  EXPECT_EQ(shadowed_point_factor({2.2, 1.7, 0}, kUp, g.light, {g.blocker}), 0.0);
  // Far corner of the floor: the blocker hides nothing; the factor is the sum of four
  // corner rectangles' closed forms (signed), to rounding.
  const double x = 0.2, y = 3.8, H = 3;
  const double exact = corner_factor(2.5 - x, y - 1.5, H) - corner_factor(1.5 - x, y - 1.5, H) -
                       corner_factor(2.5 - x, y - 2.5, H) + corner_factor(1.5 - x, y - 2.5, H);
  EXPECT_NEAR(shadowed_point_factor({x, y, 0}, kUp, g.light, {g.blocker}), exact, 1e-13 * exact);
}

TEST(ShadowKernel, PenumbraAgreesWithMonteCarloWithinFourSigma) {
  // Points across the penumbra of the partial-shadow scene, and a tilted triangular blocker
  // and a tilted receiver: the MC estimate (1e5 samples, its own standard error sigma)
  // must be within 4 sigma (a 6e-5 two-sided chance per point for a correct kernel).
  const PartialShadowGeometry g = partial_shadow_geometry();
  const Polygon3 tilted{{1.2, 1.9, 0.7}, {2.9, 1.4, 2.2}, {2.0, 2.8, 1.1}};
  struct Case {
    Eigen::Vector3d x, n;
    std::vector<Polygon3> blockers;
  };
  const Eigen::Vector3d slanted = Eigen::Vector3d(0.3, -0.2, 1).normalized();
  std::vector<Case> cases = {
      {{1.2, 1.9, 0}, kUp, {g.blocker}},  {{3.2, 1.0, 0}, kUp, {g.blocker}},
      {{2.2, 0.5, 0}, kUp, {g.blocker}},  {{2.0, 2.4, 0}, kUp, {g.blocker}},
  };
  // For the tilted blocker (no closed form), penumbra points found along a line: those the
  // kernel puts between 20 % and 80 % of the unoccluded value (MC then checks the value).
  for (double t = 0.0; t <= 4.0 && cases.size() < 8; t += 0.05) {
    const Eigen::Vector3d x(t, 0.5 + 0.6 * t, 0);
    const Eigen::Vector3d nx = t < 2 ? kUp : slanted;
    const double fraction = shadowed_point_factor(x, nx, g.light, {g.blocker, tilted}) /
                            shadowed_point_factor(x, nx, g.light, {});
    if (fraction > 0.2 && fraction < 0.8) cases.push_back({x, nx, {g.blocker, tilted}});
  }
  ASSERT_EQ(cases.size(), 8u);
  int k = 0;
  for (const auto& c : cases) {
    const double exact = shadowed_point_factor(c.x, c.n, g.light, c.blockers);
    const McEstimate mc = monte_carlo(c.x, c.n, g.light, c.blockers, 100000, 7 + k++);
    EXPECT_GT(exact, 0.0);
    EXPECT_LT(exact, shadowed_point_factor(c.x, c.n, g.light, {}));  // partly hidden
    EXPECT_NEAR(exact, mc.mean, 4 * mc.stderr_) << "case " << k;
  }
}

TEST(ShadowKernel, ContactAndDegenerateBlockersDoNotBreakIt) {
  const PartialShadowGeometry g = partial_shadow_geometry();
  const Eigen::Vector3d x(2.001, 2.0, 0.0);
  const double open = shadowed_point_factor(x, kUp, g.light, {});
  // A wall standing on the receiver 1e-3 beside x (the D0 case: x in the contact shadow),
  // up to z = 2.9: it hides the light left of X_c = 2.001 - 0.001 x 3 / 2.9, where its top
  // edge projects. The rest is the rectangle [X_c, 2.5] x [1.5, 2.5]: the signed sum of
  // four corner closed forms (corner_factor is odd in each side), to rounding.
  const Polygon3 wall{{2, -1, 0}, {2, 5, 0}, {2, 5, 2.9}, {2, -1, 2.9}};
  const double a0 = -0.001 * 3 / 2.9, a1 = 2.5 - x.x(), b0 = -0.5, b1 = 0.5;
  const double rest = corner_factor(a1, b1, 3) - corner_factor(a0, b1, 3) -
                      corner_factor(a1, b0, 3) + corner_factor(a0, b0, 3);
  EXPECT_NEAR(shadowed_point_factor(x, kUp, g.light, {wall}), rest, 1e-13);
  // The wall through x itself hides nothing (every ray to the light leaves its plane).
  const Polygon3 through{{2.001, -1, 0}, {2.001, 5, 0}, {2.001, 5, 2.9}, {2.001, -1, 2.9}};
  EXPECT_NEAR(shadowed_point_factor(x, kUp, g.light, {through}), open, 1e-14);
  // A bow-tie (self-intersecting) blocker, a zero-area one and one of two points: finite,
  // in [0, open].
  const Polygon3 bowtie{{1.7, 1.7, 1}, {2.3, 2.3, 1}, {2.3, 1.7, 1}, {1.7, 2.3, 1}};
  const Polygon3 flat{{1.7, 1.7, 1}, {2.3, 2.3, 1}, {2.0, 2.0, 1}};
  const Polygon3 two{{1.7, 1.7, 1}, {2.3, 2.3, 1}};
  const double f = shadowed_point_factor(x, kUp, g.light, {bowtie, flat, two});
  EXPECT_GE(f, 0.0);
  EXPECT_LT(f, open);
  EXPECT_NEAR(shadowed_point_factor(x, kUp, g.light, {flat, two}), open, 1e-14);
}

TEST(ShadowKernel, PointsWithinRoundingOfTheEmitterPlaneSeeNothingAndNeverCrash) {
  // Regression: the analytic estimator's refined quadrature points next to a contact edge of
  // the Cornell box (mm coordinates, tilted walls) sat 1e-14 above the emitter's plane, where
  // the recomputed heights of clipped blocker corners exceed x's by rounding: the projection
  // divided by zero and GMP raised SIGFPE on the non-finite corner. A point that close sees
  // the emitter edge-on: its factor is 0 up to O(height / distance).
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d w = Eigen::Vector3d(0.3, 1.0, 0.2).normalized();
  const Eigen::Vector3d e1 = w.unitOrthogonal(), e2 = w.cross(e1);
  const Eigen::Vector3d c(400.0, 300.0, 500.0);  // Cornell-box magnitudes (mm)
  const Polygon3 emitter{c - 150 * e1 - 150 * e2, c + 150 * e1 - 150 * e2, c + 150 * e1 + 150 * e2,
                         c - 150 * e1 + 150 * e2};
  ASSERT_GT(newell_normal(emitter).dot(w), 0.0);
  for (int trial = 0; trial < 2000; ++trial) {
    // x beside the emitter (60 to 100 mm past its edge), within 1e-16 .. 1e-11 of the
    // coordinates' magnitude of its plane.
    const double height = std::pow(10.0, -16.0 + 5.0 * (0.5 + 0.5 * u(rng))) * c.norm();
    const Eigen::Vector3d x = c + (230 + 20 * u(rng)) * e1 + 100 * u(rng) * e2 + height * w;
    const Eigen::Vector3d n = (w + 0.5 * u(rng) * e1).normalized();
    // A plate crossing the emitter's plane between x and the emitter, at a random tilt.
    const Eigen::Vector3d m = c + (180 + 5 * u(rng)) * e1 + 30 * u(rng) * e2;
    const Eigen::Vector3d s = (e2 + 0.3 * u(rng) * e1).normalized(),
                          t = (w + 0.3 * u(rng) * e1).normalized();
    const Polygon3 plate{m - 80 * s - 40 * t, m + 80 * s - 40 * t, m + 80 * s + 40 * t,
                         m - 80 * s + 40 * t};
    const double f = shadowed_point_factor(x, n, emitter, {plate});
    ASSERT_TRUE(std::isfinite(f)) << trial;
    // F = (1/pi) ∫ cos cos' / r² dA with cos' = height / r <= height / 60 at the emitter
    // (x is >= 60 mm beside it) and ∫ cos dω <= pi: F <= height / 60 (+ rounding, 1e-15).
    EXPECT_LE(f, height / 60 + 1e-15) << trial << " height " << height;
    EXPECT_GE(f, 0.0);
  }
}

}  // namespace
}  // namespace lambert
