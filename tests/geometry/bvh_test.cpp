#include "geometry/visibility/bvh.hpp"

#include <gtest/gtest.h>

#include "core/sampling.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "tests/common/bumpy_grid.hpp"

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

// Packets answer every lane as the single query does (occluded, and intersect's patch and t): rays
// between random points of random triangles of the bumpy grid (every ray grazes the height field;
// about half are blocked), ends lifted by the estimators' 1e-6 offset, plus rays through the grid's
// vertices and the midpoints of its edges (where a watertight test matters), in packets of every
// size 1..16.
TEST(Bvh, PacketsAnswerEveryLaneAsTheSingleQueryDoes) {
  const PatchMesh mesh = mesh_scene(test::bumpy_grid(24), {0.0, 0});
  const Bvh bvh(mesh);
  const auto geom = ff::patch_geometry(mesh);
  Rng rng(7);
  std::vector<Eigen::Vector3f> o, d;
  auto add = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
    o.push_back(x.cast<float>());
    d.push_back((y - x).cast<float>());
  };
  for (int r = 0; r < 20000; ++r) {
    const auto i = static_cast<std::int32_t>(rng.uniform() * mesh.size());
    const auto j = static_cast<std::int32_t>(rng.uniform() * mesh.size());
    double ja, jb;
    const Eigen::Vector3d x = ff::sample_patch(geom[i], rng.uniform(), rng.uniform(), ja);
    const Eigen::Vector3d y = ff::sample_patch(geom[j], rng.uniform(), rng.uniform(), jb);
    add(x + 1e-6 * geom[i].normal, y + 1e-6 * geom[j].normal);
  }
  const Eigen::Vector3d above(0.5, 1.0, 0.5);
  for (const auto& v : mesh.vertices) add(above, v);
  for (const auto& p : mesh.patches)
    add(above, 0.5 * (mesh.vertices[p.vertices[0]] + mesh.vertices[p.vertices[1]]));
  int blocked = 0, differ = 0, missed = 0, hits_differ = 0;
  bool hit[Bvh::kPacket];
  RayHit closest[Bvh::kPacket];
  size_t k0 = 0;
  for (int n = 1; k0 < o.size(); n = n % Bvh::kPacket + 1) {
    const int m = static_cast<int>(std::min<size_t>(n, o.size() - k0));
    bvh.occluded_packet(&o[k0], &d[k0], m, hit);
    bvh.intersect_packet(&o[k0], &d[k0], m, closest);
    for (int k = 0; k < m; ++k) {
      const bool single = bvh.occluded(o[k0 + k], d[k0 + k], 0.0f, 1.0f);
      blocked += single;
      differ += single != hit[k];
      const RayHit one = bvh.intersect(o[k0 + k], d[k0 + k]);
      missed += one.patch < 0;
      hits_differ += one.patch != closest[k].patch || one.t != closest[k].t;
    }
    k0 += m;
  }
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(hits_differ, 0);
  EXPECT_GT(missed, 0);  // rays leaving the grid: intersect's "no hit" is compared too
  // Both answers occur in number, so the comparison tests something.
  EXPECT_GT(blocked, static_cast<int>(o.size()) / 10);
  EXPECT_LT(blocked, static_cast<int>(o.size()) * 9 / 10);
}

}  // namespace lambert
