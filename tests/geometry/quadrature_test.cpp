// The unoccluded quadrature of hybrid (and of the accuracy reference) against closed forms,
// for any size ratio, height and lateral position: docs/form-factors.md's "< 1e-6 relative"
// for unoccluded pairs, checked here to 1e-5.
#include "geometry/formfactors/quadrature.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "geometry/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/formfactors/reference.hpp"

namespace lambert {
namespace {

// A big square of side S at z = 0 (facing up) and a small one of side s at height h
// (facing down) centred at (cx, cy): the exact G from the corner-sum closed form.
struct Pair {
  double S, s, h, cx, cy;
};

Scene make_scene(const Pair& p) {
  Scene scene;
  Material m{"m", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  const double H = p.S / 2, x0 = p.cx - p.s / 2, x1 = p.cx + p.s / 2, y0 = p.cy - p.s / 2,
               y1 = p.cy + p.s / 2;
  add_polygon(scene, "big", m, {{-H, -H, 0}, {H, -H, 0}, {H, H, 0}, {-H, H, 0}});
  add_polygon(scene, "small", m, {{x0, y0, p.h}, {x0, y1, p.h}, {x1, y1, p.h}, {x1, y0, p.h}});
  return scene;
}

// A strip [0, L] x [y0, y0 + w] at height z as two needle triangles (corners in the order
// a CAD exporter writes them), facing up (+z) or down.
std::vector<ff::PatchGeom> strip(double L, double y0, double w, double z, bool up) {
  const Eigen::Vector3d p00(0, y0, z), p10(L, y0, z), p11(L, y0 + w, z), p01(0, y0 + w, z);
  std::vector<ff::PatchGeom> out;
  for (const auto& t : {std::array<Eigen::Vector3d, 3>{p00, p10, p11},
                        std::array<Eigen::Vector3d, 3>{p00, p11, p01}}) {
    ff::PatchGeom g;
    g.n = 3;
    g.p = {t[0], up ? t[1] : t[2], up ? t[2] : t[1], up ? t[2] : t[1]};
    g.normal = Eigen::Vector3d(0, 0, up ? 1 : -1);
    g.area = 0.5 * L * w;
    g.centroid = (t[0] + t[1] + t[2]) / 3.0;
    g.diameter = std::hypot(L, w);
    out.push_back(g);
  }
  return out;
}

double exact_G(const Pair& p) {
  const double H = p.S / 2;
  return parallel_rectangles_G(-H, H, -H, H, p.cx - p.s / 2, p.cx + p.s / 2, p.cy - p.s / 2,
                               p.cy + p.s / 2, p.h);
}

}  // namespace

TEST(HybridQuadrature, UnoccludedPairsOfAnySizeRatioMatchTheClosedForm) {
  FormFactorOptions o;
  o.pair.samples = 4;
  o.run.progress = false;
  double worst = 0.0;
  for (double ratio : {1.0, 3.0, 10.0, 30.0, 100.0})
    for (double height : {0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0})  // in small-patch sizes
      for (double where : {0.0, 0.45, 0.5, 0.6}) {  // centre, near, over and past an edge
        const Pair p{2.0, 2.0 / ratio, height * 2.0 / ratio, where * 2.0, 0.3 * where * 2.0};
        const PatchMesh mesh = mesh_scene(make_scene(p), {});
        ASSERT_EQ(mesh.size(), 2);
        const FormFactors ff = compute_form_factors(mesh, o);
        const double G = ff.F.coeff(0, 1) * mesh.patches[0].area, exact = exact_G(p);
        // docs/form-factors.md promises < 1e-6 relative for unoccluded pairs (checked to 1e-5
        // here); the closed form itself
        // loses ~16 ulps of its largest corner term (|g| <= S² = 4) to cancellation:
        // 16 * 2.2e-16 * 4 / 2π < 1e-14 absolute.
        const double tol = 1e-5 * exact + 1e-14;
        EXPECT_NEAR(G, exact, tol) << "ratio " << ratio << " height " << height << " at " << where;
        EXPECT_NEAR(ff.F.coeff(1, 0) * mesh.patches[1].area, G, 4e-16 * G);  // reciprocity
        if (exact > 1e-10) worst = std::max(worst, std::abs(G / exact - 1));
      }
  std::printf("worst relative error %.2e\n", worst);
}

// The case: a square of side 0.1 at height 0.1 above the centre of a 2 x 2 square
// was 19 % low with a rule chosen from the big patch alone (side 0.05: 22 %).
TEST(HybridQuadrature, SmallSquareCloseAboveALargeOneIsExact) {
  for (double side : {0.1, 0.05}) {
    const Pair p{2.0, side, 0.1, 0.0, 0.0};
    FormFactorOptions o;
    o.pair.samples = 4;
    o.run.progress = false;
    const PatchMesh mesh = mesh_scene(make_scene(p), {});
    const double G = compute_form_factors(mesh, o).F.coeff(1, 0) * mesh.patches[1].area;
    EXPECT_NEAR(G, exact_G(p), 1e-6 * exact_G(p)) << side;  // kQuadratureTolerance
  }
}

// The accuracy harness's reference quadrature is tighter still (1e-9 relative).
TEST(ReferenceQuadrature, MatchesTheClosedFormToNineDigits) {
  for (const Pair& p : {Pair{2.0, 0.02, 0.0002, 0.0, 0.0}, Pair{2.0, 0.2, 0.02, 1.0, 0.3},
                        Pair{1.0, 1.0, 1.0, 0.0, 0.0}, Pair{1.0, 1.0, 0.01, 0.5, 0.0}}) {
    const PatchMesh mesh = mesh_scene(make_scene(p), {});
    const FormFactors ref = unoccluded_quadrature(mesh, 1);
    const double G = ref.F.coeff(0, 1) * mesh.patches[0].area;
    EXPECT_NEAR(G, exact_G(p), 1e-9 * exact_G(p) + 1e-14) << p.s << " " << p.h;
  }
}

// Perpendicular squares sharing an edge (the log-singular case), and a floor running under
// a wall: exact to 1e-6 with one patch each.
TEST(HybridQuadrature, SharedEdgeIsExact) {
  FormFactorOptions o;
  o.pair.samples = 4;
  o.run.progress = false;
  const FormFactors ff = compute_form_factors(mesh_scene(perpendicular_squares(), {}), o);
  EXPECT_NEAR(ff.F.coeff(0, 1), kCubeAdjacent, 1e-6 * kCubeAdjacent);
}

// CAD slivers (issue 36): a round fin tip exported as facets 100 mm long and 0.1 mm wide
// (aspect 1000), facing another such strip 1 to 200 mm away, straight above or offset. The
// quadrature halves slivers across their length and gives them a low order across it; the
// sum over the 2 x 2 triangle pairs must still be the rectangles' closed form to
// kQuadratureTolerance (1e-6 relative per pair, so of the sum). The closed form loses ~16
// ulps of its largest corner term (|g| <= L² + offset² = 0.0125): 16 * 2.2e-16 * 0.0125 / 2π
// < 1e-17 absolute, against G >= 1e-10 here. Sliver cells, cut by their axis's distance d
// (cell_distance_bound), run up to 2d long: the worst case, 50 mm up and 3 mm aside, was
// 2.2e-6 off with the order 6 of cell_order's length / d <= 2 and is 4e-8 with order 8.
TEST(HybridQuadrature, SliverStripsMatchTheClosedForm) {
  const double L = 0.1, w = 1e-4;
  for (double h : {0.001, 0.002, 0.005, 0.02, 0.05, 0.2})
    for (double offset : {0.0, 0.003, 0.05}) {
      const auto lower = strip(L, 0.0, w, 0.0, true), upper = strip(L, offset, w, h, false);
      std::vector<ff::QuadCell> cells;
      double G = 0.0;
      for (const ff::PatchGeom& a : lower)
        for (const ff::PatchGeom& b : upper)
          G += ff::integrate_unoccluded(a, b, ff::kEstimatorAccuracy, cells);
      const double exact = parallel_rectangles_G(0, L, 0, w, 0, L, offset, offset + w, h);
      EXPECT_NEAR(G, exact, ff::kQuadratureTolerance * exact + 1e-17) << h << " " << offset;
      std::printf("h %g offset %g: relative error %.1e\n", h, offset, std::abs(G / exact - 1));
    }
}

// The cost of that accuracy grows with a sliver's length only. Quartering every cell (the
// old split) kept the aspect ratio, so a strip under another 2 mm away was cut until its
// cells were 1 mm long and 1 um wide: 4^7 = 16384 cells per triangle pair where the
// length needs L / (kappa d) = 0.1 / (0.5 * 0.002) = 100. Allowed: 4x that (the criterion
// takes a cell's centre-to-edge distance minus its radius, and cells near the strip's ends
// are cut further) per pair.
TEST(HybridQuadrature, SliverCellCountGrowsWithLengthOnly) {
  const double L = 0.1, w = 1e-4, h = 0.002;
  const auto lower = strip(L, 0.0, w, 0.0, true), upper = strip(L, 0.0, w, h, false);
  std::vector<ff::QuadCell> cells;
  for (const ff::PatchGeom& a : lower)
    for (const ff::PatchGeom& b : upper) {
      ff::integrate_unoccluded(a, b, ff::kEstimatorAccuracy, cells);
      EXPECT_LE(cells.size(), 4 * L / (ff::kEstimatorAccuracy.kappa * h));
    }
}

// A sliver cell is cut by the distance along it to the singularities of F(x -> b)
// (quadrature.cpp: along_lines, line_root_distance), not by its distance to b's edges: an edge
// running beside it makes F steep across the sliver but varies it along only near the edge's ends,
// and a slanted edge only near where it crosses over. CAD's case: a fin's tip facets (needle
// triangles 100 mm x 0.1 mm) under the next fin's face, a large triangle with a long
// edge, a short one and a diagonal, parallel to the strip, turned against it (0.5 deg:
// nearly parallel; 10 deg; 90 deg), or tilted 60 deg, 1..10 mm away, the strip under its
// long edge, its middle, its diagonal. The reference cuts the strip into 1,000 squares
// (no slivers: the isotropic criterion) each integrated by kReferenceAccuracy (< 1e-9);
// the needles must match it to kQuadratureTolerance, the contract hybrid's error bar
// assumes. A closed-form check of parallel strips is SliverStripsMatchTheClosedForm.
TEST(HybridQuadrature, SliversBesideSlantedEdgesMatchAFineReference) {
  const double L = 0.1, w = 1e-4;
  double worst = 0.0;
  for (double h : {0.001, 0.003, 0.01})
    for (double turn : {0.0, 0.5, 10.0, 90.0})
      for (double tilt : {0.0, 60.0})
        for (double y : {0.0, 0.0175, 0.03}) {
          if (tilt > 0.0 && turn > 0.0) continue;
          // b: corners (-0.01, -0.005), (0.11, -0.005), (0.11, 0.035) in the plane z = h,
          // turned by `turn` about the strip's centre and tilted about its long edge, facing
          // down.
          const double c = std::cos(turn * M_PI / 180), s = std::sin(turn * M_PI / 180);
          const double ct = std::cos(tilt * M_PI / 180), st = std::sin(tilt * M_PI / 180);
          auto place = [&](double px, double py) {
            const double dx = px - 0.05, dy = py - y;
            const double rx = 0.05 + c * dx - s * dy, ry = y + s * dx + c * dy;
            const double ly = ry - (y - 0.005);  // distance from the long edge's line
            return Eigen::Vector3d(rx, (y - 0.005) + ct * ly, h + st * ly);
          };
          // One scene, one patch per polygon: b, then the reference's 1,000 pieces of the strip.
          Scene scene;
          const Material m{"m", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
          add_polygon(scene, "b", m,
                      {place(-0.01, y - 0.005), place(0.11, y + 0.035), place(0.11, y - 0.005)});
          for (int k = 0; k < 1000; ++k) {
            const double x0 = k * L / 1000, x1 = (k + 1) * L / 1000;
            add_polygon(scene, "piece", m,
                        {{x0, y, 0}, {x1, y, 0}, {x1, y + w, 0}, {x0, y + w, 0}});
          }
          const auto geom = ff::patch_geometry(mesh_scene(scene, {0.0, 0}));
          ASSERT_EQ(geom.size(), 1001u);
          const ff::PatchGeom& b = geom[0];
          ASSERT_LT(b.normal.z(), 0.0);
          double G = 0.0, reference = 0.0;
          std::vector<ff::QuadCell> cells;
          for (const ff::PatchGeom& a : strip(L, y, w, 0.0, true))
            G += ff::integrate_unoccluded(a, b, ff::kEstimatorAccuracy, cells);
          for (size_t k = 1; k < geom.size(); ++k)
            reference += ff::integrate_unoccluded(geom[k], b, ff::kReferenceAccuracy, cells);
          ASSERT_GT(reference, 0.0);
          EXPECT_NEAR(G, reference, ff::kQuadratureTolerance * reference)
              << "h " << h << " turn " << turn << " tilt " << tilt << " y " << y;
          worst = std::max(worst, std::abs(G / reference - 1));
        }
  std::printf("worst relative error %.1e\n", worst);
}

// ... at a cost that does not grow as length / distance beside a parallel edge: needles 1 mm
// under a 20 mm strip's long edge were cut by that edge's distance into 64 cells per
// triangle pair (15-16 for the pairs not under it); cut only near the edges' ends, where
// the singularities are, they take 8-12. Bound: twice that.
TEST(HybridQuadrature, SliverBesideAParallelEdgeIsCutOnlyNearItsEnds) {
  const double L = 0.1, w = 1e-4, h = 0.001;
  const auto lower = strip(L, 0.0, w, 0.0, true), upper = strip(L, 0.0, 0.02, h, false);
  std::vector<ff::QuadCell> cells;
  for (const ff::PatchGeom& a : lower)
    for (const ff::PatchGeom& b : upper) {
      ff::integrate_unoccluded(a, b, ff::kEstimatorAccuracy, cells);
      EXPECT_LE(cells.size(), 24u);
    }
}

// hybrid draws its rays from preview_unoccluded's coarser cells and integrates them only when
// a ray is unblocked (issue 36: a heat sink's fully blocked pairs skip the Gauss rules). Its
// cells split by kEstimatorAccuracy must be exactly integrate_unoccluded's, so an unoccluded
// pair's G is bitwise what it was: sliver strips over and beside each other, a small square
// close above a large one, squares sharing an edge, a far pair.
TEST(HybridQuadrature, PreviewCellsRefineIntoTheRulesCellsBitwise) {
  std::vector<std::pair<ff::PatchGeom, ff::PatchGeom>> pairs;
  for (double offset : {0.0, 0.003})
    for (const ff::PatchGeom& a : strip(0.1, 0.0, 1e-4, 0.0, true))
      for (const ff::PatchGeom& b : strip(0.1, offset, 1e-4, 0.002, false)) pairs.push_back({a, b});
  for (const Pair& p : {Pair{2.0, 0.05, 0.1, 0.0, 0.0}, Pair{2.0, 0.2, 5.0, 1.0, 0.3}}) {
    const auto geom = ff::patch_geometry(mesh_scene(make_scene(p), {}));
    pairs.push_back({geom[1], geom[0]});
  }
  const auto edge = ff::patch_geometry(mesh_scene(perpendicular_squares(), {}));
  pairs.push_back({edge[0], edge[1]});
  for (const auto& [a, b] : pairs) {
    std::vector<ff::QuadCell> fine, preview;
    std::vector<double> exact;
    const double G = ff::integrate_unoccluded(a, b, ff::kEstimatorAccuracy, fine);
    ff::preview_unoccluded(a, b, preview);
    ASSERT_FALSE(preview.empty());
    EXPECT_LE(preview.size(), fine.size());
    EXPECT_EQ(ff::integrate_cells(a, b, preview, &exact), G);
    double by_cell = 0.0;
    for (size_t c = 0; c < preview.size(); ++c) {
      EXPECT_GT(preview[c].G, 0.0);
      by_cell += exact[c];
    }
    // The cells' integrals sum to G in another order: a few roundings of G.
    EXPECT_NEAR(by_cell, G, 1e-14 * G);
  }
}

}  // namespace lambert
