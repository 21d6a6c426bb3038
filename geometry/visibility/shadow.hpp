#pragma once
// Exact direct light in partial shadow: the irradiance factor at a point from a polygonal
// emitter partly hidden by polygonal blockers, in closed form.
//
// From x, a blocker point p hides the emitter point where the ray x -> p meets the emitter's
// plane (central projection from x). The visible part of the emitter is therefore the
// emitter polygon minus the projections of every blocker (the part of each blocker strictly
// between x's height and the emitter's plane), and minus what lies behind x's horizon. That
// difference is computed with CGAL's Boolean_set_operations_2 on exact (Epeck) coordinates
// in the emitter's plane, and Lambert's contour formula summed over its boundary (outer
// loops counter-clockwise, holes clockwise) gives
//   F_{dx->E,visible} = -(1/2π) Σ_loops Σ_k θ_k n_x · (r_k × r_{k+1}) / |r_k × r_{k+1}|,
// exact up to the rounding of the projected corners (double, about 1e-15 relative).
//
// Each blocker is first clipped to the view pyramid from x through the emitter's convex hull
// (outside it nothing is hidden), so its projection stays within the hull and its rounding
// at the emitter's scale. Limits: blocker points within a relative 1e-12 of x's height above
// the emitter plane or of the plane itself are dropped before the projection. Blockers are planar
// polygons (any winding, one side as good as the other); non-simple ones are triangulated by ear
// clipping first.

#include <Eigen/Core>
#include <vector>

#include "geometry/polygon.hpp"

namespace lambert {

/// The exact factor F_{dx->E} of the part of `emitter` (planar polygon wound counter-clockwise
/// about its front normal) that x (unit normal n) sees past `blockers`: the fraction of the
/// radiosity B_E of a uniform Lambertian emitter arriving as irradiance at x (H = B_E F).
/// 0 when x is behind the emitter's plane. O(k log k) in the blockers' k projected corners.
double shadowed_point_factor(const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                             const Polygon3& emitter, const std::vector<Polygon3>& blockers);

/// The visible part of `emitter` from x (the region whose contour the factor integrates), as
/// loops in 3-D on the emitter's plane: outer boundaries counter-clockwise about its front
/// normal, holes clockwise. Empty when nothing is visible.
std::vector<Polygon3> visible_emitter_region(const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                                             const Polygon3& emitter,
                                             const std::vector<Polygon3>& blockers);

}  // namespace lambert
