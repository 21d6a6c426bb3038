#pragma once
// Checks of a PatchMesh shared by the tests: conformity, surface areas, triangle angles.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>

#include "geometry/mesh/mesh.hpp"
#include "geometry/polygon.hpp"
#include "geometry/scene.hpp"

namespace lambert::test {

/// Area of a surface's faces in the scene.
inline double scene_face_area(const Scene& s, std::int32_t surface) {
  double a = 0;
  for (const auto& f : s.faces) {
    if (f.surface != surface) continue;
    std::vector<Eigen::Vector3d> poly;
    for (auto v : f.vertices) poly.push_back(s.vertices[v]);
    a += polygon_area(poly);
  }
  return a;
}

/// Every surface's patches cover the area of its faces: |Σ A_i - A_faces| <= rel A + abs.
inline void expect_surface_areas(const Scene& scene, const PatchMesh& m, double rel, double abs) {
  for (size_t s = 0; s < scene.surfaces.size(); ++s) {
    double area = 0;
    for (const auto& p : m.patches)
      if (p.surface == static_cast<std::int32_t>(s)) area += p.area;
    EXPECT_NEAR(area, scene_face_area(scene, static_cast<std::int32_t>(s)), rel * area + abs)
        << scene.surfaces[s].name;
  }
}

// Every patch edge interior to a surface is shared by exactly two patches and no vertex of
// a surface lies strictly inside another patch edge of it (no T-vertices): checked by
// exact vertex ids (welded) and a distance test relative to the edge length. A non-manifold
// input (three faces on one edge) may have more than two patches on an edge.
inline void expect_conforming(const PatchMesh& m, bool manifold = true) {
  std::map<std::pair<int, int>, int> uses;
  for (const auto& p : m.patches)
    for (int k = 0; k < p.vertex_count; ++k) {
      int a = p.vertices[k], b = p.vertices[(k + 1) % p.vertex_count];
      uses[{std::min(a, b), std::max(a, b)}]++;
    }
  if (manifold) {
    for (const auto& [e, n] : uses) EXPECT_LE(n, 2);
  }
  for (const auto& [e, n] : uses) {
    const Eigen::Vector3d a = m.vertices[e.first], b = m.vertices[e.second];
    const double len = (b - a).norm();
    for (size_t v = 0; v < m.vertices.size(); ++v) {
      if (m.vertex_surface[v] != m.vertex_surface[e.first] || static_cast<int>(v) == e.first ||
          static_cast<int>(v) == e.second)
        continue;
      const Eigen::Vector3d p = m.vertices[v];
      const double u = (p - a).dot(b - a) / (len * len);
      if (u <= 1e-9 || u >= 1 - 1e-9) continue;
      ASSERT_GT((p - a - u * (b - a)).norm(), 1e-9 * len) << "T-vertex " << v;
    }
  }
}

// The smallest angle of a triangle patch, degrees.
inline double min_angle(const PatchMesh& m, const Patch& p) {
  double best = 180;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d a = m.vertices[p.vertices[k]], b = m.vertices[p.vertices[(k + 1) % 3]],
                          c = m.vertices[p.vertices[(k + 2) % 3]];
    best = std::min(best, std::acos(std::clamp((b - a).normalized().dot((c - a).normalized()), -1.0, 1.0)) * 180 / M_PI);
  }
  return best;
}

}  // namespace lambert::test
