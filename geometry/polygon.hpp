#pragma once
// Planar polygon utilities: area, normal, planarity, triangulation.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace lambert {

/// Newell's normal of a polygon: a vector of length 2*area along the front normal
/// (counter-clockwise winding), robust for any simple planar polygon.
Eigen::Vector3d newell_normal(const std::vector<Eigen::Vector3d>& poly);

/// Area of a planar polygon (half the Newell normal's length).
double polygon_area(const std::vector<Eigen::Vector3d>& poly);

/// Largest distance of a vertex from the polygon's mean plane (Newell normal through the
/// vertex mean); 0 for triangles.
double planarity_deviation(const std::vector<Eigen::Vector3d>& poly);

/// Largest distance between two vertices.
double polygon_diameter(const std::vector<Eigen::Vector3d>& poly);

/// Triangulates a simple polygon by ear clipping in its Newell plane; returns index
/// triples into `poly`, wound like the polygon. Works for convex and concave polygons.
std::vector<std::array<int, 3>> triangulate(const std::vector<Eigen::Vector3d>& poly);

/// True when the planar polygon is strictly convex in its Newell plane.
bool is_convex(const std::vector<Eigen::Vector3d>& poly);

}  // namespace lambert
