// Discontinuity meshing on scenes loaded from files, and its effect on the radiosity.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "apps/adapt_stage.hpp"
#include "apps/problem.hpp"
#include "common/mesh_checks.hpp"
#include "geometry/adapt.hpp"
#include "geometry/analytic.hpp"
#include "geometry/discontinuity.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/shadow.hpp"
#include "geometry/vertex_field.hpp"
#include "io/obj_loader.hpp"
#include "solvers/radiosity.hpp"

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

// Solves the partial-shadow scene on `mesh` (hybrid: exact unoccluded factors times a
// visible fraction from 256 kernel-distributed rays per pair).
Eigen::MatrixX3d solve_partial_shadow(const PatchMesh& mesh) {
  FormFactorOptions fo;
  fo.estimator = "hybrid";
  fo.samples = 256;
  fo.progress = false;
  const FormFactors F = compute_form_factors(mesh, fo);
  SolveOptions so;
  so.tol = 1e-12;
  return solve_radiosity(make_problem(mesh, F.F), so).B;
}

// The exact floor radiosity of the partial-shadow scene at x (analytic.hpp).
double exact_floor(const Eigen::Vector3d& x) {
  const PartialShadowGeometry g = partial_shadow_geometry();
  return 0.5 * shadowed_point_factor(x, Eigen::Vector3d::UnitZ(), g.light, {g.blocker});
}

// The L1 error of the patch-constant floor radiosity against the exact field, over the
// floor's area: Σ_i ∫_i |B_i - B(x)| dA / A_floor, by the midpoint rule on 16 similar
// sub-triangles per patch (its own error is O(h²/16 B''), below the O(h B') measured).
double floor_error(const PatchMesh& mesh, const Eigen::MatrixX3d& B) {
  double sum = 0, area = 0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    if (p.surface != 0) continue;
    const Eigen::Vector3d a = mesh.vertices[p.vertices[0]], b = mesh.vertices[p.vertices[1]],
                          c = mesh.vertices[p.vertices[2]];
    const double bi = B.row(i).mean();
    double err = 0;
    const int n = 4;
    for (int u = 0; u < n; ++u)
      for (int v = 0; u + v < n; ++v) {
        const Eigen::Vector3d o = a + (b - a) * u / n + (c - a) * v / n;
        err += std::abs(bi - exact_floor(o + ((b - a) + (c - a)) / (3.0 * n)));
        if (u + v < n - 1) err += std::abs(bi - exact_floor(o + (2.0 * (b - a) + 2.0 * (c - a)) / (3.0 * n)));
      }
    sum += p.area * err / (n * n);
    area += p.area;
  }
  return sum / area;
}

// Adaptive meshing on the partial-shadow scene: the floor error falls round by round, and
// at the final patch count it is below the uniform mesh's with as many patches.
TEST(AdaptiveRadiosity, ImprovesMonotonicallyAndBeatsUniformAtEqualPatches) {
  const Scene scene = partial_shadow_scene();
  FormFactorArgs ff;
  ff.estimator = "hybrid";
  ff.samples = 256;
  RunArgs run;
  run.quiet = true;
  SolveOptions so;
  so.tol = 1e-12;
  std::vector<double> errors;
  std::int64_t final_patches = 0;
  for (int rounds = 1; rounds <= 3; ++rounds) {
    LoadedScene loaded;
    loaded.scene = scene;
    MeshOptions mo;
    mo.target_patches = 150;
    loaded.mesh = mesh_scene(scene, mo);
    AdaptArgs adapt;
    adapt.rounds = rounds;
    FormFactors F;
    RadiositySolution sol;
    const auto report = adapt_scene(loaded, ff, so, run, adapt, F, sol);
    ASSERT_EQ(static_cast<int>(report.size()), rounds + 1);
    test::expect_conforming(loaded.mesh);
    // A_i F_ij = A_j F_ji for the updated F (pair estimator: exact by construction).
    for (Eigen::Index i = 0; i < F.F.rows(); ++i)
      for (SparseF::InnerIterator it(F.F, i); it; ++it)
        ASSERT_NEAR(loaded.mesh.patches[i].area * it.value(),
                    loaded.mesh.patches[it.col()].area * F.F.coeff(it.col(), i),
                    1e-12 * loaded.mesh.patches[i].area * it.value());
    errors.push_back(floor_error(loaded.mesh, sol.B));
    final_patches = loaded.mesh.size();
  }
  MeshOptions uni;
  uni.target_patches = final_patches / 2;  // quads, then split in two like adaptive's start
  const PatchMesh um = triangulate_quads(mesh_scene(scene, uni)).mesh;
  const double e_uni = floor_error(um, solve_partial_shadow(um));
  std::printf("adaptive floor error by round: %.3g %.3g %.3g (%lld patches); uniform %.3g (%d)\n",
              errors[0], errors[1], errors[2], static_cast<long long>(final_patches), e_uni, um.size());
  EXPECT_LT(errors[1], errors[0]);
  EXPECT_LT(errors[2], errors[1]);
  EXPECT_LT(errors[2], e_uni);
}

}  // namespace
}  // namespace lambert
