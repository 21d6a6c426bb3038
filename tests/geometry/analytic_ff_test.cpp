// The analytic estimator: exact point factors past polygonal blockers, integrated to a
// tolerance (geometry/formfactors/analytic.hpp), against closed forms and exact references.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common/occluded_reference.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert {
namespace {

// An axis-aligned rectangle at height z, facing +z (up) or -z.
Polygon3 rect(double x0, double x1, double y0, double y1, double z, bool up) {
  Polygon3 p{{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}};
  if (!up) std::reverse(p.begin(), p.end());
  return p;
}

// One case with a known exact G.
struct Case {
  const char* name;
  Polygon3 a, b;
  std::vector<Polygon3> blockers;
  double exact;
};

std::vector<Case> cases() {
  const PartialShadowGeometry g = partial_shadow_geometry();
  // The partial-shadow reference: cut along its event lines and integrated at order 24
  // (orders 12 and 20 agree to ~1e-16, geometry/analytic.hpp).
  const double shadow = 16.0 * partial_shadow_floor_light_factor(24);
  Polygon3 floor = g.floor;
  return {
      {"unit squares", rect(0, 1, 0, 1, 0, true), rect(0, 1, 0, 1, 1, false), {},
       parallel_rectangles_G(0, 1, 0, 1, 0, 1, 0, 1, 1)},
      // 1:20 sizes, offset and close: the integrand varies on the small square's distance.
      {"small over large", rect(0.3, 0.4, 0.5, 0.6, 0, true), rect(0, 2, 0, 2, 0.15, false), {},
       parallel_rectangles_G(0.3, 0.4, 0.5, 0.6, 0, 2, 0, 2, 0.15)},
      {"offset thin", rect(0, 3, 0, 0.05, 0, true), rect(1, 2, 0.5, 1.5, 0.4, false), {},
       parallel_rectangles_G(0, 3, 0, 0.05, 1, 2, 0.5, 1.5, 0.4)},
      {"partial shadow", floor, g.light, {g.blocker}, shadow},
      // Independent references (tests/common/occluded_reference.hpp: Howell's element-to-
      // rectangle factors integrated over cells cut at every kink, ~1e-15).
      {"centred blocker", rect(0, 1, 0, 1, 0, true), rect(0, 1, 0, 1, 1, false),
       {rect(0.25, 0.75, 0.25, 0.75, 0.5, true)},
       ref::parallel_blocked_G({0, 1, 0, 1}, {0, 1, 0, 1}, 1.0, {0.25, 0.75, 0.25, 0.75}, 0.5, 32)},
      {"corner blocker", rect(0, 1, 0, 1, 0, true), rect(0, 1, 0, 1, 1, false),
       {rect(0, 0.5, 0, 0.5, 0.5, false)},  // facing away: blockers block from both sides
       ref::parallel_blocked_G({0, 1, 0, 1}, {0, 1, 0, 1}, 1.0, {0, 0.5, 0, 0.5}, 0.5, 32)},
      {"off-centre blocker", rect(0, 1, 0, 1, 0, true), rect(0, 1, 0, 1, 1, false),
       {rect(0.1, 0.45, 0.3, 0.95, 0.3, true)},
       ref::parallel_blocked_G({0, 1, 0, 1}, {0, 1, 0, 1}, 1.0, {0.1, 0.45, 0.3, 0.95}, 0.3, 32)},
      {"unequal offset", rect(0, 2, 0, 1, 0, true), rect(0.5, 1.5, -0.5, 1.5, 1, false),
       {rect(0.2, 1, 0.1, 0.6, 0.4, true)},
       ref::parallel_blocked_G({0, 2, 0, 1}, {0.5, 1.5, -0.5, 1.5}, 1.0, {0.2, 1, 0.1, 0.6}, 0.4, 32)},
      {"large receiver", rect(0, 1, 0, 1, 0, true), rect(-1, 2, -1, 2, 2, false),
       {rect(0.4, 0.9, -0.2, 0.3, 1.5, true)},
       ref::parallel_blocked_G({0, 1, 0, 1}, {-1, 2, -1, 2}, 2.0, {0.4, 0.9, -0.2, 0.3}, 1.5, 32)},
      // Perpendicular squares sharing an edge, a fin on the plane x = z from that edge.
      {"fin 0.1", rect(0, 1, 0, 1, 0, true), {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}},
       {{{0, 0, 0}, {0, 1, 0}, {0.1, 1, 0.1}, {0.1, 0, 0.1}}}, ref::perpendicular_fin_G(0.1, 32)},
      {"fin 0.3", rect(0, 1, 0, 1, 0, true), {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}},
       {{{0, 0, 0}, {0, 1, 0}, {0.3, 1, 0.3}, {0.3, 0, 0.3}}}, ref::perpendicular_fin_G(0.3, 32)},
  };
}

TEST(AnalyticPair, UnblockedPairsMatchTheClosedFormTo1e12) {
  for (const Case& c : cases()) {
    if (!c.blockers.empty()) continue;
    const ff::AnalyticEstimate e = ff::analytic_pair_G(c.a, c.b, {}, 1e-13);
    // The estimate is the low rule's error to a few per cent (calibration test below), so
    // a request of 1e-13 leaves the value within 1e-12 of the exact G (G <= 1 here).
    EXPECT_TRUE(e.converged) << c.name;
    EXPECT_NEAR(e.G, c.exact, 1e-12) << c.name << " estimate " << e.error;
  }
}

TEST(AnalyticPair, BlockedPairsMatchIndependentReferencesTo1e9) {
  for (const Case& c : cases()) {
    if (c.blockers.empty()) continue;
    const ff::AnalyticEstimate e = ff::analytic_pair_G(c.a, c.b, c.blockers, 1e-10);
    // Requested 1e-10 (G <= 0.4): the 1e-9 with a margin of 10 for the estimate's
    // calibration (at most 10x optimistic, test below).
    EXPECT_TRUE(e.converged) << c.name;
    EXPECT_NEAR(e.G, c.exact, 1e-9) << c.name << " estimate " << e.error;
  }
}

