#include "geometry/vertex_field.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>

namespace lambert {
namespace {

const Material kWhite{"white", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};

// A unit-ish open box (5 quads on one surface "box": creases at its edges), a trapezoid and
// a triangle on their own surfaces. All planar; exercises creases, non-parallelogram quads
// and triangle subdivision.
Scene test_scene() {
  Scene s;
  const Eigen::Vector3d p[8] = {{0, 0, 0},   {2, 0, 0},   {2, 1, 0},   {0, 1, 0},
                                {0, 0, 1.5}, {2, 0, 1.5}, {2, 1, 1.5}, {0, 1, 1.5}};
  add_polygon(s, "box", kWhite, {p[0], p[3], p[2], p[1]});  // z = 0
  add_polygon(s, "box", kWhite, {p[0], p[1], p[5], p[4]});  // y = 0
  add_polygon(s, "box", kWhite, {p[1], p[2], p[6], p[5]});  // x = 2
  add_polygon(s, "box", kWhite, {p[2], p[3], p[7], p[6]});  // y = 1
  add_polygon(s, "box", kWhite, {p[3], p[0], p[4], p[7]});  // x = 0
  add_polygon(s, "trapezoid", kWhite, {{3, 0, 0}, {5, 0, 0}, {4.5, 1, 0.3}, {3.2, 1, 0.3}});
  add_polygon(s, "triangle", kWhite, {{0, 3, 0}, {2, 3, 0.5}, {0.5, 4.5, 1}});
  return s;
}

// A linear function of position.
double linear(const Eigen::Vector3d& x) { return 2.0 + 0.7 * x.x() - 1.3 * x.y() + 0.4 * x.z(); }

// A smooth positive non-linear field (what radiosity looks like: gradients toward corners).
double smooth(const Eigen::Vector3d& x) {
  return 1.0 + x.x() * x.x() + 0.5 * std::sin(3 * x.y()) * x.z() + 0.5;
}

}  // namespace

TEST(VertexField, SplitsAtSurfacesAndCreasesOnly) {
  const Scene s = test_scene();
  const PatchMesh mesh = mesh_scene(s, {0.25, 0});
  const VertexField f = build_shading_vertices(mesh);
  // Every box corner on the z = 0 face joins 3 faces at 90°: 3 shading vertices on one mesh
  // vertex. A vertex inside a face has one.
  std::map<std::int32_t, int> per_mesh_vertex;
  for (auto v : f.mesh_vertex) ++per_mesh_vertex[v];
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const auto& x = mesh.vertices[v];
    if (mesh.vertex_surface[v] != 0) {
      EXPECT_EQ(per_mesh_vertex[static_cast<std::int32_t>(v)], 1);
      continue;
    }
    // Grid points are computed as (1-u) a + u b: exact to a few ulps of the coordinates.
    auto on = [](double a, double b) { return std::abs(a - b) < 1e-12; };
    const int on_planes =
        (on(x.x(), 0) || on(x.x(), 2)) + (on(x.y(), 0) || on(x.y(), 1)) + on(x.z(), 0);
    const int expected = std::max(1, on_planes);
    EXPECT_EQ(per_mesh_vertex[static_cast<std::int32_t>(v)], expected)
        << "vertex " << x.transpose();
  }
  // Corner normals are the normals of the patches they belong to.
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    for (int k = 0; k < mesh.patches[i].vertex_count; ++k)
      EXPECT_GT(f.normals[f.patch_corners[i][k]].dot(mesh.patches[i].normal), 0.999);
}

TEST(VertexField, ConstantFieldIsExactInBothModes) {
  const PatchMesh mesh = mesh_scene(test_scene(), {0.3, 0});
  const Eigen::RowVector3d b(1.0, 2.5, 0.125);
  const Eigen::MatrixX3d patch = b.replicate(mesh.size(), 1);
  for (auto mode : {VertexInterpolation::AreaWeighted, VertexInterpolation::Conservative}) {
    const VertexField f = interpolate_to_vertices(mesh, patch, mode);
    // Each value is sum(A_i b) / sum(A_i) over <= 8 patches: a few roundings of relative
    // 2^-53 each, so relative 1e-14 is ample; the rescale factor is 1 within the same.
    for (std::int32_t k = 0; k < f.size(); ++k)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(f.values(k, c), b[c], 1e-14 * b[c]);
  }
}

