#pragma once
// Planar polygon utilities: area, normal, planarity, triangulation.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

namespace lambert {

/// A polygon in 3-D as its corners in order.
using Polygon3 = std::vector<Eigen::Vector3d>;

/// Newell's normal of a polygon: a vector of length 2*area along the front normal
/// (counter-clockwise winding), robust for any simple planar polygon. Its length
/// overflows for coordinates beyond ~1e154; polygon_area does not.
Eigen::Vector3d newell_normal(const std::vector<Eigen::Vector3d>& poly);

/// Area of a planar polygon (half the Newell normal's length), computed on the polygon
/// scaled by a power of two so that squares cannot overflow (exact otherwise).
double polygon_area(const std::vector<Eigen::Vector3d>& poly);

/// Largest distance of a vertex from the polygon's mean plane (Newell normal through the
/// vertex mean); 0 for triangles.
double planarity_deviation(const std::vector<Eigen::Vector3d>& poly);

/// A polygon whose area is below this fraction of its squared extent (bounding-box diagonal)
/// is degenerate: its normal is not defined to better than ~1e-5 relative in double precision
/// (the cross product of near-parallel edges loses that many digits), so it cannot be a patch.
/// The one rule of every scene loader (OBJ, STL).
constexpr double kDegenerateRelArea = 1e-10;

/// True when the polygon has zero area by kDegenerateRelArea (or fewer than 3 corners).
bool is_degenerate_polygon(const std::vector<Eigen::Vector3d>& poly);

/// Largest distance between two vertices (O(n^2)).
double polygon_diameter(const std::vector<Eigen::Vector3d>& poly);

/// Diagonal of the bounding box, between the diameter and sqrt(3) times it (O(n)).
double polygon_extent(const std::vector<Eigen::Vector3d>& poly);

/// How far a point sampled on quad (p0, p1, p2, p3) (unit normal n) can lie below the
/// surface Embree traces for it, along n: |(p0 - p1 + p2 - p3) · n| / 2 (0 when planar).
/// Embree traces a quad as the triangles (0, 1, 3), (2, 3, 1); the samplers place points on
/// the bilinear surface (sample_patch) or on the triangles (0, 1, 2), (0, 2, 3)
/// (KernelSampler). With corner heights h_k along n and w = h0 - h1 + h2 - h3, the bilinear
/// surface strays from either triangle pair by at most |w| / 4 (at the centre, where it is the
/// corners' mean and the diagonals' midpoints differ from it by ±w / 4), and the two triangle
/// pairs -- the upper and lower faces of the corners' tetrahedron, which holds every sampled
/// point -- by at most |w| / 2. The OBJ loader keeps quads up to 1e-4 of their extent off
/// their plane; on a 52 cm tile that is 5e-3 cm, more than the rays' offset (1e-6 of the
/// scene's size), so a ray whose end lies below its own patch's traced triangles would be
/// counted as blocked by that patch: every ray end on a patch is lifted by offset + warp.
inline double quad_warp(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                        const Eigen::Vector3d& p2, const Eigen::Vector3d& p3,
                        const Eigen::Vector3d& n) {
  return 0.5 * std::abs((p0 - p1 + p2 - p3).dot(n));
}

/// A planar polygon's frame: origin o (its first corner), unit front normal w (Newell), and
/// in-plane axes u (along the longest edge from o) and v = w x u, so counter-clockwise about
/// w is counter-clockwise in (u, v).
struct PlaneFrame {
  Eigen::Vector3d o, u, v, w;
  Eigen::Vector2d to2d(const Eigen::Vector3d& p) const { return {(p - o).dot(u), (p - o).dot(v)}; }
  Eigen::Vector3d to3d(const Eigen::Vector2d& q) const { return o + q.x() * u + q.y() * v; }
  double height(const Eigen::Vector3d& p) const { return w.dot(p - o); }  ///< above the plane
};
PlaneFrame plane_frame(const std::vector<Eigen::Vector3d>& poly);

/// Triangulates a simple polygon in its Newell plane; returns index triples into `poly`,
/// wound like the polygon. Works for convex and concave polygons: O(n) for strictly convex
/// ones (the fan ear clipping would produce), ear clipping up to kEarClippingCorners corners
/// (O(n^2) or more), triangulate_simple above (O(n log n)). A non-simple polygon above that
/// size is a SceneError (ear clipping could take hours on it).
std::vector<std::array<int, 3>> triangulate(const std::vector<Eigen::Vector3d>& poly);
constexpr int kEarClippingCorners = 64;

/// Triangulates a simple polygon given counter-clockwise in 2D, in O(n log n) (constrained
/// Delaunay, geometry/polygon_cdt.cpp): index triples, counter-clockwise. Empty when the
/// polygon is not simple (repeated corners, crossing edges).
std::optional<std::vector<std::array<int, 3>>> triangulate_simple(
    const std::vector<Eigen::Vector2d>& p);

/// True when the planar polygon is strictly convex in its Newell plane.
bool is_convex(const std::vector<Eigen::Vector3d>& poly);

}  // namespace lambert