TEST(AnalyticPair, PartialShadowMatchesTheExactOccludedFactorTo1e9) {
  const Case c = cases()[3];
  const ff::AnalyticEstimate e = ff::analytic_pair_G(c.a, c.b, c.blockers, 1e-10);
  // Requested 1e-10 of G = 0.27 (F_floor->light x 16): the 1e-9 the issue asks for with a
  // margin of 10 for the estimate's calibration (at most 10x optimistic, test below).
  EXPECT_NEAR(e.G, c.exact, 1e-9) << "estimate " << e.error;
  EXPECT_GT(e.events, 0);
  // The cells' patterns carry the integral: fresh point factors mostly to classify.
  EXPECT_LT(e.direct_evaluations, e.evaluations / 5);
}

TEST(AnalyticPair, FinHidingTheWholeWallGivesExactlyZero) {
  // The fin to x = z = 0.5: light gets through only from floor points x0 > c / (1 - c) = 1.
  const ff::AnalyticEstimate e = ff::analytic_pair_G(
      rect(0, 1, 0, 1, 0, true), {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}},
      {{{0, 0, 0}, {0, 1, 0}, {0.5, 1, 0.5}, {0.5, 0, 0.5}}}, 1e-12);
  EXPECT_EQ(ref::perpendicular_fin_G(0.5, 32), 0.0);
  EXPECT_EQ(e.G, 0.0);
}

TEST(AnalyticPair, FullyBlockedPairIsExactlyZero) {
  // A blocker larger than both squares' shadow cone, mid-way, and one touching b.
  for (double z : {0.5, 0.999}) {
    const ff::AnalyticEstimate e = ff::analytic_pair_G(
        rect(0, 1, 0, 1, 0, true), rect(0, 1, 0, 1, 1, false), {rect(-1.5, 2.5, -1.5, 2.5, z, true)}, 1e-12);
    EXPECT_EQ(e.G, 0.0) << z;
    EXPECT_EQ(e.error, 0.0) << z;
  }
}

TEST(AnalyticPair, ErrorEstimateIsCalibrated) {
  // Over every case and tolerance, the true error must lie below the estimate in at least
  // 95 % of the runs, and not more than 10x below it (the estimator issue's rule), for
  // errors above the rounding floor (1e-14 relative, where the estimate is floored).
  int runs = 0, above = 0, far_below = 0;
  for (const Case& c : cases()) {
    for (double tol : {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9}) {
      const ff::AnalyticEstimate e = ff::analytic_pair_G(c.a, c.b, c.blockers, tol);
      const double err = std::abs(e.G - c.exact);
      if (e.error <= 1e-13 * c.exact) {
        std::printf("%-16s tol %.0e  estimate %.3e at the floor\n", c.name, tol, e.error);
        continue;
      }
      ++runs;
      above += err > e.error;
      far_below += err < e.error / 10.0;
      std::printf("%-16s tol %.0e  estimate %.3e  true %.3e  ratio %.3f\n", c.name, tol, e.error, err,
                  err / e.error);
    }
  }
  ASSERT_GT(runs, 10);
  EXPECT_LE(above, runs / 20) << runs << " runs";
  EXPECT_LE(far_below, runs / 20) << runs << " runs";
}

TEST(AnalyticPair, SquareInAnOpenBoxWithAnOffsetPlateClosesToTheEscapeReference) {
  // A square floating in an open box (walls x, y in {0, 1}, z in [0, 1], facing in; top
  // open) under an offset two-sided plate. Every direction from the square ends on a wall,
  // on the plate's underside, or leaves through the opening, so
  //   sum_walls G_sw = A_s - G_s,plate - G_s,opening,
  // with G_s,plate the unoccluded closed form and G_s,opening the occluded parallel factor
  // of the independent reference (Howell's element factors integrated over kink-cut cells,
  // ~1e-15). Each wall is integrated from both sides as well (integrals over different
  // polygons, partitioned differently): they must agree within their two estimates.
  const Polygon3 square = rect(0.25, 0.75, 0.2, 0.7, 0.1, true);
  const ref::Rect plate_rect{0.3, 0.85, 0.15, 0.5};
  const double plate_z = 0.6;
  const Polygon3 plate =
      rect(plate_rect.x0, plate_rect.x1, plate_rect.y0, plate_rect.y1, plate_z, false);
  const std::vector<Polygon3> walls{
      {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}},  // x = 0, facing +x
      {{1, 0, 0}, {1, 0, 1}, {1, 1, 1}, {1, 1, 0}},  // x = 1, facing -x
      {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}},  // y = 0, facing +y
      {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}},  // y = 1, facing -y
  };
  const Polygon3 box_floor = rect(0, 1, 0, 1, 0, true);  // behind the square: clipped away
  const double tol = 1e-10;
  double walls_G = 0.0;
  for (size_t w = 0; w < walls.size(); ++w) {
    std::vector<Polygon3> blockers{plate, box_floor};
    for (size_t k = 0; k < walls.size(); ++k)
      if (k != w) blockers.push_back(walls[k]);
    const ff::AnalyticEstimate to = ff::analytic_pair_G(square, walls[w], blockers, tol);
    const ff::AnalyticEstimate from = ff::analytic_pair_G(walls[w], square, blockers, tol);
    EXPECT_TRUE(to.converged && from.converged) << w;
    EXPECT_GT(to.G, 0.0) << w;
    EXPECT_NEAR(to.G, from.G, to.error + from.error + 1e-15) << "wall " << w;
    walls_G += to.G;
  }
  const double A = polygon_area(square);
  const double plate_G = parallel_rectangles_G(0.25, 0.75, 0.2, 0.7, plate_rect.x0, plate_rect.x1,
                                               plate_rect.y0, plate_rect.y1, plate_z - 0.1);
  const double opening_G = ref::parallel_blocked_G({0.25, 0.75, 0.2, 0.7}, {0, 1, 0, 1}, 0.9,
                                                   plate_rect, plate_z - 0.1, 32);
  // Four walls at tol 1e-10 each, the estimate at most 10x optimistic (calibration test):
  // within 4e-9, the 1e-9 per entry.
  EXPECT_NEAR(walls_G, A - plate_G - opening_G, 4e-9);
  // The opening through the engine too (the plate as its only blocker; walls touch the shaft).
  const ff::AnalyticEstimate open =
      ff::analytic_pair_G(square, rect(0, 1, 0, 1, 1, false), {plate, walls[0], walls[1]}, tol);
  EXPECT_NEAR(open.G, opening_G, 1e-9);
}

