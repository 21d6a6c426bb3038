// Discontinuity lines and the constrained Delaunay mesh (discontinuity.hpp).
#include "geometry/mesh/discontinuity.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <set>

#include "common/mesh_checks.hpp"
#include "geometry/analytic.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

using test::expect_conforming;
using test::min_angle;
using test::scene_face_area;

TEST(DiscontinuityLines, LieOnTheAnalyticWedgesOfThePartialShadowScene) {
  const Scene scene = partial_shadow_scene();
  const auto [xs, ys] = partial_shadow_lines();
  const auto segs = discontinuity_segments(scene, {});
  std::set<double> seen_x, seen_y;
  int on_floor = 0;
  for (const auto& s : segs) {
    if (s.face != 0) continue;  // the floor
    ++on_floor;
    EXPECT_EQ(s.order, 1);  // nothing touches the floor: no D0 line
    EXPECT_NEAR(s.a.z(), 0.0, 1e-15);
    EXPECT_NEAR(s.b.z(), 0.0, 1e-15);
    // Each line is x = c or y = c for one of the analytic c, to 1e-9 relative (4: the
    // floor's size; the construction's rounding is ~1e-15).
    bool matched = false;
    for (double c : xs)
      if (std::abs(s.a.x() - c) <= 4e-9 && std::abs(s.b.x() - c) <= 4e-9) matched = true, seen_x.insert(c);
    for (double c : ys)
      if (std::abs(s.a.y() - c) <= 4e-9 && std::abs(s.b.y() - c) <= 4e-9) matched = true, seen_y.insert(c);
    EXPECT_TRUE(matched) << "(" << s.a.transpose() << ") - (" << s.b.transpose() << ")";
  }
  EXPECT_GT(on_floor, 0);
  EXPECT_EQ(seen_x.size(), xs.size());  // every analytic line was found
  EXPECT_EQ(seen_y.size(), ys.size());
}

TEST(DiscontinuityMesh, FollowsTheLinesConformsAndPreservesArea) {
  const Scene scene = partial_shadow_scene();
  MeshOptions mo;
  mo.max_edge = 0.3;
  mo.discontinuity = true;
  const PatchMesh m = mesh_scene(scene, mo);
  expect_conforming(m);
  std::vector<double> area(scene.surfaces.size(), 0);
  for (const auto& p : m.patches) {
    area[p.surface] += p.area;
    EXPECT_EQ(p.vertex_count, 3);
    for (int k = 0; k < 3; ++k)  // the edge bound (CGAL's size criterion, all edges)
      EXPECT_LE((m.vertices[p.vertices[k]] - m.vertices[p.vertices[(k + 1) % 3]]).norm(), 0.3 * (1 + 1e-12));
  }
  // Area is preserved: the triangles tile each face (to rounding, 1e-12 relative).
  for (size_t s = 0; s < area.size(); ++s)
    EXPECT_NEAR(area[s], scene_face_area(scene, static_cast<int>(s)), 1e-12 * area[s]);
  // No floor triangle straddles an analytic D1/D2 line where the line was found (the lines
  // are patch edges): test each line at its extent, the union of its segments.
  const auto [xs, ys] = partial_shadow_lines();
  const auto segs = discontinuity_segments(scene, {});
  int straddling = 0, checked = 0;
  for (const auto& s : segs) {
    if (s.face != 0) continue;
    const bool vertical = std::abs(s.a.x() - s.b.x()) < 1e-9;
    const double c = vertical ? s.a.x() : s.a.y();
    const double lo = vertical ? std::min(s.a.y(), s.b.y()) : std::min(s.a.x(), s.b.x());
    const double hi = vertical ? std::max(s.a.y(), s.b.y()) : std::max(s.a.x(), s.b.x());
    for (const auto& p : m.patches) {
      if (p.surface != 0) continue;
      const double along = vertical ? p.centroid.y() : p.centroid.x();
      if (along <= lo || along >= hi) continue;
      double below = 0, above = 0;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& v = m.vertices[p.vertices[k]];
        const double d = (vertical ? v.x() : v.y()) - c;
        below = std::min(below, d);
        above = std::max(above, d);
      }
      ++checked;
      if (below < -1e-9 && above > 1e-9) ++straddling;
    }
  }
  EXPECT_GT(checked, 0);
  EXPECT_EQ(straddling, 0);
  // Quality: every triangle's smallest angle is at least the refinement bound, except where
  // two constraints meet at a smaller angle (here all lines are axis-parallel or floor
  // edges, so none: the bound holds everywhere, to rounding).
  double worst = 180;
  for (const auto& p : m.patches) worst = std::min(worst, min_angle(m, p));
  EXPECT_GE(worst, kMinAngleDegrees - 1e-6);
}

