#include "geometry/mesh.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <map>
#include <set>

#include "core/error.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

Material white() { return {"white", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()}; }

// A scene with a quad, a triangle, a concave L-shaped hexagon and a two-face surface
// whose faces share an edge, all in different orientations.
Scene mixed_scene() {
  Scene s;
  add_polygon(s, "quad", white(), {{0, 0, 0}, {3, 0, 0}, {3, 2, 0}, {0, 2, 0}});
  add_polygon(s, "tri", white(), {{0, 0, 1}, {0, 2.5, 1.2}, {1.7, 0.3, 2}});
  add_polygon(s, "ell", white(),
              {{0, 0, 5}, {2, 0, 5}, {2, 1, 5}, {1, 1, 5}, {1, 2, 5}, {0, 2, 5}});
  add_polygon(s, "pair", white(), {{0, 0, 9}, {1, 0, 9}, {1, 1, 9}, {0, 1, 9}});
  add_polygon(s, "pair", white(), {{1, 0, 9}, {2.5, 0, 9}, {1, 1, 9}});
  return s;
}

std::vector<double> surface_areas(const Scene& s) {
  std::vector<double> a(s.surfaces.size(), 0.0);
  for (const auto& f : s.faces) {
    std::vector<Eigen::Vector3d> poly;
    for (auto v : f.vertices) poly.push_back(s.vertices[v]);
    a[f.surface] += polygon_area(poly);
  }
  return a;
}

}  // namespace

TEST(Mesh, PreservesEverySurfaceAreaAndRespectsTheEdgeBound) {
  const Scene scene = mixed_scene();
  const auto exact = surface_areas(scene);
  for (double h : {10.0, 0.7, 0.31, 0.05}) {
    const PatchMesh mesh = mesh_scene(scene, {h, 0});
    std::vector<double> area(scene.surfaces.size(), 0.0);
    for (const auto& p : mesh.patches) {
      area[p.surface] += p.area;
      for (int k = 0; k < p.vertex_count; ++k) {
        const double len = (mesh.vertices[p.vertices[k]] -
                            mesh.vertices[p.vertices[(k + 1) % p.vertex_count]]).norm();
        // Sub-edges are exact fractions L/n <= h of the element edges, up to rounding.
        ASSERT_LE(len, h * (1 + 1e-12));
      }
    }
    for (size_t s = 0; s < exact.size(); ++s)
      EXPECT_NEAR(area[s], exact[s], 1e-12 * exact[s]) << "surface " << s << " h=" << h;
  }
}

TEST(Mesh, IsConformingWithinASurface) {
  // Every interior edge of a surface's patch mesh is shared by exactly two patches with
  // opposite orientation; boundary edges once. A T-junction would leave an edge used once
  // in the interior, so count: directed edges with no reverse twin must lie on the outline.
  const Scene scene = mixed_scene();
  const PatchMesh mesh = mesh_scene(scene, {0.3, 0});
  std::map<std::pair<int, int>, int> directed;
  for (const auto& p : mesh.patches) {
    if (p.surface != 3) continue;  // the two-face surface "pair"
    for (int k = 0; k < p.vertex_count; ++k)
      ++directed[{p.vertices[k], p.vertices[(k + 1) % p.vertex_count]}];
  }
  double unmatched_length = 0;
  for (const auto& [e, n] : directed) {
    EXPECT_EQ(n, 1);
    if (!directed.count({e.second, e.first}))
      unmatched_length += (mesh.vertices[e.first] - mesh.vertices[e.second]).norm();
  }
  // The outline of the union (unit square + triangle) is 2.5 + 1 + 1 + sqrt(1.5^2 + 1).
  EXPECT_NEAR(unmatched_length, 4.5 + std::sqrt(3.25), 1e-9);
}

TEST(Mesh, NormalsFollowTheWinding) {
  Scene s;
  add_polygon(s, "up", white(), {{0, 0, 0}, {1, 0, 0}, {1, 0, -1}, {0, 0, -1}});  // +y
  add_polygon(s, "down", white(), {{0, 0, 0}, {0, 0, -1}, {1, 0, -1}, {1, 0, 0}});  // -y
  const PatchMesh mesh = mesh_scene(s, {0.25, 0});
  for (const auto& p : mesh.patches) {
    const double expected = p.surface == 0 ? 1.0 : -1.0;
    EXPECT_NEAR(p.normal.y(), expected, 1e-15);
  }
}

TEST(Mesh, PatchCountTargetIsApproximatelyMet) {
  const Scene scene = mixed_scene();
  for (std::int64_t target : {100, 1000, 5000}) {
    const PatchMesh mesh = mesh_scene(scene, {0, target});
    // Counts move in steps as edge counts n jump; within 25 % of the target at these sizes.
    EXPECT_NEAR(static_cast<double>(mesh.size()), target, 0.25 * target);
  }
}

TEST(Mesh, HashDependsOnGeometryOnly) {
  Scene a = mixed_scene();
  Scene b = a;
  b.materials[0].rho = Eigen::Vector3d::Constant(0.1);
  EXPECT_EQ(mesh_hash(mesh_scene(a, {0.5, 0})), mesh_hash(mesh_scene(b, {0.5, 0})));
  EXPECT_NE(mesh_hash(mesh_scene(a, {0.5, 0})), mesh_hash(mesh_scene(a, {0.4, 0})));
}

}  // namespace lambert

namespace lambert {

TEST(Mesh, TinyMaxEdgeIsRefusedBeforeAllocating) {
  // 1e-6 on a unit-sized scene means ~1e12 patches: a clear UsageError, not an allocation.
  EXPECT_THROW(mesh_scene(mixed_scene(), {1e-6, 0}), UsageError);
}

}  // namespace lambert