TEST(VertexField, LinearFieldIsExactAtInteriorVerticesOfUniformGrids) {
  // A rectangle (uniform quad grid) and a triangle (similar-triangle subdivision), both
  // tilted off the axes. Patch value = mean of the linear field over the patch = its value at
  // the centroid; around an interior vertex the patches are point-symmetric, so the
  // area-weighted mean of their centroids is the vertex and the mean reproduces f exactly.
  Scene s;
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  add_polygon(s, "rect", kWhite,
              {R * Eigen::Vector3d(0, 0, 0), R * Eigen::Vector3d(3, 0, 0),
               R * Eigen::Vector3d(3, 2, 0), R * Eigen::Vector3d(0, 2, 0)});
  add_polygon(
      s, "tri", kWhite,
      {R * Eigen::Vector3d(4, 0, 0), R * Eigen::Vector3d(7, 0, 0), R * Eigen::Vector3d(5, 2.5, 0)});
  const PatchMesh mesh = mesh_scene(s, {0.4, 0});
  Eigen::MatrixX3d patch(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    patch.row(i).setConstant(linear(mesh.patches[i].centroid));
  const VertexField f = interpolate_to_vertices(mesh, patch, VertexInterpolation::AreaWeighted);
  const Eigen::Matrix3d Rinv = R.transpose();
  int interior = 0;
  for (std::int32_t k = 0; k < f.size(); ++k) {
    const Eigen::Vector3d local = Rinv * f.positions[k];
    const double eps = 1e-9;  // well inside: grid points are >= 0.25 from the boundary
    bool inside;
    if (f.surface[k] == 0) {
      inside = local.x() > eps && local.x() < 3 - eps && local.y() > eps && local.y() < 2 - eps;
    } else {
      // Inside the triangle (4,0)-(7,0)-(5,2.5): above y = 0 and left/right of the slanted edges.
      const double left = (local.x() - 4) * 2.5 - (local.y()) * 1.0;   // edge (4,0)->(5,2.5)
      const double right = (7 - local.x()) * 2.5 - (local.y()) * 2.0;  // edge (7,0)->(5,2.5)
      inside = local.y() > eps && left > eps && right > eps;
    }
    if (!inside) continue;
    ++interior;
    // |f| <= ~10 here; centroids and the weighted mean carry relative rounding ~1e-15 on
    // coordinates of size <= 7, i.e. absolute ~1e-14 in f: 1e-12 bounds it with margin.
    EXPECT_NEAR(f.values(k, 0), linear(f.positions[k]), 1e-12) << "vertex " << k;
  }
  EXPECT_GT(interior, 20);
}

TEST(VertexField, QuadIntegralIsExactForBilinearFieldsOnTrapezoids) {
  // On a planar quad a linear function of position is bilinear in (u, v), so setting the
  // corner values to f(corner) makes the interpolant equal f, and ∫ f dA = A f(centroid).
  const PatchMesh mesh = mesh_scene(test_scene(), {0.7, 0});
  VertexField f = build_shading_vertices(mesh);
  for (std::int32_t k = 0; k < f.size(); ++k) f.values.row(k).setConstant(linear(f.positions[k]));
  int quads = 0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    quads += p.vertex_count == 4;
    const double exact = p.area * linear(p.centroid);
    // Both sides are sums of 4 terms of size <= A·|f|; rounding <= ~1e-15 relative.
    EXPECT_NEAR(integrate_patch(mesh, f, i)[0], exact, 1e-12 * std::abs(exact) + 1e-15);
  }
  EXPECT_GT(quads, 0);
}

