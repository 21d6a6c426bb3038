#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

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

}  // namespace lambert
