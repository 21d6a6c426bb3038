// The hierarchical method against the matrix method on the built-in Cornell box.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/hierarchical/hierarchical.hpp"
#include "geometry/render/light_trace.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/obj_loader.hpp"
#include "pipeline/problem.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {
namespace {

// Per-surface area-weighted average radiosity.
std::vector<Eigen::Vector3d> surface_means(const PatchMesh& mesh, const Eigen::MatrixX3d& B) {
  std::vector<Eigen::Vector3d> out;
  for (const SurfaceRadiosity& s : surface_averages(mesh, B)) out.push_back(s.average);
  return out;
}

std::vector<Eigen::Vector3d> matrix_means(const Scene& scene, std::int64_t patches) {
  MeshOptions mo;
  mo.target_patches = patches;
  const PatchMesh mesh = mesh_scene(scene, mo);
  FormFactorOptions fo;
  fo.estimator = "hybrid";
  fo.pair.samples = 4;
  const FormFactors F = compute_form_factors(mesh, fo);
  SolveOptions so;
  so.tol = 1e-10;
  return surface_means(mesh, solve_radiosity(make_problem(mesh, F.F), so).B);
}

// The worst per-surface, per-channel relative difference of the hierarchical solution from
// the matrix method's (hybrid, 2000 patches, Gauss-Seidel to 1e-10) falls as epsilon falls,
// and at epsilon = 1e-5 (6.7k leaves) it is within 1 %, the bound. That bound is
// the size of the reference's own discretisation error (its per-surface averages move by up
// to 0.9 % from 2000 to 8000 patches, measured), so the methods agree as far as the
// reference can tell; hybrid's visibility noise on surface averages is < 1e-3 relative.
TEST(HierarchicalCornellSlow, AgreesWithTheMatrixMethodAndConvergesAsEpsilonFalls) {
  const Scene scene = load_obj(builtin_cornell_box_path());
  const auto ref = matrix_means(scene, 2000);
  std::vector<double> worst;
  for (double eps : {1e-3, 1e-4, 1e-5}) {
    HierarchicalOptions o;
    o.epsilon = eps;
    o.tol = 1e-9;
    const HierarchicalResult r = solve_hierarchical(scene, o);
    const auto m = surface_means(r.mesh, r.B);
    ASSERT_EQ(m.size(), ref.size());
    double w = 0;
    for (std::size_t s = 0; s < m.size(); ++s)
      for (int c = 0; c < 3; ++c)
        if (ref[s][c] > 0) w = std::max(w, std::abs(m[s][c] / ref[s][c] - 1));
    worst.push_back(w);
    // The energy balance is an identity of the link bookkeeping: emitted - absorbed -
    // escaped = sum A (E + rho H - B), the last sweep's residual, each leaf's B within
    // tol x max B = 1e-9 x 17 (the light) of its update; over the total area 5.6e6 against
    // the emitted 2.3e5 that is <= 17e-9 x 24 = 4e-7 relative.
    EXPECT_LT(r.stats.energy[0].relative_imbalance, 1e-6);
  }
  EXPECT_LT(worst[1], worst[0]);
  EXPECT_LT(worst[2], worst[1]);
  EXPECT_LE(worst[2], 0.01) << "worst per-surface difference at epsilon 1e-5";
}

// Issue 37, item 3 (hierarchical accurate by default): at its default settings the Cornell
// box is within 1 % worst per surface of an independent reference, light tracing (no F, no
// discretisation of B; geometry/render/light_trace.hpp). 2e7 photons give per-surface
// standard errors <= 8e-4 relative (measured; asserted below, <= 1.2e-3), so the bound is 1 %
// plus 4 of the reference's own standard errors. Measured: 0.78 % at the default 1e-5; the
// old default 1e-4 gave 1.96 % and fails here.
TEST(HierarchicalCornellSlow, DefaultIsWithinOnePercentOfLightTracing) {
  const Scene scene = load_obj(builtin_cornell_box_path());
  const HierarchicalResult h = solve_hierarchical(scene, HierarchicalOptions{});
  const auto m = surface_means(h.mesh, h.B);
  const PatchMesh faces = mesh_scene(scene, {});
  const LightTraceResult lt = light_trace(faces, Bvh(faces, 0), 20000000, 1, 0);
  ASSERT_EQ(m.size(), lt.surfaces.size());
  double worst = 0.0;
  for (std::size_t s = 0; s < m.size(); ++s)
    for (int c = 0; c < 3; ++c) {
      const double ref = lt.surfaces[s].average[c], se = lt.surfaces[s].stderr_[c] / ref;
      if (!(ref > 0)) continue;
      EXPECT_LE(se, 1.2e-3) << lt.surfaces[s].name;
      EXPECT_LE(std::abs(m[s][c] / ref - 1), 0.01 + 4 * se) << lt.surfaces[s].name << " " << c;
      worst = std::max(worst, std::abs(m[s][c] / ref - 1));
    }
  std::printf("worst per-surface difference to light tracing %.2f %%\n", 100 * worst);
}

TEST(HierarchicalCornellSlow, BitwiseIdenticalForAnyThreadCount) {
  // At the default epsilon the hierarchy has ~8,000 nodes and ~160,000 links: enough for
  // every parallel path (the push-pull's subtrees beside its serial top, the links' sort in
  // pieces and the merge along its path) to run in pieces, whose boundaries move with the
  // thread count; 3 threads is not a power of two.
  const Scene scene = load_obj(builtin_cornell_box_path());
  HierarchicalOptions o;
  o.threads = 1;
  const HierarchicalResult a = solve_hierarchical(scene, o);
  ASSERT_GT(a.stats.links, 100000);
  for (int threads : {2, 3}) {
    o.threads = threads;
    const HierarchicalResult b = solve_hierarchical(scene, o);
    ASSERT_EQ(a.B.rows(), b.B.rows());
    EXPECT_EQ(a.stats.rays, b.stats.rays);
    EXPECT_EQ(a.stats.links, b.stats.links);
    EXPECT_EQ(a.stats.iterations, b.stats.iterations);
    for (Eigen::Index i = 0; i < a.B.rows(); ++i)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(a.B(i, c), b.B(i, c)) << "leaf " << i;
    for (Eigen::Index i = 0; i < a.B.rows(); ++i)
      ASSERT_EQ(a.error_bound[i], b.error_bound[i]) << "leaf " << i;
  }
}

}  // namespace
}  // namespace lambert
