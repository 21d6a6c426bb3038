#include "geometry/visibility/bvh.hpp"

#include <gtest/gtest.h>

namespace lambert {

TEST(Bvh, OccludesOnlyThroughThePlate) {
  Scene s;
  Material m{"m", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "plate", m, {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}});
  const PatchMesh mesh = mesh_scene(s, {0.5, 0});
  const Bvh bvh(mesh);
  // Through the plate from either side: blocked. Beside it: free.
  EXPECT_TRUE(bvh.occluded({0.2f, 0.3f, -1}, {0, 0, 2}, 0.0f, 1.0f));
  EXPECT_TRUE(bvh.occluded({0.2f, 0.3f, 1}, {0, 0, -2}, 0.0f, 1.0f));
  EXPECT_FALSE(bvh.occluded({1.5f, 0.3f, -1}, {0, 0, 2}, 0.0f, 1.0f));
  // Segment that stops short of the plate.
  EXPECT_FALSE(bvh.occluded({0.2f, 0.3f, -1}, {0, 0, 2}, 0.0f, 0.49f));
  const RayHit hit = bvh.intersect({0.2f, 0.3f, -1}, {0, 0, 1});
  ASSERT_GE(hit.patch, 0);
  // Embree computes t in single precision: a few ulps of 1 (1.2e-7 each); 1e-6 leaves room.
  EXPECT_NEAR(hit.t, 1.0, 1e-6);
  // The hit patch (0.5 x 0.5 cells) contains (0.2, 0.3): its centroid is within half a cell.
  const auto c = mesh.patches[hit.patch].centroid;
  EXPECT_LE(std::abs(c.x() - 0.2), 0.25);
  EXPECT_LE(std::abs(c.y() - 0.3), 0.25);
}

}  // namespace lambert
