#pragma once
// Adaptive quadrature of the unoccluded point-to-patch factor over a patch (internal).
//
//   G0(a, b) = ∫_{A_a} F(x -> b) dA_x,   F(x -> b) exact by Lambert's contour formula,
//
// the unoccluded G_ab of two patches. The integrand is smooth in x but varies on the
// length scale of x's distance to b, so a rule chosen from the patch sizes alone fails when
// b is small and close (a 0.1 square 0.1 above a 2 x 2 one is 19 % low with one 12 x 12
// rule). Here the parameter square of a is split into cells, recursively, until every cell
// is small against its distance to b (diameter h <= kappa * d), and each cell gets a
// Gauss-Legendre rule whose order grows with h / d; cells touching b (d = 0: a shared edge
// or a contact line) are split to a maximum depth. The relative error of an order-m rule on
// a cell falls like (h / 2d)^(2m) (the integrand's singularities lie ~d away in the complex
// plane); the orders below were checked against closed forms for size ratios 1..100,
// heights 0.01..10 sizes (tests/geometry/quadrature_test.cpp). Cost: O(log(size / d)) cells.

#include <vector>

#include "geometry/formfactors/kernels.hpp"

namespace lambert::ff {

/// How fine the adaptive rule is.
struct QuadratureAccuracy {
  double kappa;   ///< split cells with diameter > kappa * distance to the other patch
  int max_depth;    ///< maximum number of splits
  int touch_depth;  ///< maximum splits of cells touching the other patch (shared edge)
  int extra;      ///< added to every cell's Gauss order
};

/// For the estimators (relative error < 1e-6 for any size ratio, ~1e-6 at shared edges).
constexpr QuadratureAccuracy kEstimatorAccuracy{0.5, 10, 3, 0};
/// Relative error bound of kEstimatorAccuracy, checked by tests/geometry/quadrature_test.cpp
/// (measured worst 5.2e-8 over size ratios 1..100 and heights 0.01..10; 7e-11 for a
/// shared edge; 3.5e-7 for 100 mm x 0.1 mm sliver strips 1 mm apart and 50 mm aside, as
/// before sliver cells were cut by their axis's distance: HybridQuadrature.SliverStrips...);
/// hybrid adds it to its standard error.
constexpr double kQuadratureTolerance = 1e-6;
/// The coarser partition hybrid draws its rays from (preview_unoccluded): cells up to 16x
/// their distance to b (kappa 1/16) instead of 2x. Its every split is also one of
/// kEstimatorAccuracy's, so integrate_cells refines its cells into exactly kEstimatorAccuracy's.
constexpr QuadratureAccuracy kPreviewAccuracy{0.0625, 10, 3, 0};
/// For the reference of `lambert accuracy` and the tests (relative error < 1e-9).
constexpr QuadratureAccuracy kReferenceAccuracy{2.0, 16, 10, 6};

/// One cell of the partition (a planar triangle or quad with its area and normal) and its
/// contribution G = ∫_cell F(x -> b) dA_x, with the Gauss rule that integrates it.
struct QuadCell {
  PatchGeom g;
  double G = 0.0;
  int order_u = 0, order_v = 0;  ///< Gauss orders (along, across for a sliver)
  bool sliver = false;           ///< the rule runs in sliver_frame's parameters
  int depth = 0;                 ///< splits from the patch
};

/// Splits the part of `a` in front of `b`'s plane into cells and integrates F(x -> b) over
/// each (cells with G > 0 only are kept, in a fixed order). Returns Σ G. Thread-safe.
double integrate_unoccluded(const PatchGeom& a, const PatchGeom& b,
                            const QuadratureAccuracy& accuracy, std::vector<QuadCell>& cells);

/// A coarser partition of the same part of a (kPreviewAccuracy), every cell of positive
/// area valued by one point factor at its parameter midpoint instead of a Gauss rule (good
/// to ~(h / 2d)^2; hybrid draws its rays from it and integrates only where some ray is
/// unblocked). Returns Σ G.
double preview_unoccluded(const PatchGeom& a, const PatchGeom& b, std::vector<QuadCell>& cells);

/// ∫_a F(x -> b) dA_x from the cells of preview_unoccluded: each split further into
/// integrate_unoccluded's cells (kEstimatorAccuracy), each by its Gauss rule, those with
/// G > 0 summed. Returns their total, bitwise integrate_unoccluded's; with `exact`, also
/// (*exact)[c] = ∫_cell F(x -> b) dA_x for each preview cell.
double integrate_cells(const PatchGeom& a, const PatchGeom& b, const std::vector<QuadCell>& cells,
                       std::vector<double>* exact = nullptr);

/// The part of patch a in front of patch b's plane, as one or more pieces (a itself, or
/// triangles of the clipped polygon). F(x -> b) is exactly 0 behind b's plane and jumps
/// there, so integrating over the front part keeps the integrand smooth.
void front_part(const PatchGeom& a, const PatchGeom& b, std::vector<PatchGeom>& pieces);

/// Distance from x to the (planar, convex) patch g.
double distance_to_patch(const Eigen::Vector3d& x, const PatchGeom& g);

/// A lower bound on the distance from any point of `cell` (a planar convex triangle or quad)
/// to patch b (<= 0 when they may touch): from the cell's bounding sphere, or for a sliver
/// (long side > 4 x its width) from its long axis less its half width, which is the true
/// distance to within that width where the sphere undercuts it by up to half the length.
double cell_distance_bound(const PatchGeom& cell, const PatchGeom& b);

}  // namespace lambert::ff
