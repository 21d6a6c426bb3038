// Discontinuity meshing on scenes loaded from files, and its effect on the radiosity.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "common/mesh_checks.hpp"
#include "geometry/discontinuity.hpp"
#include "io/obj_loader.hpp"

namespace lambert {
namespace {

using test::expect_conforming;
using test::scene_face_area;

TEST(DiscontinuityMesh, CornellBlocksGetContactLinesAlongTheirFootprints) {
  const Scene scene = load_obj(builtin_cornell_box_path());
  const auto segs = discontinuity_segments(scene, {});
  std::int32_t floor = -1;
  for (size_t s = 0; s < scene.surfaces.size(); ++s)
    if (scene.surfaces[s].name == "floor") floor = static_cast<std::int32_t>(s);
  ASSERT_GE(floor, 0);
  // The footprint edges: block face edges lying in y = 0.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> footprint;
  for (const auto& f : scene.faces) {
    const std::string& name = scene.surfaces[f.surface].name;
    if (name != "short_block" && name != "tall_block") continue;
    for (size_t k = 0; k < f.vertices.size(); ++k) {
      const Eigen::Vector3d a = scene.vertices[f.vertices[k]], b = scene.vertices[f.vertices[(k + 1) % f.vertices.size()]];
      if (a.y() == 0 && b.y() == 0) footprint.push_back({a, b});
    }
  }
  ASSERT_EQ(footprint.size(), 8u);  // two blocks, four sides each
  // Each footprint edge is covered by D0 lines on the floor (to 1e-9 of the box's size).
  for (const auto& [a, b] : footprint) {
    bool covered = false;
    for (const auto& s : segs) {
      if (s.order != 0 || scene.faces[s.face].surface != floor) continue;
      const bool same = ((s.a - a).norm() < 1e-6 && (s.b - b).norm() < 1e-6) ||
                        ((s.a - b).norm() < 1e-6 && (s.b - a).norm() < 1e-6);
      covered = covered || same;
    }
    EXPECT_TRUE(covered) << a.transpose() << " - " << b.transpose();
  }
  // The mesh has those edges (vertices at both ends of each footprint edge on the floor,
  // and no floor triangle straddles a footprint line inside the edge's extent).
  MeshOptions mo;
  mo.max_edge = 60;
  mo.discontinuity = true;
  const PatchMesh m = mesh_scene(scene, mo);
  expect_conforming(m);
  for (const auto& [a, b] : footprint) {
    const Eigen::Vector3d d = (b - a).normalized(), side = Eigen::Vector3d::UnitY().cross(d);
    for (const auto& p : m.patches) {
      if (p.surface != floor) continue;
      const double along = (p.centroid - a).dot(d);
      if (along <= 0 || along >= (b - a).norm()) continue;
      double lo = 0, hi = 0;
      for (int k = 0; k < 3; ++k) {
        const double s = (m.vertices[p.vertices[k]] - a).dot(side);
        lo = std::min(lo, s);
        hi = std::max(hi, s);
      }
      EXPECT_FALSE(lo < -1e-6 && hi > 1e-6) << "a floor triangle crosses a block's footprint";
    }
  }
  for (size_t s = 0; s < scene.surfaces.size(); ++s) {
    double area = 0;
    for (const auto& p : m.patches)
      if (p.surface == static_cast<std::int32_t>(s)) area += p.area;
    EXPECT_NEAR(area, scene_face_area(scene, static_cast<int>(s)), 1e-12 * area + 1e-9);
  }
}

}  // namespace
}  // namespace lambert