// The faces of a box [x0, x1] x [y0, y1] x [z0, z1] (any winding: blockers block from both
// sides), with its bottom face or not (a box standing on a floor has none). With `halves`
// the two sides along x are given as two halves each, one above the other: the same
// surface, but their vertical edges no longer pair up with the other sides' whole ones, so
// the faces are not recognised as a closed convex solid and each is cut from every point.
std::vector<Polygon3> box_faces(double x0, double x1, double y0, double y1, double z0, double z1,
                                bool bottom, bool halves) {
  std::vector<Polygon3> f{rect(x0, x1, y0, y1, z1, true)};
  if (bottom) f.push_back(rect(x0, x1, y0, y1, z0, false));
  const double zm = 0.5 * (z0 + z1);
  auto side = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    const Eigen::Vector3d up(0, 0, 1);
    if (!halves || p.y() != q.y()) {  // only the sides along x in halves
      f.push_back({p + z0 * up, q + z0 * up, q + z1 * up, p + z1 * up});
      return;
    }
    f.push_back({p + z0 * up, q + z0 * up, q + zm * up, p + zm * up});
    f.push_back({p + zm * up, q + zm * up, q + z1 * up, p + z1 * up});
  };
  side({x0, y0, 0}, {x1, y0, 0});
  side({x1, y0, 0}, {x1, y1, 0});
  side({x1, y1, 0}, {x0, y1, 0});
  side({x0, y1, 0}, {x0, y0, 0});
  return f;
}

TEST(AnalyticPair, FacesOfABoxTurnedAwayHideNothingMore) {
  // A box's faces turned away from the integrated point (or from the whole receiver) are
  // skipped (solid_back_planes): the same box given with two sides in halves (not a solid,
  // every face cut) must give the same G. Cases: a box standing on the floor seen from the
  // ceiling (its open bottom on the emitter's plane), the same pair integrated over the
  // floor (the cap on the receiver's plane: nothing may be skipped), a closed box floating
  // between two squares and one off to the side between perpendicular walls.
  struct Pair {
    const char* name;
    Polygon3 a, b;
    double z0;
    bool bottom;
  };
  const Polygon3 floor = rect(0, 10, 0, 8, 0, true), ceiling = rect(0, 10, 0, 8, 3, false);
  const Polygon3 wall{{0, 0, 0}, {0, 8, 0}, {0, 8, 3}, {0, 0, 3}};  // x = 0, facing +x
  const std::vector<Pair> pairs{
      {"ceiling -> floor past a standing box", ceiling, floor, 0.0, false},
      {"floor -> ceiling past a standing box", floor, ceiling, 0.0, false},
      {"ceiling -> floor past a floating box", ceiling, floor, 0.7, true},
      {"wall -> floor past a floating box", wall, floor, 0.7, true},
  };
  for (const Pair& p : pairs) {
    const double tol = 1e-6 * std::min(polygon_area(p.a), polygon_area(p.b));
    const ff::AnalyticEstimate solid =
        ff::analytic_pair_G(p.a, p.b, box_faces(3, 5.5, 2, 3.5, p.z0, 1.6, p.bottom, false), tol);
    const ff::AnalyticEstimate cut =
        ff::analytic_pair_G(p.a, p.b, box_faces(3, 5.5, 2, 3.5, p.z0, 1.6, p.bottom, true), tol);
    EXPECT_TRUE(solid.converged && cut.converged) << p.name;
    // Each is within its estimate of the exact G (calibrated: ErrorEstimateIsCalibrated),
    // so they agree within the sum of the two (each <= tol when converged).
    EXPECT_NEAR(solid.G, cut.G, solid.error + cut.error + 1e-15) << p.name;
    EXPECT_GT(cut.G, 0.0) << p.name;
    std::printf("%-40s G %.12f  %.12f  estimates %.1e %.1e  cells %lld %lld\n", p.name, solid.G,
                cut.G, solid.error, cut.error, static_cast<long long>(solid.cells),
                static_cast<long long>(cut.cells));
  }
}

