#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace lambert {

TEST(Polygon, AreaOfHugeCoordinatesDoesNotOverflow) {
  // Squared norms of 1e150 coordinates would be 1e300 * 1e300 = inf without scaling; the
  // power-of-two scaling is exact, so the area is the exact 0.5e300 to rounding.
  const std::vector<Eigen::Vector3d> tri = {{1e150, 1e150, 0}, {2e150, 1e150, 0}, {1e150, 2e150, 0}};
  EXPECT_DOUBLE_EQ(polygon_area(tri), 0.5e300);
  EXPECT_TRUE(std::isfinite(polygon_extent(tri)));
  EXPECT_DOUBLE_EQ(planarity_deviation({{0, 0, 0}, {1e200, 0, 0}, {1e200, 1e200, 0}, {0, 1e200, 0}}), 0.0);
}

TEST(Polygon, ScalingLeavesOrdinaryAreasBitwiseUnchanged) {
  const std::vector<Eigen::Vector3d> quad = {{0.1, 0.2, 0.3}, {1.7, 0.2, 0.3}, {1.7, 2.9, 0.35}, {0.1, 2.9, 0.35}};
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (size_t k = 1; k + 1 < quad.size(); ++k) n += (quad[k] - quad[0]).cross(quad[k + 1] - quad[0]);
  EXPECT_EQ(polygon_area(quad), 0.5 * n.norm());
}

TEST(Polygon, ConvexFanIsTheEarClippingOrder) {
  // A regular hexagon: the fan from the last corner, clipping corners 0, 1, 2 in turn.
  std::vector<Eigen::Vector3d> hex;
  for (int k = 0; k < 6; ++k) hex.emplace_back(std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0);
  const auto t = triangulate(hex);
  ASSERT_EQ(t.size(), 4u);
  EXPECT_EQ(t[0], (std::array<int, 3>{5, 0, 1}));
  EXPECT_EQ(t[2], (std::array<int, 3>{5, 2, 3}));
  EXPECT_EQ(t[3], (std::array<int, 3>{3, 4, 5}));
}

// A star of n corners alternating between radii 1 and 0.5 (n even), in the plane z = 0.3,
// counter-clockwise seen from +z; its exact area is n/2 triangles (0, r1, r2) twice.
std::vector<Eigen::Vector3d> star(int n) {
  std::vector<Eigen::Vector3d> p;
  for (int k = 0; k < n; ++k) {
    const double t = 2.0 * M_PI * k / n, r = k % 2 ? 0.5 : 1.0;
    p.emplace_back(r * std::cos(t), r * std::sin(t), 0.3);
  }
  return p;
}

TEST(Polygon, NonConvexPolygonOfAHundredThousandCornersTriangulatesInNLogN) {
  // Issue 33, item 7: ear clipping is O(n^2) or worse on a non-convex polygon (a 10^5-corner
  // outline took hours); above kEarClippingCorners the constrained Delaunay triangulation
  // runs in O(n log n) (about 0.1 s here).
  const int n = 100000;
  const std::vector<Eigen::Vector3d> p = star(n);
  const auto tris = triangulate(p);
  ASSERT_EQ(tris.size(), static_cast<size_t>(n - 2));
  double area = 0.0;
  for (const auto& t : tris) {
    for (int v : t) ASSERT_TRUE(v >= 0 && v < n);
    // Wound like the polygon: every triangle's normal along +z.
    const double z = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).z();
    ASSERT_GT(z, 0.0);
    area += 0.5 * z;
  }
  // n/2 kites of two triangles (0, r=1, r=0.5) with angle 2 pi / n between corners:
  // area = n * 0.5 * 1 * 0.5 * sin(2 pi / n); the triangles tile it to rounding.
  const double exact = n * 0.25 * std::sin(2.0 * M_PI / n);
  EXPECT_NEAR(area, exact, 1e-12 * exact * std::sqrt(n));
  // The same outline with two corners swapped crosses itself: refused, not hours of clipping.
  std::vector<Eigen::Vector3d> crossed = p;
  std::swap(crossed[10], crossed[20]);
  EXPECT_THROW(triangulate(crossed), SceneError);
  // Small non-convex polygons keep ear clipping (its order is part of meshes' bitwise results).
  const auto small = triangulate(star(kEarClippingCorners));
  EXPECT_EQ(small.size(), static_cast<size_t>(kEarClippingCorners - 2));
}

}  // namespace lambert