TEST(DiscontinuityMesh, SelfIntersectingAndNonManifoldBlockersStillMesh) {
  Scene scene = partial_shadow_scene();
  const Material black{"black", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  // A bow-tie face, three faces sharing one edge (non-manifold) and a fin piercing the floor.
  add_polygon(scene, "bowtie", black, {{0.5, 0.5, 1}, {1.2, 1.2, 1}, {1.2, 0.5, 1}, {0.5, 1.2, 1}});
  for (double ang : {0.0, 2.0, 4.0})
    add_polygon(scene, "fan", black,
                {{3, 3, 0.5}, {3, 3.8, 0.5}, {3 + 0.4 * std::cos(ang), 3.4, 0.5 + 0.4 * std::sin(ang)}});
  add_polygon(scene, "fin", black, {{0.5, 3.0, -0.3}, {1.5, 3.0, -0.3}, {1.5, 3.0, 0.6}, {0.5, 3.0, 0.6}});
  MeshOptions mo;
  mo.max_edge = 0.4;
  mo.discontinuity = true;
  const PatchMesh m = mesh_scene(scene, mo);
  ASSERT_GT(m.size(), 0);
  for (const auto& p : m.patches) EXPECT_GT(p.area, 0.0);
  expect_conforming(m, /*manifold=*/false);
  // The fin pierces the floor: a D0 line along y = 3 on the floor.
  bool pierced = false;
  for (const auto& s : discontinuity_segments(scene, {}))
    pierced = pierced || (s.order == 0 && s.face == 0 && std::abs(s.a.y() - 3) < 1e-12 &&
                          std::abs(s.b.y() - 3) < 1e-12);
  EXPECT_TRUE(pierced);
}

}  // namespace
}  // namespace lambert

namespace lambert {

// Issue 35, item 5 (warning floods): a CAD part's discontinuity mesh stopped refining
// hundreds of planes at their vertex budget and said so once per plane (917 lines on the
// heat sink). Now one line for all of them, with the size of the effect. Three unit squares
// on three planes, each with a fan of lines 1e-4 rad apart (angles no refinement resolves):
// every plane hits its budget, the log has one such line naming the count of planes and how
// many triangles are thin, and the mesh is still complete (area kept).
TEST(DiscontinuityMesh, PlanesThatStopRefiningAreSummarisedInOneWarning) {
  Scene scene;
  const Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  std::vector<DiscontinuitySegment> lines;
  for (int k = 0; k < 3; ++k) {
    const double z = 2.0 * k;
    add_polygon(scene, "plate" + std::to_string(k), grey,
                {{0, 0, z}, {1, 0, z}, {1, 1, z}, {0, 1, z}});
    for (int j = 0; j < 6; ++j) {
      const double t = 0.3 + 1e-4 * j;  // the fan's directions from (0.05, 0.05)
      lines.push_back({Eigen::Vector3d(0.05, 0.05, z),
                       Eigen::Vector3d(0.05 + 0.9 * std::cos(t), 0.05 + 0.9 * std::sin(t), z), 1,
                       k});
    }
  }
  ::testing::internal::CaptureStderr();
  const PatchMesh mesh = mesh_scene_constrained(scene, 0.0, lines);
  const std::string err = ::testing::internal::GetCapturedStderr();
  std::size_t count = 0;
  for (std::size_t at = err.find("stopped refining"); at != std::string::npos;
       at = err.find("stopped refining", at + 1))
    ++count;
  EXPECT_EQ(count, 1u) << err;
  EXPECT_NE(err.find("stopped refining 3 planes (the first of surface 'plate0'"), std::string::npos)
      << err;
  EXPECT_NE(err.find("triangles are thinner than the 20.7 degree bound (the thinnest "),
            std::string::npos)
      << err;
  double area = 0.0;
  for (const Patch& p : mesh.patches) area += p.area;
  EXPECT_NEAR(area, 3.0, 1e-12);
}

}  // namespace lambert