TEST(AnalyticPair, CornellBlockFaceToTiltedWallIsFinite) {
  // Regression: a pair of the measured Cornell box at 20 patches (mm; the tall block's side
  // face, standing on the floor, to half of the slightly tilted right wall, past the floor,
  // walls and the block's other faces). Event lines through corners on the floor, at a's
  // height, met a's plane at overflowing coordinates (inf, 0/0), and CGAL's CDT raised
  // SIGFPE in GMP on them. G must be finite, 0 <= G <= min(A_a, A_b) (G = A_a F_ab with
  // F <= 1 both ways), with a finite estimate, whatever the budget.
  const Polygon3 a{
      {423.0, 0.0, 247.0}, {423.0, 330.0, 247.0}, {472.0, 330.0, 406.0}, {472.0, 0.0, 406.0}};
  const Polygon3 b{{552.8, 0.0, 0.0}, {549.6, 0.0, 559.2}, {556.0, 548.8, 559.2}};
  const std::vector<Polygon3> blockers{
      {{552.8, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 559.2}, {549.6, 0.0, 559.2}},
      {{556.0, 548.8, 0.0}, {556.0, 548.8, 227.0}, {0.0, 548.8, 227.0}, {0.0, 548.8, 0.0}},
      {{556.0, 548.8, 332.0}, {556.0, 548.8, 559.2}, {0.0, 548.8, 559.2}, {0.0, 548.8, 332.0}},
      {{556.0, 548.8, 227.0}, {556.0, 548.8, 332.0}, {343.0, 548.8, 332.0}, {343.0, 548.8, 227.0}},
      {{549.6, 0.0, 559.2}, {0.0, 0.0, 559.2}, {0.0, 548.8, 559.2}, {556.0, 548.8, 559.2}},
      {{552.8, 0.0, 0.0}, {556.0, 548.8, 559.2}, {556.0, 548.8, 0.0}},
      {{423.0, 330.0, 247.0}, {265.0, 330.0, 296.0}, {314.0, 330.0, 456.0}, {472.0, 330.0, 406.0}},
      {{472.0, 0.0, 406.0}, {472.0, 330.0, 406.0}, {314.0, 330.0, 456.0}, {314.0, 0.0, 456.0}},
      {{265.0, 0.0, 296.0}, {265.0, 330.0, 296.0}, {423.0, 330.0, 247.0}, {423.0, 0.0, 247.0}}};
  const double bound = std::min(polygon_area(a), polygon_area(b));
  std::vector<ff::AnalyticEstimate> runs;
  for (std::int64_t budget : {std::int64_t{200}, std::int64_t{20000}}) {
    const ff::AnalyticEstimate e = ff::analytic_pair_G(a, b, blockers, 1e-6 * bound, budget);
    ASSERT_TRUE(std::isfinite(e.G) && std::isfinite(e.error)) << budget;
    EXPECT_GE(e.G, 0.0);
    EXPECT_LE(e.G, bound * (1 + 1e-12));
    runs.push_back(e);
  }
  // The two budgets agree within their estimates (each the low rule's error, calibrated).
  EXPECT_NEAR(runs[0].G, runs[1].G, runs[0].error + runs[1].error);
}

// A closed 10 x 8 x 3 room (six faces facing in) with `boxes` boxes standing on the floor
// (five faces each, facing out, no bottom), mirror-symmetric about x = 5: boxes come in
// mirror pairs on a 2 x 5 grid of the half x < 5, and an odd count adds one centred on
// x = 5 (one box: the 2 x 1.5 x 1.2 box in the middle). The floor is one quad
// running under the boxes. `footprint` receives the boxes' floor area.
struct Room {
  std::vector<std::string> names;
  std::vector<Polygon3> faces;
  double footprint = 0.0;
  void add(const std::string& name, Polygon3 p) {
    names.push_back(name);
    faces.push_back(std::move(p));
  }
};

Room symmetric_room(int boxes) {
  const double X = 10, Y = 8, Z = 3;
  Room r;
  auto add = [&](const std::string& name, Polygon3 p) { r.add(name, std::move(p)); };
  add("wall_x0", {{0, 0, 0}, {0, Y, 0}, {0, Y, Z}, {0, 0, Z}});
  add("wall_x1", {{X, 0, 0}, {X, 0, Z}, {X, Y, Z}, {X, Y, 0}});
  add("wall_y0", {{0, 0, 0}, {0, 0, Z}, {X, 0, Z}, {X, 0, 0}});
  add("wall_y1", {{0, Y, 0}, {X, Y, 0}, {X, Y, Z}, {0, Y, Z}});
  add("floor", {{0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0}});
  add("ceiling", {{0, 0, Z}, {0, Y, Z}, {X, Y, Z}, {X, 0, Z}});
  auto box = [&](double x0, double x1, double y0, double y1, double h) {
    const std::string n = "box " + std::to_string(r.names.size() / 5);
    add(n, {{x0, y0, h}, {x1, y0, h}, {x1, y1, h}, {x0, y1, h}});  // top
    add(n, {{x0, y0, 0}, {x0, y0, h}, {x0, y1, h}, {x0, y1, 0}});  // -x
    add(n, {{x1, y0, 0}, {x1, y1, 0}, {x1, y1, h}, {x1, y0, h}});  // +x
    add(n, {{x0, y0, 0}, {x1, y0, 0}, {x1, y0, h}, {x0, y0, h}});  // -y
    add(n, {{x0, y1, 0}, {x0, y1, h}, {x1, y1, h}, {x1, y1, 0}});  // +y
    r.footprint += (x1 - x0) * (y1 - y0);
  };
  if (boxes % 2 == 1) box(4, 6, 3.25, 4.75, 1.2);
  for (int k = 0; k < boxes / 2; ++k) {
    const int c = k % 2, row = k / 2;  // left-half slots: x in [0.5, 3.9], y in [0.4, 7.4]
    const double x0 = 0.5 + 2.2 * c, x1 = x0 + 0.8 + 0.2 * (row % 3);
    const double y0 = 0.4 + 1.5 * row, y1 = y0 + 0.6 + 0.2 * ((row + c) % 3);
    const double h = 0.5 + 0.25 * ((k * 3) % 5);
    box(x0, x1, y0, y1, h);
    box(X - x1, X - x0, y0, y1, h);  // the mirror image (its -x face mirrors the +x one)
  }
  return r;
}

// F of the room, one patch per face.
FormFactors room_factors(const Room& r, double tol, int threads) {
  Scene s;
  const Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  for (size_t k = 0; k < r.faces.size(); ++k) add_polygon(s, r.names[k], grey, r.faces[k]);
  const PatchMesh mesh = mesh_scene(s, {});
  FormFactorOptions o;
  o.estimator = "analytic";
  o.analytic.tol = tol;
  o.run.progress = false;
  o.run.threads = threads;
  o.run.with_stderr = true;
  return compute_form_factors(mesh, o);
}

double area_of(const Polygon3& p) { return polygon_area(p); }

// G of faces a -> b of the room past every other face, at an absolute target of tol on F.
ff::AnalyticEstimate room_pair(const Room& r, size_t a, size_t b, double tol) {
  std::vector<Polygon3> blockers;
  for (size_t k = 0; k < r.faces.size(); ++k)
    if (k != a && k != b) blockers.push_back(r.faces[k]);
  const double bound = std::min(area_of(r.faces[a]), area_of(r.faces[b]));
  return ff::analytic_pair_G(r.faces[a], r.faces[b], blockers, tol * bound);
}

