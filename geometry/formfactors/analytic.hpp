#pragma once
// Estimator "analytic": occluded area-to-area factors by exact point factors and adaptive
// quadrature (internal to geometry/).
//
//   G_ab = ∫_{A_a} F_{dx->b, visible}(x) dA_x        (scene units², = A_a F_ab = A_b F_ba)
//
// F_{dx->b, visible} is exact at every x up to rounding (b minus the cone from x over each
// convex blocker piece, each cone the intersection of the half-planes of its edges' lines on
// b's plane, split off in floating point into convex visible pieces; Lambert's contour
// formula on each piece). Pieces that form a closed convex solid (a box's faces, also one
// standing open on a plane both polygons stand on) give one cone, over the solid's
// silhouette from x, and its faces turned away from all of a are dropped.
// It is analytic in x except on the event lines where the visible polygon's combinatorics
// change: for a vertex v and an edge e of two different objects (b, blockers) the points x
// of a's plane on a line through v and e (EV events), the lines where a blocker's plane
// meets a's plane (the blocker seen edge-on), and contact lines (a blocker edge on a's
// plane). So a is cut along all of them (a CGAL constrained Delaunay triangulation with the
// event segments as constraints), and inside each triangle the integrand is analytic; EEE
// events (a vertex of the visible polygon made by three edges of three objects, curves on
// a) are not cut: there the adaptive refinement below converges algebraically.
//
// Per triangle, the visible pieces are computed once at its centroid, each corner recorded
// by what defines it (a corner of b, the crossing of two feature lines); the point factor is
// then evaluated from those features at every quadrature point (~1 µs). The pattern is
// verified against the pieces computed afresh at three inset corners of the triangle (value
// to 1e-10); where it fails, every point of that triangle is computed afresh (~10-50 µs with
// a few dozen blockers; the CGAL polygon booleans this replaced took ~1 ms).
//
// Quadrature: each triangle (collapsed Duffy map onto the unit square) gets tensor
// Gauss-Legendre rules of orders kLowOrder and kHighOrder; the value is the low-order sum
// and its error estimate |Q_high - Q_low| (the high rule is many times more accurate on an
// analytic integrand, so the estimate is the low rule's true error to a few per cent: it is
// calibrated, not merely an upper bound). The triangle with the largest estimate is split
// into four until the estimates sum to at most the tolerance, or an evaluation budget is
// spent (then `converged` is false). Cost: O(k² log k) event segments for k blockers, a
// CDT of them, then about 50 point factors per triangle (orders 4 and 6). Thread-safe (no
// shared state).
//
// At loose tolerances (tol_G >= 1e-6 of a's area) with two or more blocker pieces left, the
// event partition costs far more than the tolerance needs, so G is the unoccluded integral
// (one pattern everywhere) minus the hidden part by adaptive quadrature of fresh point
// factors without events: per cell only the blockers in its shaft to b, a cell with none
// exactly 0, cells split to their distance to the blockers before a rule is trusted, the
// value the order-6 sum and the estimate twice the plain sum of |Q_6 - Q_4| (a cell may hold
// a kink). A pair that spends 1e5 fresh point factors so is integrated along the events.

#include <cstdint>
#include <vector>

#include "geometry/polygon.hpp"

namespace lambert::ff {

/// The result of one analytic pair integral.
struct AnalyticEstimate {
  double G = 0.0;      ///< ∫_a F_{dx->b, visible} dA_x (scene units²)
  double error = 0.0;  ///< estimate of |G - exact| (scene units²)
  std::int64_t evaluations = 0;          ///< point factors evaluated
  std::int64_t direct_evaluations = 0;   ///< of which from the blockers (no pattern)
  std::int64_t cells = 0;                ///< triangles integrated (after refinement)
  std::int64_t events = 0;               ///< event segments a was cut along
  bool converged = true;  ///< false when the budget ran out before the tolerance was met
};

/// Default budget of point factors per pair (a few seconds at worst).
constexpr std::int64_t kAnalyticMaxEvaluations = 4'000'000;

/// G of the convex planar polygons a (integrated over) and b (both wound counter-clockwise
/// about their front normals) past `blockers` (planar polygons, blocking from both sides;
/// pass only those that can meet the hull of a and b, any others are clipped away), to an
/// absolute error estimate of at most `tol_G` (scene units²).
AnalyticEstimate analytic_pair_G(const Polygon3& a, const Polygon3& b,
                                 const std::vector<Polygon3>& blockers, double tol_G,
                                 std::int64_t max_evaluations = kAnalyticMaxEvaluations);

}  // namespace lambert::ff