TEST(VertexField, ConservativeInterpolationConservesPowerPerSurface) {
  const PatchMesh mesh = mesh_scene(test_scene(), {0.2, 0});
  Eigen::MatrixX3d patch(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const double v = smooth(mesh.patches[i].centroid);
    patch.row(i) << v, 2 * v, 0.5 + 0.1 * v;
  }
  std::vector<SurfacePower> power;
  interpolate_to_vertices(mesh, patch, VertexInterpolation::Conservative, &power);
  ASSERT_EQ(power.size(), 3u);
  for (const auto& s : power) {
    // kPowerTolerance (1e-9) is derived in vertex_field.hpp from the rounding of the sums.
    EXPECT_LE(s.relative_error(), kPowerTolerance) << s.name;
    EXPECT_GT(s.area, 0.0);
  }
  // Without the rescale the trapezoid (not a parallelogram: corner masses differ from A/4)
  // loses power well above rounding: this is what the rescale is for.
  EXPECT_GT(power[1].area_weighted_relative_error(), 1e-6) << power[1].name;
  // Area-weighted mode reports the same powers it leaves unscaled.
  interpolate_to_vertices(mesh, patch, VertexInterpolation::AreaWeighted, &power);
  for (const auto& s : power) {
    EXPECT_EQ(s.field_power, s.area_weighted_power);
    EXPECT_EQ(s.scale, Eigen::Vector3d::Ones());
  }
}

TEST(VertexField, AreaWeightedConservesPowerOnTrianglesAndParallelograms) {
  // ∫ f dA = sum_k v_k m_k with lumped masses m_k = sum_{i ∋ k} A_i / c when every patch at k
  // has c corners with hat integrals A_i / c (triangles; parallelogram quads); then
  // ∫ f dA = sum_i A_i b_i exactly (derivation in vertex_field.hpp), for any field.
  Scene s;
  add_polygon(s, "parallelogram", kWhite, {{0, 0, 0}, {3, 0, 0}, {4, 2, 1}, {1, 2, 1}});
  add_polygon(s, "triangles", kWhite, {{0, 3, 0}, {2, 3, 0.5}, {0.5, 4.5, 1}});
  add_polygon(s, "triangles", kWhite, {{2, 3, 0.5}, {2.5, 4.8, 1.2}, {0.5, 4.5, 1}});
  const PatchMesh mesh = mesh_scene(s, {0.2, 0});
  Eigen::MatrixX3d patch(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    patch.row(i).setConstant(smooth(mesh.patches[i].centroid));
  std::vector<SurfacePower> power;
  interpolate_to_vertices(mesh, patch, VertexInterpolation::AreaWeighted, &power);
  ASSERT_EQ(power.size(), 2u);
  // Both sides are sums of ~10^3 positive terms: relative rounding <= 10^3 · 2^-53 ≈ 1e-13.
  for (const auto& p : power) EXPECT_LE(p.relative_error(), 1e-12) << p.name;
}

TEST(VertexField, PatchWeightsReproduceThePointOnTrianglesAndQuads) {
  const PatchMesh mesh = mesh_scene(test_scene(), {0.6, 0});
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    const auto c = mesh.corners(i);
    // A point inside: a convex combination of the corners.
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    const double lam[4] = {0.1, 0.2, 0.3, 0.4};
    double sum = 0;
    for (int k = 0; k < p.vertex_count; ++k) sum += lam[k];
    for (int k = 0; k < p.vertex_count; ++k) x += lam[k] / sum * c[k];
    const auto w = patch_weights(mesh, i, x);
    Eigen::Vector3d back = Eigen::Vector3d::Zero();
    double wsum = 0;
    for (int k = 0; k < p.vertex_count; ++k) {
      back += w[k] * c[k];
      wsum += w[k];
      EXPECT_GE(w[k], 0.0);
    }
    // Newton converges to 1e-13 in (u, v) on a patch of size <= 1: position error ~1e-13.
    EXPECT_NEAR((back - x).norm(), 0.0, 1e-11);
    EXPECT_NEAR(wsum, 1.0, 1e-14);
  }
}

}  // namespace lambert