TEST(AnalyticRoom, MirrorWallsSeeTheFloorPastAStandingPlateAlike) {
  // Issue 33: wall_x1 -> floor was off by 2e-3 (unconverged) where its mirror image
  // wall_x0 -> floor was right. Both walls share an edge with the floor, whose frame has
  // irrational axes: the floor's corners on wall_x1's plane lay ~1e-15 behind the horizon
  // of every point of it, the horizon cut the shared edge at a point matching no feature,
  // and every cell fell back to the booleans until the pair's budget ran out. A plate
  // standing on the floor between the walls (mirror-symmetric) is the cheapest blocker
  // that makes the pair go through the corner identification.
  const double X = 10, Y = 8, Z = 3, A = Y * Z, tol = 1e-8;
  const Polygon3 wall_x0{{0, 0, 0}, {0, Y, 0}, {0, Y, Z}, {0, 0, Z}};
  const Polygon3 wall_x1{{X, 0, 0}, {X, 0, Z}, {X, Y, Z}, {X, Y, 0}};
  const Polygon3 floor{{0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0}};
  const std::vector<Polygon3> plate{{{4, 4, 0}, {6, 4, 0}, {6, 4, 1.2}, {4, 4, 1.2}}};
  const ff::AnalyticEstimate e0 = ff::analytic_pair_G(wall_x0, floor, plate, tol * A);
  const ff::AnalyticEstimate e1 = ff::analytic_pair_G(wall_x1, floor, plate, tol * A);
  EXPECT_TRUE(e0.converged && e1.converged) << "F " << e0.G / A << " +- " << e0.error / A
                                            << ", mirror " << e1.G / A << " +- " << e1.error / A;
  // Each within its estimate (<= tol A when converged, calibrated: AnalyticPair tests), so
  // the mirror images agree within the sum of the two, at most 2 tol in F.
  EXPECT_NEAR(e0.G / A, e1.G / A, (e0.error + e1.error) / A + 1e-15);
  EXPECT_LE(e0.error + e1.error, 2 * tol * A);
}

TEST(AnalyticRoomSlow, MirrorWallsSeeTheFloorPastACentredBoxAlike) {
  // The scene (about 2 s: ~200 cells, each classified by the booleans).
  const Room r = symmetric_room(1);
  const double tol = 1e-6, A = area_of(r.faces[0]);
  const ff::AnalyticEstimate e0 = room_pair(r, 0, 4, tol), e1 = room_pair(r, 1, 4, tol);
  EXPECT_TRUE(e0.converged && e1.converged) << "F " << e0.G / A << " +- " << e0.error / A
                                            << ", mirror " << e1.G / A << " +- " << e1.error / A;
  // Each within its estimate (<= tol A when converged, calibrated: AnalyticPair tests), so
  // the mirror images agree within the sum of the two, at most 2 tol in F.
  EXPECT_NEAR(e0.G / A, e1.G / A, (e0.error + e1.error) / A + 1e-15)
      << "estimates " << e0.error / A << " " << e1.error / A;
  EXPECT_LE(e0.error + e1.error, 2 * tol * A);
}

// The whole F of a symmetric furnished room, one patch per face, at tol: converged, the
// mirror images of every pair equal, every row closed.
void check_room(int boxes, double tol) {
  const Room r = symmetric_room(boxes);
  Scene s;
  const Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  for (size_t k = 0; k < r.faces.size(); ++k) add_polygon(s, r.names[k], grey, r.faces[k]);
  const PatchMesh mesh = mesh_scene(s, {});
  ASSERT_EQ(mesh.size(), static_cast<std::int32_t>(r.faces.size()));
  FormFactorOptions o;
  o.estimator = "analytic";
  o.analytic.tol = tol;
  o.run.progress = false;
  o.run.with_stderr = true;
  const FormFactors ff = compute_form_factors(mesh, o);
  // Every pair converges: with the visible pieces computed in floating point (no polygon
  // booleans) no pair runs out of its budget. Before, pairs of a box face and the plane it
  // stands on did (corner identification failed near the contact), and 4 boxes took 70 s.
  EXPECT_EQ(ff.stats.pairs_unverified, 0) << boxes << " boxes";
  // The patch of the mirror image of each patch (x -> 10 - x), by centroid.
  const std::int32_t n = mesh.size();
  std::vector<std::int32_t> mirror(n, -1);
  for (std::int32_t i = 0; i < n; ++i) {
    Eigen::Vector3d c = mesh.patches[i].centroid;
    c.x() = 10.0 - c.x();
    for (std::int32_t j = 0; j < n; ++j)
      if ((mesh.patches[j].centroid - c).norm() < 1e-9) mirror[i] = j;
    ASSERT_GE(mirror[i], 0) << i;
  }
  const Eigen::MatrixXd F(ff.F), E(ff.stderr_F);
  for (std::int32_t i = 0; i < n; ++i) {
    // Each entry is within tol of the exact factor (its estimate is <= tol when converged
    // and bounds the true error: calibration test above), so a row of m entries sums to its
    // exact value within m tol: 1 for every face (each direction ends on a face of the
    // closed room), 1 - footprint / 80 for the floor (under the boxes it sees their
    // insides, which have no faces here); a mirror pair of entries agrees within 2 tol.
    const bool floor = mesh.surface_names[mesh.patches[i].surface] == "floor";
    const double exact = floor ? 1.0 - r.footprint / 80.0 : 1.0;
    const double m = static_cast<double>((F.row(i).array() != 0.0).count());
    EXPECT_NEAR(F.row(i).sum(), exact, m * tol)
        << boxes << " boxes, row " << i << " (" << mesh.surface_names[mesh.patches[i].surface]
        << "), estimates " << E.row(i).sum();
    for (std::int32_t j = 0; j < n; ++j)
      EXPECT_NEAR(F(i, j), F(mirror[i], mirror[j]), 2 * tol)
          << boxes << " boxes, F(" << i << "," << j << ") against its mirror image";
  }
}

