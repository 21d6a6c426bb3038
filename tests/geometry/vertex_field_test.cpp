#include "geometry/render/vertex_field.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "geometry/mesh/adapt.hpp"

namespace lambert {
namespace {

const Material kGreyWall{"white", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};

// A unit-ish open box (5 quads on one surface "box": creases at its edges), a trapezoid and
// a triangle on their own surfaces. All planar; exercises creases, non-parallelogram quads
// and triangle subdivision.
Scene test_scene() {
  Scene s;
  const Eigen::Vector3d p[8] = {{0, 0, 0},   {2, 0, 0},   {2, 1, 0},   {0, 1, 0},
                                {0, 0, 1.5}, {2, 0, 1.5}, {2, 1, 1.5}, {0, 1, 1.5}};
  add_polygon(s, "box", kGreyWall, {p[0], p[3], p[2], p[1]});  // z = 0
  add_polygon(s, "box", kGreyWall, {p[0], p[1], p[5], p[4]});  // y = 0
  add_polygon(s, "box", kGreyWall, {p[1], p[2], p[6], p[5]});  // x = 2
  add_polygon(s, "box", kGreyWall, {p[2], p[3], p[7], p[6]});  // y = 1
  add_polygon(s, "box", kGreyWall, {p[3], p[0], p[4], p[7]});  // x = 0
  add_polygon(s, "trapezoid", kGreyWall, {{3, 0, 0}, {5, 0, 0}, {4.5, 1, 0.3}, {3.2, 1, 0.3}});
  add_polygon(s, "triangle", kGreyWall, {{0, 3, 0}, {2, 3, 0.5}, {0.5, 4.5, 1}});
  return s;
}

// A linear function of position.
// A rotation off the axes, and the 3 x 2 rectangle "rect" rotated by it.
Eigen::Matrix3d tilt() {
  return Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
}
void add_tilted_rectangle(Scene& s, const Eigen::Matrix3d& R) {
  add_polygon(s, "rect", kGreyWall,
              {R * Eigen::Vector3d(0, 0, 0), R * Eigen::Vector3d(3, 0, 0),
               R * Eigen::Vector3d(3, 2, 0), R * Eigen::Vector3d(0, 2, 0)});
}

double linear(const Eigen::Vector3d& x) { return 2.0 + 0.7 * x.x() - 1.3 * x.y() + 0.4 * x.z(); }

// A smooth positive non-linear field (what radiosity looks like: gradients toward corners).
double smooth(const Eigen::Vector3d& x) {
  return 1.0 + x.x() * x.x() + 0.5 * std::sin(3 * x.y()) * x.z() + 0.5;
}

// A constant patch field gives that constant at every shading vertex, in both modes.
void expect_constant_field_exact(const PatchMesh& mesh) {
  const Eigen::RowVector3d b(1.0, 2.5, 0.125);
  const Eigen::MatrixX3d patch = b.replicate(mesh.size(), 1);
  for (auto mode : {VertexInterpolation::AreaWeighted, VertexInterpolation::Conservative}) {
    const VertexField f = interpolate_to_vertices(mesh, patch, mode);
    // Each value is sum(A_i b) / sum(A_i) over <= 8 patches: a few roundings of relative
    // 2^-53 each, so relative 1e-14 is ample; the rescale factor is 1 within the same, and
    // anchoring a hanging vertex, v_a + t (v_b - v_a), is exact for v_a = v_b.
    for (std::int32_t k = 0; k < f.size(); ++k)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(f.values(k, c), b[c], 1e-14 * b[c]);
  }
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
  expect_constant_field_exact(mesh_scene(test_scene(), {0.3, 0}));
}

TEST(VertexField, LinearFieldIsExactAtInteriorVerticesOfUniformGrids) {
  // A rectangle (uniform quad grid) and a triangle (similar-triangle subdivision), both
  // tilted off the axes. Patch value = mean of the linear field over the patch = its value at
  // the centroid; around an interior vertex the patches are point-symmetric, so the
  // area-weighted mean of their centroids is the vertex and the mean reproduces f exactly.
  Scene s;
  const Eigen::Matrix3d R = tilt();
  add_tilted_rectangle(s, R);
  add_polygon(
      s, "tri", kGreyWall,
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

// A graded mesh (what --adapt makes: a tilted rectangle's quads split in two, then the
// triangles near one corner bisected twice by longest-edge propagation) and a linear field.
// The area-weighted mean is off at vertices where large and small triangles meet (their
// centroids' weighted mean is not the vertex: O(H |∇f|), measured above 1e-3 here); the
// linear fit (LinearFit, what `run` shades an adapted mesh with) is exact at every interior
// vertex, up to the per-surface rescale it shares with Conservative (divided out: the
// boundary's corners keep the mean, so the scale is not exactly 1). 1e-12: rounding of
// the 2x2 least squares on coordinates <= 3 and values <= 10.
TEST(VertexField, LinearFitIsExactAtInteriorVerticesOfGradedMeshes) {
  Scene s;
  const Eigen::Matrix3d R = tilt();
  add_tilted_rectangle(s, R);
  PatchMesh mesh = triangulate_quads(mesh_scene(s, {0.4, 0})).mesh;
  const Eigen::Matrix3d Rinv = R.transpose();
  for (int round = 0; round < 2; ++round) {
    std::vector<char> marked(mesh.size(), 0);
    for (std::int32_t i = 0; i < mesh.size(); ++i) {
      const Eigen::Vector3d c = Rinv * mesh.patches[i].centroid;
      marked[i] = c.x() < 1.2 && c.y() < 1.0;
    }
    mesh = refine_marked(mesh, marked).mesh;
  }
  Eigen::MatrixX3d patch(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    patch.row(i).setConstant(linear(mesh.patches[i].centroid));
  std::vector<SurfacePower> power;
  const VertexField fit =
      interpolate_to_vertices(mesh, patch, VertexInterpolation::LinearFit, &power);
  const VertexField mean = interpolate_to_vertices(mesh, patch, VertexInterpolation::AreaWeighted);
  int interior = 0;
  double mean_worst = 0;
  for (std::int32_t k = 0; k < fit.size(); ++k) {
    const Eigen::Vector3d local = Rinv * fit.positions[k];
    const double eps = 1e-9;
    if (!(local.x() > eps && local.x() < 3 - eps && local.y() > eps && local.y() < 2 - eps))
      continue;
    ++interior;
    EXPECT_NEAR(fit.values(k, 0) / power[0].scale[0], linear(fit.positions[k]), 1e-12)
        << "vertex " << k;
    mean_worst = std::max(mean_worst, std::abs(mean.values(k, 0) - linear(fit.positions[k])));
  }
  EXPECT_GT(interior, 40);
  EXPECT_GT(mean_worst, 1e-3) << "the mesh is not graded enough to tell the fit from the mean";
  // Still conservative: the rescale makes the field's integral the patches' power.
  EXPECT_NEAR(power[0].field_power[0], power[0].patch_power[0], 1e-9 * power[0].patch_power[0]);
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
  add_polygon(s, "parallelogram", kGreyWall, {{0, 0, 0}, {3, 0, 0}, {4, 2, 1}, {1, 2, 1}});
  add_polygon(s, "triangles", kGreyWall, {{0, 3, 0}, {2, 3, 0.5}, {0.5, 4.5, 1}});
  add_polygon(s, "triangles", kGreyWall, {{2, 3, 0.5}, {2.5, 4.8, 1.2}, {0.5, 4.5, 1}});
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

namespace {

using Polygon = std::vector<Eigen::Vector3d>;

// The 4 children of an element as the hierarchical method splits it: a triangle into the 4
// similar triangles through its edge midpoints 0.5 (a + b) (the middle one last), a quad into
// 4 quads through its edge midpoints and its centre. Same winding as the parent.
std::vector<Polygon> split(const Polygon& e) {
  auto mid = [&](size_t a, size_t b) -> Eigen::Vector3d { return 0.5 * (e[a] + e[b]); };
  if (e.size() == 3) {
    const Eigen::Vector3d m01 = mid(0, 1), m12 = mid(1, 2), m20 = mid(2, 0);
    return {{e[0], m01, m20}, {m01, e[1], m12}, {m20, m12, e[2]}, {m01, m12, m20}};
  }
  const Eigen::Vector3d m01 = mid(0, 1), m12 = mid(1, 2), m23 = mid(2, 3), m30 = mid(3, 0);
  const Eigen::Vector3d c = 0.5 * (m01 + m23);
  return {{e[0], m01, c, m30}, {m01, e[1], m12, c}, {c, m12, e[2], m23}, {m30, c, m23, e[3]}};
}

// Replaces element `k` of `elements` by its 4 children (appended at the end).
void refine(std::vector<Polygon>& elements, size_t k) {
  const std::vector<Polygon> children = split(elements[k]);
  elements.erase(elements.begin() + static_cast<std::ptrdiff_t>(k));
  elements.insert(elements.end(), children.begin(), children.end());
}

// A PatchMesh of planar elements on one surface per list, vertices shared within a surface by
// exact position (as the hierarchical method's leaves are), never across surfaces.
PatchMesh build_mesh(const std::vector<std::vector<Polygon>>& surfaces) {
  PatchMesh mesh;
  for (size_t s = 0; s < surfaces.size(); ++s) {
    mesh.surface_names.push_back("s" + std::to_string(s));
    std::map<std::array<double, 3>, std::int32_t> ids;
    for (const Polygon& e : surfaces[s]) {
      Patch p;
      p.vertex_count = static_cast<int>(e.size());
      p.surface = static_cast<std::int32_t>(s);
      for (int k = 0; k < p.vertex_count; ++k) {
        const std::array<double, 3> key{e[k].x(), e[k].y(), e[k].z()};
        auto [it, added] = ids.emplace(key, static_cast<std::int32_t>(mesh.vertices.size()));
        if (added) {
          mesh.vertices.push_back(e[k]);
          mesh.vertex_surface.push_back(p.surface);
        }
        p.vertices[k] = it->second;
      }
      // A fan of triangles from corner 0 (planar, convex elements).
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      for (int k = 1; k + 1 < p.vertex_count; ++k) {
        const Eigen::Vector3d cross = (e[k] - e[0]).cross(e[k + 1] - e[0]);
        p.area += 0.5 * cross.norm();
        p.centroid += 0.5 * cross.norm() * (e[0] + e[k] + e[k + 1]) / 3.0;
        normal += cross;
      }
      p.centroid /= p.area;
      p.normal = normal.normalized();
      mesh.patches.push_back(p);
    }
  }
  return mesh;
}

// smooth() at the patch centroids, a different field per channel.
Eigen::MatrixX3d smooth_field(const PatchMesh& mesh) {
  Eigen::MatrixX3d b(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const double v = smooth(mesh.patches[i].centroid);
    b.row(i) << v, 2 * v, 0.5 + 0.1 * v;
  }
  return b;
}

// The interpolated field at x as patch i sees it: its weights times its corners' values.
Eigen::Vector3d value_from(const PatchMesh& mesh, const VertexField& f, std::int32_t i,
                           const Eigen::Vector3d& x) {
  const auto w = patch_weights(mesh, i, x);
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int k = 0; k < mesh.patches[i].vertex_count; ++k)
    v += w[k] * f.values.row(f.patch_corners[i][k]).transpose();
  return v;
}

// Distance from x to the segment [p, q].
double distance_to_segment(const Eigen::Vector3d& x, const Eigen::Vector3d& p,
                           const Eigen::Vector3d& q) {
  const double s = std::clamp((x - p).dot(q - p) / (q - p).squaredNorm(), 0.0, 1.0);
  return (x - (p + s * (q - p))).norm();
}

// The largest seam of a field: at points sampled along every patch edge, the largest
// difference between the values seen from that patch and from any other patch of the same
// surface, not across a crease, whose boundary holds the point.
struct Seam {
  double worst = 0.0;      // max |difference| over points and channels
  double magnitude = 0.0;  // max |value| seen
  int comparisons = 0;     // point pairs compared
};

Seam largest_seam(const PatchMesh& mesh, const VertexField& f) {
  const double cos_max = std::cos(kCreaseAngleDegrees * M_PI / 180.0);
  Seam seam;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const auto ci = mesh.corners(i);
    for (size_t k = 0; k < ci.size(); ++k) {
      for (double s : {0.06, 0.25, 0.43, 0.5, 0.71, 0.97}) {
        const Eigen::Vector3d x = (1 - s) * ci[k] + s * ci[(k + 1) % ci.size()];
        const Eigen::Vector3d vi = value_from(mesh, f, i, x);
        for (std::int32_t j = 0; j < mesh.size(); ++j) {
          if (j == i || mesh.patches[j].surface != mesh.patches[i].surface ||
              mesh.patches[j].normal.dot(mesh.patches[i].normal) < cos_max)
            continue;
          const auto cj = mesh.corners(j);
          bool on_boundary = false;
          // Sample points are off the edge by rounding only (~1e-16 here); 1e-12 of the unit
          // scale separates them from points off by a fraction of an element.
          for (size_t l = 0; l < cj.size(); ++l)
            on_boundary |= distance_to_segment(x, cj[l], cj[(l + 1) % cj.size()]) < 1e-12;
          if (!on_boundary) continue;
          const Eigen::Vector3d vj = value_from(mesh, f, j, x);
          seam.worst = std::max(seam.worst, (vi - vj).cwiseAbs().maxCoeff());
          seam.magnitude = std::max(seam.magnitude, vi.cwiseAbs().maxCoeff());
          ++seam.comparisons;
        }
      }
    }
  }
  return seam;
}

// Continuity tolerance, relative to the largest value |v|. A value seen from a patch is
// sum_k w_k v_k with sum_k w_k = 1, w_k >= 0: <= 4 eps |v| of rounding, plus the weights'
// error. Barycentric weights solve 2 x 2 normal equations: b and c share a relative error
// <= kappa eps (kappa the Gram matrix's condition, <= 25 for the thinnest triangle below,
// the tall T2's middle child) and w0 = 1 - b - c, so the value moves by <= kappa eps times
// corner differences <= 2 |v|; the quads' Gauss-Newton converges to rounding in (u, v). An
// anchored value v_a + t (v_b - v_a) adds 3 roundings, the rescale 1. Both sides together:
// <= 2 (4 + 2 x 25) eps + 4 eps = 112 eps: 128 eps (2.8e-14); seen: <= 3 eps. The cracks
// are 0.2 |v| without anchoring, 0.04 |v| with anchors in decreasing edge length order.
constexpr double kSeamTolerance = 128 * std::numeric_limits<double>::epsilon();

// The rule's promises on a mesh with hanging vertices: the field is continuous in both
// modes, Conservative keeps each surface's power to kPowerTolerance (derived in
// vertex_field.hpp), a constant stays exact.
void expect_crack_free(const PatchMesh& mesh) {
  for (auto mode : {VertexInterpolation::AreaWeighted, VertexInterpolation::Conservative}) {
    std::vector<SurfacePower> power;
    const VertexField f = interpolate_to_vertices(mesh, smooth_field(mesh), mode, &power);
    const Seam seam = largest_seam(mesh, f);
    EXPECT_GT(seam.comparisons, 0);
    EXPECT_LE(seam.worst, kSeamTolerance * seam.magnitude)
        << to_string(mode) << ": seam " << seam.worst << " of " << seam.magnitude;
    if (mode != VertexInterpolation::Conservative) continue;
    for (const auto& s : power) EXPECT_LE(s.relative_error(), kPowerTolerance) << s.name;
  }
  expect_constant_field_exact(mesh);
}

// A rotation that takes the test meshes off the axes (positions no longer dyadic).
const Eigen::Matrix3d kTilt =
    Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();

// Two unit squares side by side, the left one coarse, the right one split into 4 and its
// lower-left child split again: (1, 1/2) and (1, 1/4) hang on the coarse edge x = 1,
// (3/2, 1/4) on a fine edge, and (5/4, 1/2) on a fine edge whose end (1, 1/2) hangs itself
// (a chain).
PatchMesh squares() {
  std::vector<Polygon> e = {{kTilt * Eigen::Vector3d(0, 0, 0), kTilt * Eigen::Vector3d(1, 0, 0),
                             kTilt * Eigen::Vector3d(1, 1, 0), kTilt * Eigen::Vector3d(0, 1, 0)},
                            {kTilt * Eigen::Vector3d(1, 0, 0), kTilt * Eigen::Vector3d(2, 0, 0),
                             kTilt * Eigen::Vector3d(2, 1, 0), kTilt * Eigen::Vector3d(1, 1, 0)}};
  refine(e, 1);  // children 1..4, the lower-left one first
  refine(e, 1);
  return build_mesh({e});
}

// Two triangles on the edge (0,0)-(1,0): T1 below, coarse; T2 above, tall (height 2.5),
// split into 4, and its child at (1, 0) split again. The middle child's edge from (1/2, 0)
// to (3/4, 5/4) (length 1.27, longer than the coarse edge) holds a vertex whose end (1/2, 0)
// hangs on T1: ordering anchors by decreasing edge length would read that end before it is
// set.
PatchMesh triangle_chain() {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), below(0.5, -1, 0), above(0.5, 2.5, 0);
  std::vector<Polygon> e = {{kTilt * a, kTilt * below, kTilt * b},
                            {kTilt * a, kTilt * b, kTilt * above}};
  refine(e, 1);  // children 1..4: at a, at b, at the apex, middle
  refine(e, 2);  // the child at b
  return build_mesh({e});
}

// Triangles and quads on one surface: a fine trapezoid (split into 4) between a coarse
// triangle on its right and a triangle on its left split twice next to it. Tri-coarse /
// quad-fine and quad-fine / tri-finer, and a non-parallelogram quad.
PatchMesh mixed() {
  const Eigen::Vector3d q0(0, 0, 0), q1(1, 0.1, 0), q2(1, 0.9, 0), q3(0, 1, 0);
  std::vector<Polygon> e = {{kTilt * q0, kTilt * q1, kTilt * q2, kTilt * q3},
                            {kTilt * q1, kTilt * Eigen::Vector3d(2, 0.5, 0), kTilt * q2},
                            {kTilt * q0, kTilt * q3, kTilt * Eigen::Vector3d(-1, 0.5, 0)}};
  refine(e, 0);  // the trapezoid: [0] right triangle, [1] left triangle, [2..5] quads
  refine(e, 1);  // the left triangle: children [5..8]; [5] is at q0
  refine(e, 5);
  return build_mesh({e});
}

// The unanchored field of `mesh` as lambert computed it before hanging vertices: the
// area-weighted mean of the patches at each shading vertex, in patch order.
Eigen::MatrixX3d area_weighted_reference(const PatchMesh& mesh, const Eigen::MatrixX3d& b) {
  const VertexField f = build_shading_vertices(mesh);
  Eigen::MatrixX3d values = Eigen::MatrixX3d::Zero(f.size(), 3);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(f.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    for (int k = 0; k < mesh.patches[i].vertex_count; ++k) {
      values.row(f.patch_corners[i][k]) += mesh.patches[i].area * b.row(i);
      weight[f.patch_corners[i][k]] += mesh.patches[i].area;
    }
  }
  for (std::int32_t k = 0; k < f.size(); ++k)
    if (weight[k] > 0) values.row(k) /= weight[k];
  return values;
}

}  // namespace

TEST(HangingVertices, QuadsSplitNextToACoarseQuadAreContinuous) { expect_crack_free(squares()); }

TEST(HangingVertices, TriangleChainIsContinuous) { expect_crack_free(triangle_chain()); }

TEST(HangingVertices, MixedTrianglesAndQuadsAreContinuous) { expect_crack_free(mixed()); }

TEST(HangingVertices, FindsEveryVertexInsideAnotherPatchsEdge) {
  // squares(): (1, 1/2), (1, 1/4), (5/4, 1/2), (3/2, 1/4); triangle_chain(): (1/2, 0), (3/4, 0),
  // (5/8, 5/8); mixed(): the trapezoid's right midpoint (on the coarse triangle), a quarter
  // point of its left edge and the midpoint of the left triangle's middle child's edge.
  const std::pair<PatchMesh, size_t> cases[] = {
      {squares(), 4}, {triangle_chain(), 3}, {mixed(), 3}};
  for (const auto& [mesh, hanging] : cases)
    EXPECT_EQ(find_hanging_vertices(mesh, build_shading_vertices(mesh)).size(), hanging);
}

TEST(HangingVertices, AnchorsComeAfterTheAnchorsOfTheirEnds) {
  for (const PatchMesh& mesh : {squares(), triangle_chain(), mixed()}) {
    const VertexField f = build_shading_vertices(mesh);
    const auto hanging = find_hanging_vertices(mesh, f);
    std::vector<char> set(f.size(), 1);
    for (const auto& h : hanging) set[h.vertex] = 0;
    for (const auto& h : hanging) {
      EXPECT_TRUE(set[h.a] && set[h.b]) << "vertex " << h.vertex;
      set[h.vertex] = 1;
      // a and b are consecutive corners of the coarse patch, as it uses them.
      const auto& c = f.patch_corners[h.patch];
      const int n = mesh.patches[h.patch].vertex_count;
      bool edge = false;
      for (int k = 0; k < n; ++k) edge |= c[k] == h.a && c[(k + 1) % n] == h.b;
      EXPECT_TRUE(edge) << "vertex " << h.vertex;
      // h lies on the coarse edge at t: both sides are a few roundings of coordinates <= 7
      // (ulp 8.9e-16), so 1e-14 apart at most; a wrong t is off by >= 1/8 of an edge.
      const Eigen::Vector3d& xa = f.positions[h.a];
      const Eigen::Vector3d on_edge = xa + h.t * (f.positions[h.b] - xa);
      EXPECT_NEAR((on_edge - f.positions[h.vertex]).norm(), 0.0, 1e-14);
    }
  }
}

TEST(HangingVertices, OnlyVerticesWithinTheCreaseAngleAreAnchored) {
  // A floor split into 4 next to a coarse wall along y = 1, folded by `fold` degrees: the
  // floor's (1/2, 1, 0) lies on the wall's edge. Across a crease the field may jump.
  for (double fold : {10.0, 90.0}) {
    const double c = std::cos(fold * M_PI / 180.0), s = std::sin(fold * M_PI / 180.0);
    std::vector<Polygon> e = {{{0, 1, 0}, {1, 1, 0}, {1, 1 + c, s}, {0, 1 + c, s}},
                              {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}};
    refine(e, 1);
    const PatchMesh mesh = build_mesh({e});
    const auto hanging = find_hanging_vertices(mesh, build_shading_vertices(mesh));
    EXPECT_EQ(hanging.size(), fold < kCreaseAngleDegrees ? 1u : 0u) << fold << "°";
    if (fold < kCreaseAngleDegrees) expect_crack_free(mesh);
  }
}

TEST(HangingVertices, DependencyCycleFromInputTJunctionsTerminates) {
  // A pinwheel: four 1 x 2 rectangles around a unit square. Each rectangle's inner corner is
  // the midpoint of its neighbour's long edge, so the four T-junctions form a cycle
  // (2,1) <- (2,2) <- (1,2) <- (1,1) <- (2,1). One anchor is dropped, the other 3 are kept.
  auto rect = [](double x0, double y0, double x1, double y1) {
    return Polygon{{x0, y0, 0}, {x1, y0, 0}, {x1, y1, 0}, {x0, y1, 0}};
  };
  const PatchMesh mesh = build_mesh(
      {{rect(0, 0, 2, 1), rect(2, 0, 3, 2), rect(1, 2, 3, 3), rect(0, 1, 1, 3), rect(1, 1, 2, 2)}});
  const VertexField f = build_shading_vertices(mesh);
  EXPECT_EQ(find_hanging_vertices(mesh, f).size(), 3u);
  std::vector<SurfacePower> power;
  interpolate_to_vertices(mesh, smooth_field(mesh), VertexInterpolation::Conservative, &power);
  EXPECT_LE(power[0].relative_error(), kPowerTolerance);
}

TEST(HangingVertices, ConformingMeshIsBitwiseTheAreaWeightedMean) {
  // mesh_scene builds conforming meshes: no hanging vertex, and the output is exactly what the
  // area-weighted mean (and for Conservative its rescale) gave before hanging vertices.
  const PatchMesh mesh = mesh_scene(test_scene(), {0.2, 0});
  EXPECT_TRUE(find_hanging_vertices(mesh, build_shading_vertices(mesh)).empty());
  const Eigen::MatrixX3d b = smooth_field(mesh);
  const Eigen::MatrixX3d reference = area_weighted_reference(mesh, b);
  const VertexField area = interpolate_to_vertices(mesh, b, VertexInterpolation::AreaWeighted);
  EXPECT_TRUE(area.values == reference);
  std::vector<SurfacePower> power;
  const VertexField cons =
      interpolate_to_vertices(mesh, b, VertexInterpolation::Conservative, &power);
  const std::vector<SurfacePower> before = surface_power(mesh, b, area);
  for (size_t k = 0; k < power.size(); ++k)
    EXPECT_TRUE(power[k].area_weighted_power == before[k].field_power) << power[k].name;
  for (std::int32_t k = 0; k < cons.size(); ++k) {
    const Eigen::RowVector3d scaled =
        reference.row(k).array() * power[cons.surface[k]].scale.transpose().array();
    EXPECT_TRUE(cons.values.row(k) == scaled) << "vertex " << k;
  }
}

}  // namespace lambert