TEST(AnalyticRoom, OneBoxRoomIsClosedAndTheSameForAnyThreadCount) {
  // Issue 36 item 1 (rooms at View3D's speed): the one-box room at 1e-5 closes (row sums
  // within m tol, check_room) in ~0.1 s; -j 1 and -j 2 give the same F bit for bit.
  check_room(1, 1e-5);
  const Room r = symmetric_room(1);
  const FormFactors one = room_factors(r, 1e-5, 1), two = room_factors(r, 1e-5, 2);
  const Eigen::MatrixXd F1(one.F), F2(two.F);
  EXPECT_EQ((F1 - F2).cwiseAbs().maxCoeff(), 0.0);
}

TEST(AnalyticRoomSlow, SymmetricFurnishedRoomsAreSymmetricAndClosed) {
  // 1, 2 and 4 boxes at tol 1e-5 (the room family of issue 36; bench/analytic_bench covers
  // more): about 0.3, 1 and 10 s on 2 cores. With the polygon booleans 3 boxes at 1e-4 took
  // 250 s on the CI machine and some pairs stopped unconverged.
  for (int boxes : {1, 2, 4}) {
    SCOPED_TRACE(boxes);
    check_room(boxes, 1e-5);
  }
}

TEST(AnalyticRoomSlow, FourBoxFloorAndCeilingConvergeAt1e8) {
  // bench/analytic_bench's 4-box room (boxes standing on the floor, one patch per face): its
  // ceiling -> floor pair ran out of its budget at 1e-8 with the rounded CDT (cells cut off
  // their event lines by rounding failed their pattern check cell after cell); the exact CDT
  // the estimator then falls back to converges (~30 s on 2 busy cores).
  // As the bench builds it (same corners, windings and order: the partition depends on them).
  const double X = 10, Y = 8, Z = 3;
  const Polygon3 floor{{0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0}};
  const Polygon3 ceiling{{0, 0, Z}, {0, Y, Z}, {X, Y, Z}, {X, 0, Z}};
  std::vector<Polygon3> blockers{{{0, 0, 0}, {0, Y, 0}, {0, Y, Z}, {0, 0, Z}},
                                 {{X, 0, 0}, {X, 0, Z}, {X, Y, Z}, {X, Y, 0}},
                                 {{0, 0, 0}, {0, 0, Z}, {X, 0, Z}, {X, 0, 0}},
                                 {{0, Y, 0}, {X, Y, 0}, {X, Y, Z}, {0, Y, Z}}};
  int n = 0;
  for (int i = 0; i < 5 && n < 4; ++i)
    for (int j = 0; j < 4 && n < 4; ++j, ++n) {
      const double x0 = 0.6 + 1.9 * i + 0.1 * (j % 2), y0 = 0.7 + 1.8 * j + 0.15 * (i % 3);
      const double x1 = x0 + 0.8 + 0.1 * ((i + j) % 3), y1 = y0 + 0.6 + 0.1 * ((i * j) % 4);
      const double h = 0.5 + 0.25 * ((i + 2 * j) % 5);
      blockers.push_back({{x0, y0, h}, {x1, y0, h}, {x1, y1, h}, {x0, y1, h}});
      blockers.push_back({{x0, y0, 0}, {x1, y0, 0}, {x1, y0, h}, {x0, y0, h}});
      blockers.push_back({{x1, y1, 0}, {x0, y1, 0}, {x0, y1, h}, {x1, y1, h}});
      blockers.push_back({{x0, y1, 0}, {x0, y0, 0}, {x0, y0, h}, {x0, y1, h}});
      blockers.push_back({{x1, y0, 0}, {x1, y1, 0}, {x1, y1, h}, {x1, y0, h}});
    }
  const double tol = 1e-8, A = 80.0;
  const ff::AnalyticEstimate e = ff::analytic_pair_G(ceiling, floor, blockers, tol * A);
  std::printf("F %.12f +- %.1e, %lld point factors (%lld fresh), %lld cells\n", e.G / A,
              e.error / A, static_cast<long long>(e.evaluations),
              static_cast<long long>(e.direct_evaluations), static_cast<long long>(e.cells));
  EXPECT_TRUE(e.converged) << "F " << e.G / A << " +- " << e.error / A;
  // Converged: its estimate is at most the target (the estimate is calibrated: above).
  EXPECT_LE(e.error, tol * A);
  EXPECT_GT(e.G, 0.0);
}

// bench/analytic_bench's furnished room: the closed 10 x 8 x 3 room and the first `boxes` of
// its 19 boxes standing on the floor (five faces each, no bottom), in the bench's order.
Room bench_room(int boxes) {
  const double X = 10, Y = 8, Z = 3;
  Room r;
  auto add = [&](const std::string& name, Polygon3 p) { r.add(name, std::move(p)); };
  add("floor", {{0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0}});
  add("ceiling", {{0, 0, Z}, {0, Y, Z}, {X, Y, Z}, {X, 0, Z}});
  add("wall -x", {{0, 0, 0}, {0, Y, 0}, {0, Y, Z}, {0, 0, Z}});
  add("wall +x", {{X, 0, 0}, {X, 0, Z}, {X, Y, Z}, {X, Y, 0}});
  add("wall -y", {{0, 0, 0}, {0, 0, Z}, {X, 0, Z}, {X, 0, 0}});
  add("wall +y", {{0, Y, 0}, {X, Y, 0}, {X, Y, Z}, {0, Y, Z}});
  int n = 0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j) {
      if ((i == 2 && j == 2) || n == boxes) continue;
      const double x0 = 0.6 + 1.9 * i + 0.1 * (j % 2), y0 = 0.7 + 1.8 * j + 0.15 * (i % 3);
      const double x1 = x0 + 0.8 + 0.1 * ((i + j) % 3), y1 = y0 + 0.6 + 0.1 * ((i * j) % 4);
      const double h = 0.5 + 0.25 * ((i + 2 * j) % 5);
      const std::string name = "box " + std::to_string(n++);
      r.footprint += (x1 - x0) * (y1 - y0);
      add(name, {{x0, y0, h}, {x1, y0, h}, {x1, y1, h}, {x0, y1, h}});
      add(name, {{x0, y0, 0}, {x1, y0, 0}, {x1, y0, h}, {x0, y0, h}});
      add(name, {{x1, y1, 0}, {x0, y1, 0}, {x0, y1, h}, {x1, y1, h}});
      add(name, {{x0, y1, 0}, {x0, y0, 0}, {x0, y0, h}, {x0, y1, h}});
      add(name, {{x1, y0, 0}, {x1, y1, 0}, {x1, y1, h}, {x1, y0, h}});
    }
  return r;
}

TEST(AnalyticPair, HiddenPartByDirectQuadratureKeepsItsEstimateWhereShadowBandsAreNarrow) {
  // Issue 36 item 1: at loose tolerances a pair with several blocker pieces is the unoccluded
  // integral minus the hidden part by quadrature of fresh point factors (no event lines). The
  // bench room's ceiling seen from the wall x = 0 past its 4 boxes: the boxes hide the far
  // ceiling only from a band z < ~0.3 m of the 8 x 3 m wall, which the rules of two cells
  // over the whole wall both all but miss; they agreed to 2.7e-3 where the error was 6.3e-3.
  // Cells are now split to the scale of their distance to the blockers before a rule is
  // trusted. Reference: the event partition at 1e-7 x A (below kDirectMinRelTol: events
  // only; estimate 1e-6, calibrated above), far below the tolerances checked.
  const Room r = bench_room(4);
  std::vector<Polygon3> blockers;
  for (size_t k = 0; k < r.faces.size(); ++k)
    if (k != 1 && k != 2) blockers.push_back(r.faces[k]);
  const Polygon3& wall = r.faces[2];
  const double A = polygon_area(wall);
  const ff::AnalyticEstimate ref = ff::analytic_pair_G(wall, r.faces[1], blockers, 1e-7 * A);
  ASSERT_TRUE(ref.converged);
  ASSERT_GT(ref.events, 0);
  for (double tol : {1e-2, 3e-3, 1e-3}) {
    const ff::AnalyticEstimate e = ff::analytic_pair_G(wall, r.faces[1], blockers, tol * A);
    EXPECT_TRUE(e.converged) << tol;
    EXPECT_EQ(e.events, 0) << tol << ": by direct quadrature";
    EXPECT_LE(e.error, tol * A) << tol;
    // The true error within the estimate (plus the reference's own).
    EXPECT_LE(std::abs(e.G - ref.G), e.error + ref.error) << tol << " estimate " << e.error;
  }
}

TEST(AnalyticRoomSlow, FourBoxRoomEntriesLieWithinTheirStatedErrors) {
  // Issue 36 item 1: every entry of the bench's 4-box room at --tol 1e-4 and 1e-5 (most pairs
  // by the unoccluded integral minus the hidden part's direct quadrature) lies within its own
  // stated error (stderr_F) of the 1e-8 reference plus the reference's stated error, and
  // within tol; -j 1 and -j 2 give the same F bit for bit. About 15 s on 2 busy cores
  // (the reference: 10 s).
  const Room r = bench_room(4);
  const FormFactors ref = room_factors(r, 1e-8, 2);
  ASSERT_EQ(ref.stats.pairs_unverified, 0);
  const Eigen::MatrixXd Fr(ref.F), Er(ref.stderr_F);
  for (double tol : {1e-4, 1e-5}) {
    const FormFactors two = room_factors(r, tol, 2);
    EXPECT_EQ(two.stats.pairs_unverified, 0) << tol;
    const Eigen::MatrixXd F(two.F), E(two.stderr_F);
    int checked = 0;
    double worst = 0.0;  // the largest error / stated error, at F(wi, wj)
    Eigen::Index wi = 0, wj = 0;
    for (Eigen::Index i = 0; i < F.rows(); ++i)
      for (Eigen::Index j = 0; j < F.cols(); ++j) {
        const double err = std::abs(F(i, j) - Fr(i, j));
        EXPECT_LE(err, E(i, j) + Er(i, j) + 1e-15)
            << "tol " << tol << ", F(" << i << "," << j << ")";
        EXPECT_LE(err, tol) << "tol " << tol << ", F(" << i << "," << j << ")";
        if (F(i, j) != 0.0 || Fr(i, j) != 0.0) {
          ++checked;
          const double ratio = err / (E(i, j) + Er(i, j) + 1e-300);
          if (ratio > worst) {
            worst = ratio;
            wi = i;
            wj = j;
          }
        }
      }
    std::printf("tol %.0e: %d entries, largest error / stated %.3f at F(%d,%d) = %.6e\n", tol,
                checked, worst, static_cast<int>(wi), static_cast<int>(wj), Fr(wi, wj));
    if (tol == 1e-4) {
      const FormFactors one = room_factors(r, tol, 1);
      EXPECT_EQ((Eigen::MatrixXd(one.F) - F).cwiseAbs().maxCoeff(), 0.0);
      EXPECT_EQ((Eigen::MatrixXd(one.stderr_F) - E).cwiseAbs().maxCoeff(), 0.0);
    }
  }
}

TEST(AnalyticRoomSlow, NineteenBoxRoomClosesAt1e4) {
  // Issue 36 item 1's target: the bench's 19-box room (101 polygons) at --tol 1e-4 closes
  // within 1e-4 (View3D: 7.9e-3 in 9.4 s). It took 420 s with the event partition alone;
  // now ~10 s of CPU. Each row sum is within the sum of its entries' stated errors of its
  // exact value (1; the floor's 1 - footprint / 80, under the boxes it sees their insides),
  // and, measured 6.5e-5 at worst, within the target 1e-4.
  const Room r = bench_room(19);
  ASSERT_EQ(r.faces.size(), 101u);
  const FormFactors ff = room_factors(r, 1e-4, 2);
  EXPECT_EQ(ff.stats.pairs_unverified, 0);
  const Eigen::MatrixXd F(ff.F), E(ff.stderr_F);
  for (Eigen::Index i = 0; i < F.rows(); ++i) {
    const double exact = i == 0 ? 1.0 - r.footprint / 80.0 : 1.0;
    const double err = std::abs(F.row(i).sum() - exact);
    EXPECT_LE(err, E.row(i).sum()) << "row " << i << " (" << r.names[i] << ")";
    EXPECT_LE(err, 1e-4) << "row " << i << " (" << r.names[i] << ")";
  }
}

// The inside of the unit cube with a two-sided plate (two faces back to back), tilted so that
// its edge-on line and contact-free shadows cut every face's integral.
Scene cube_with_plate() {
  Scene s = unit_cube();
  const Material m{"plate", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  const Polygon3 plate{{0.2, 0.3, 0.35}, {0.75, 0.3, 0.5}, {0.75, 0.7, 0.55}, {0.2, 0.7, 0.4}};
  add_polygon(s, "plate up", m, plate);
  add_polygon(s, "plate down", m, Polygon3(plate.rbegin(), plate.rend()));
  return s;
}

TEST(AnalyticEstimatorSlow, ClosedBoxWithTiltedPlateRowsSumToOne) {
  const PatchMesh mesh = mesh_scene(cube_with_plate(), {});  // one patch per face
  ASSERT_EQ(mesh.size(), 8);
  FormFactorOptions o;
  o.estimator = "analytic";
  // 1e-7: the twelve pairs of faces sharing a cube edge converge algebraically at the contact
  // (isotropic splitting; docs/form-factors.md "The analytic estimator"), about 0.3 s each
  // here; 1e-9 takes 10 s.
  o.analytic.tol = 1e-7;
  o.run.progress = false;
  o.run.with_stderr = true;
  o.run.threads = 1;
  const FormFactors ff = compute_form_factors(mesh, o);
  o.run.threads = 2;
  const FormFactors ff2 = compute_form_factors(mesh, o);
  ASSERT_EQ(ff.F.nonZeros(), ff2.F.nonZeros());
  for (Eigen::Index k = 0; k < ff.F.nonZeros(); ++k)
    EXPECT_EQ(ff.F.valuePtr()[k], ff2.F.valuePtr()[k]) << "entry " << k << " depends on threads";
  EXPECT_EQ(ff.stats.pairs_unverified, 0);
  for (Eigen::Index i = 0; i < ff.F.rows(); ++i) {
    // Every direction from a face ends on another face: the row sums to 1 exactly. Each of
    // its <= 7 entries is within its estimate (<= tol when converged, calibrated).
    double sum = 0.0, err = 0.0;
    for (SparseF::InnerIterator it(ff.F, i); it; ++it) {
      sum += it.value();
      err += ff.stderr_F.coeff(i, it.col());
      // Reciprocity: both entries come from one G (divided by each area).
      const double a = mesh.patches[i].area * it.value(), b = mesh.patches[it.col()].area * ff.F.coeff(it.col(), i);
      EXPECT_NEAR(a, b, 1e-15 * a);
    }
    EXPECT_LE(err, 7 * o.analytic.tol) << "row " << i;
    EXPECT_NEAR(sum, 1.0, 7 * o.analytic.tol)
        << "row " << i << " (" << mesh.surface_names[mesh.patches[i].surface] << ")";
  }
  // The cube's faces see a little less of the opposite face than the empty cube's exact
  // opposite factor; the plate takes the difference.
  EXPECT_LT(ff.F.coeff(4, 5), kCubeOpposite);
}

}  // namespace
}  // namespace lambert

namespace lambert {

TEST(AnalyticPair, WhereTheBudgetRunsOutThePairIsSampledAndTheBetterEstimateKept) {
  // Issue 36: where the budget of point factors runs out before --ff-tol, the pair is sampled
  // by hybrid until its standard error meets the same tolerance, and the better of the two
  // estimates is kept. Two unit squares 1 apart past a tilted strip: the integral's first
  // cells already carry an error estimate of 8.6e-7, so at tol 1e-6 it converges within the
  // default budget (no rays), and with a budget of 8 point factors at tol 1e-7 it cannot
  // refine: the pair is sampled (rays traced) but 2^20 samples cannot reach 1e-7 (a
  // visible fraction of ~0.5 from n rays has a standard error of ~0.5 G / sqrt(n) = 5e-5),
  // so the integral's estimate is kept, unverified.
  Scene s = parallel_squares(1.0);
  Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "strip", grey, {{0.2, -1, 0.35}, {0.6, -1, 0.45}, {1.1, 2, 0.65}, {0.7, 2, 0.55}});
  const PatchMesh mesh = mesh_scene(s, {});
  const std::vector<ff::PatchGeom> geom = ff::patch_geometry(mesh);
  const Bvh bvh(mesh, 1);
  ff::PairContext ctx{geom, bvh, PairEstimatorParams{}.samples, 1, 1e-6 * mesh.scale, 1e-6};
  const ff::PairEstimate full = ff::estimate_analytic(ctx, 0, 1);
  EXPECT_FALSE(full.unverified);
  EXPECT_EQ(full.rays, 0);
  EXPECT_LE(std::sqrt(full.var), 1e-6);
  ctx.tol = 1e-7;
  ctx.analytic_budget = 8;
  const ff::PairEstimate short_of = ff::estimate_analytic(ctx, 0, 1);
  EXPECT_TRUE(short_of.unverified);
  EXPECT_GT(short_of.rays, 1 << 20);
  // The integral's estimate (its error is the smaller): within both stated errors.
  EXPECT_GT(std::sqrt(short_of.var), 1e-7);
  EXPECT_LT(std::sqrt(short_of.var), 1e-5);
  EXPECT_NEAR(short_of.G, full.G, 1e-6 + std::sqrt(short_of.var));
}

}  // namespace lambert
