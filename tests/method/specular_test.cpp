// Extended form factors (geometry/formfactors/specular.hpp): the image method through a
// plane mirror, transmission through an index-matched and a tinted dielectric, reciprocity,
// determinism, and the furnace / energy balance of closed boxes with a mirror wall.

#include "geometry/formfactors/specular.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "geometry/analytic.hpp"
#include "geometry/visibility/bvh.hpp"
#include "pipeline/problem.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {
namespace {

Material diffuse(double rho, double e = 0.0) {
  return {"diffuse", Eigen::Vector3d::Constant(rho), Eigen::Vector3d::Constant(e)};
}

Material mirror(double rho_s, double rho_d = 0.0) {
  Specular sp;
  sp.reflectance.setConstant(rho_s);
  return {"mirror", Eigen::Vector3d::Constant(rho_d), Eigen::Vector3d::Zero(), sp};
}

Material glass(double ior, double tf) {
  Specular sp;
  sp.dielectric = true;
  sp.ior = ior;
  sp.transmission.setConstant(tf);
  return {"glass", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), sp};
}

// A glass slab [lo, hi]² x [z0, z1]: a closed box of six faces wound outward.
void add_slab(Scene& s, const Material& g, double lo, double hi, double z0, double z1) {
  add_polygon(s, "slab", g, {{lo, lo, z0}, {lo, hi, z0}, {hi, hi, z0}, {hi, lo, z0}});
  add_polygon(s, "slab", g, {{lo, lo, z1}, {hi, lo, z1}, {hi, hi, z1}, {lo, hi, z1}});
  add_polygon(s, "slab", g, {{lo, lo, z0}, {hi, lo, z0}, {hi, lo, z1}, {lo, lo, z1}});
  add_polygon(s, "slab", g, {{lo, hi, z0}, {lo, hi, z1}, {hi, hi, z1}, {hi, hi, z0}});
  add_polygon(s, "slab", g, {{lo, lo, z0}, {lo, lo, z1}, {lo, hi, z1}, {lo, hi, z0}});
  add_polygon(s, "slab", g, {{hi, lo, z0}, {hi, hi, z0}, {hi, hi, z1}, {hi, lo, z1}});
}

FormFactors extended(const PatchMesh& mesh, const std::string& estimator, int rays,
                     std::uint64_t seed = 1, int threads = 0, int depth = 8) {
  FormFactorOptions o;
  o.estimator = estimator;
  o.pair.samples = 64;
  o.gather.rays = rays;
  o.specular.rays = rays;
  o.specular.depth = depth;
  o.run.seed = seed;
  o.run.threads = threads;
  o.run.with_stderr = true;
  o.run.progress = false;
  return compute_form_factors(mesh, o);
}

// The surface factor (area-weighted sum over the patches of two surfaces) and its
// standard error (entries independent: variances add).
std::pair<double, double> surface_factor(const PatchMesh& mesh, const FormFactors& ff,
                                         std::int32_t from, std::int32_t to) {
  double g = 0.0, var = 0.0, area = 0.0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    if (mesh.patches[i].surface != from) continue;
    area += mesh.patches[i].area;
    for (SparseF::InnerIterator it(ff.F, i); it; ++it) {
      if (mesh.patches[it.col()].surface != to) continue;
      g += mesh.patches[i].area * it.value();
      var += std::pow(mesh.patches[i].area * ff.stderr_F.coeff(i, it.col()), 2);
    }
  }
  return {g / area, std::sqrt(var) / area};
}

// Square a = [0,1]² and rectangle b = [1.5,2.5] x [0,0.6] side by side in z = 0 (facing
// +z: no direct exchange), under a plane mirror at z = kH facing down, large enough to hold
// every reflection point of a path from a to b.
constexpr double kH = 0.5;
Scene mirror_over_plates(double rho_s) {
  Scene s;
  add_polygon(s, "a", diffuse(0.5), {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  add_polygon(s, "b", diffuse(0.5), {{1.5, 0, 0}, {2.5, 0, 0}, {2.5, 0.6, 0}, {1.5, 0.6, 0}});
  add_polygon(s, "mirror", mirror(rho_s),
              {{-2, -2, kH}, {-2, 2.6, kH}, {4.5, 2.6, kH}, {4.5, -2, kH}});
  return s;
}

}  // namespace

// Image method: the mirror's image of b lies in z = 2 kH facing down, so a path a -> mirror
// -> b carries ρ_s times the factor from a to that image, Ehlert & Smith's offset formula.
// 4 standard errors (replicates, Student-t inflated): a false alarm below 1e-3.
TEST(ExtendedFormFactors, PlaneMirrorMatchesTheImageMethod) {
  const double rho_s = 0.8;
  const PatchMesh mesh = mesh_scene(mirror_over_plates(rho_s), {0.25, 0});
  const double G = parallel_rectangles_G(0, 1, 0, 1, 1.5, 2.5, 0, 0.6, 2 * kH);
  for (const std::string estimator : {"hybrid", "gather", "mc"}) {
    const FormFactors ff = extended(mesh, estimator, 4096);
    const auto [f_ab, se_ab] = surface_factor(mesh, ff, 0, 1);
    const auto [f_ba, se_ba] = surface_factor(mesh, ff, 1, 0);
    EXPECT_GT(se_ab, 0.0);
    EXPECT_NEAR(f_ab, rho_s * G / 1.0, 4 * se_ab) << estimator << " stderr " << se_ab;
    EXPECT_NEAR(f_ba, rho_s * G / 0.6, 4 * se_ba) << estimator << " stderr " << se_ba;
    EXPECT_GT(ff.stats.specular_rays, 0);
  }
}

// A_i F_ij = A_j F_ji for every entry of the extended F (direct part reciprocal by the pair
// estimator, specular part averaged from both ends): equal to rounding, 1e-12 relative.
TEST(ExtendedFormFactors, AreReciprocalEntryByEntry) {
  const PatchMesh mesh = mesh_scene(mirror_over_plates(0.9), {0.3, 0});
  const FormFactors ff = extended(mesh, "hybrid", 256);
  std::int64_t checked = 0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    for (SparseF::InnerIterator it(ff.F, i); it; ++it) {
      const auto j = static_cast<std::int32_t>(it.col());
      const double gij = mesh.patches[i].area * it.value();
      const double gji = mesh.patches[j].area * ff.F.coeff(j, i);
      EXPECT_NEAR(gij, gji, 1e-12 * gij) << i << " " << j;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

// Reversibility, the physics the averaging relies on: through a glass slab (index 1.5,
// Fresnel reflection at both faces, refraction, internal reflections) between two unequal
// parallel plates, each side's own estimate A_a S_ab and A_b S_ba (rays from a only, from b
// only) agree within 4 combined standard errors (independent streams), and carry most of
// the unoccluded G: Fresnel loses ~8 % at the four crossings near normal incidence while the
// slab brings b optically closer (apparent depth), so G_ab lies near the unoccluded value
// (measured 1.03 x), not below half of it.
TEST(ExtendedFormFactors, PathsThroughGlassAreReversibleFromEitherEnd) {
  Scene s;
  add_polygon(s, "a", diffuse(0.5), {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  add_polygon(s, "b", diffuse(0.5), {{0.2, 0.1, 1}, {0.2, 0.5, 1}, {0.8, 0.5, 1}, {0.8, 0.1, 1}});
  add_slab(s, glass(1.5, 1.0), -2, 3, 0.4, 0.6);
  const PatchMesh mesh = mesh_scene(s, {});  // one patch per face
  const Bvh bvh(mesh);
  FormFactorOptions o;
  o.specular.rays = 65536;
  o.run.with_stderr = true;
  o.run.progress = false;
  const ff::SpecularTransport sp = ff::compute_specular_transport(mesh, o, bvh, false);
  const double g_ab = 1.0 * sp.S.coeff(0, 1), g_ba = 0.24 * sp.S.coeff(1, 0);
  const double se = std::hypot(1.0 * sp.stderr_S.coeff(0, 1), 0.24 * sp.stderr_S.coeff(1, 0));
  ASSERT_GT(se, 0.0);
  EXPECT_NEAR(g_ab, g_ba, 4 * se) << "G from a " << g_ab << ", from b " << g_ba;
  const double unoccluded = parallel_rectangles_G(0, 1, 0, 1, 0.2, 0.8, 0.1, 0.5, 1.0);
  EXPECT_GT(g_ab, 0.5 * unoccluded);
  EXPECT_LT(g_ab, 1.5 * unoccluded);
}

// The same seed gives the same F bitwise for 1 and 2 threads.
TEST(ExtendedFormFactors, AreDeterministicForAnyThreadCount) {
  const PatchMesh mesh = mesh_scene(mirror_over_plates(0.9), {0.3, 0});
  const FormFactors one = extended(mesh, "gather", 64, 7, 1);
  const FormFactors two = extended(mesh, "gather", 64, 7, 2);
  ASSERT_EQ(one.F.nonZeros(), two.F.nonZeros());
  for (std::int64_t k = 0; k < one.F.nonZeros(); ++k)
    ASSERT_EQ(one.F.valuePtr()[k], two.F.valuePtr()[k]);
  EXPECT_EQ(one.specular_continued, two.specular_continued);
}

// A dielectric of index 1 (no Fresnel reflection, no bending) between two opposed unit
// squares lets everything through: F equals the unoccluded closed form; with Tf = 0.5 half
// of it (light enters the slab's front once). The slab: a closed box 0.1 thick, faces out.
TEST(ExtendedFormFactors, TransmitThroughIndexMatchedAndTintedGlass) {
  for (const double tf : {1.0, 0.5}) {
    Scene s = parallel_squares(1.0);  // "a" at z = 0 facing +z, "b" at z = 1 facing -z
    add_slab(s, glass(1.0, tf), -1, 2, 0.45, 0.55);
    const PatchMesh mesh = mesh_scene(s, {0.5, 0});
    const FormFactors ff = extended(mesh, "gather", 8192);
    const auto [f, se] = surface_factor(mesh, ff, 0, 1);
    EXPECT_GT(se, 0.0);
    // 4 standard errors, as above.
    EXPECT_NEAR(f, tf * kCubeOpposite, 4 * se) << "Tf " << tf << " stderr " << se;
  }
}

// Furnace with a mirror wall: the inside of the unit cube, five diffuse walls of ρ = 0.5 and
// E = 1 and a perfect mirror (ρ_s = 1, ρ_d = 0) for +z. Every path from a diffuse wall
// ends on a diffuse wall (a plane mirror cannot see itself), so each diffuse row of F sums
// to 1 over the diffuse columns and B = E / (1 − ρ) = 2. Two checks:
//  - statistics: each such row sum's deviation δ_i from 1 lies within 4 σ_i (σ_i the row's
//    entry standard errors summed in quadrature; a lossy or missed mirror would make δ
//    ~0.2, the mirror's share of the hemisphere);
//  - the solve: on the diffuse patches e = B − 2 solves e = ρ F e + ρ · 2 δ (the mirror's
//    B is 0), and ‖ρ F‖∞ ≤ ρ (1 + max δ), so ‖e‖∞ ≤ max|δ| / (1 − ρ (1 + max δ))
//    = 2 max|δ| / (1 − max δ) with the observed δ, plus the solver's tol · ‖E‖ / (1 − ρ).
TEST(ExtendedFormFactors, FurnaceWithAMirrorWallGivesEOverOneMinusRho) {
  Scene s = unit_cube();
  for (auto& m : s.materials) m = diffuse(0.5, 1.0);
  const auto mirror_surface = std::find_if(s.surfaces.begin(), s.surfaces.end(),
                                           [](const Surface& x) { return x.name == "+z"; });
  ASSERT_NE(mirror_surface, s.surfaces.end());
  mirror_surface->material = static_cast<std::int32_t>(s.materials.size());
  s.materials.push_back(mirror(1.0));
  const PatchMesh mesh = mesh_scene(s, {0.25, 0});
  const FormFactors ff = extended(mesh, "hybrid", 2048);
  double worst_delta = 0.0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    if (mesh.specular_of(i)) continue;
    double sum = 0.0, var = 0.0;
    for (SparseF::InnerIterator it(ff.F, i); it; ++it) {
      if (mesh.specular_of(static_cast<std::int32_t>(it.col()))) continue;
      sum += it.value();
      var += std::pow(ff.stderr_F.coeff(i, it.col()), 2);
    }
    ASSERT_GT(var, 0.0);
    EXPECT_NEAR(sum, 1.0, 4.0 * std::sqrt(var)) << "row " << i;
    worst_delta = std::max(worst_delta, std::abs(sum - 1.0));
  }
  SolveOptions so;
  so.solver = "gauss-seidel";
  so.tol = 1e-10;
  const RadiosityProblem problem = make_problem(mesh, ff);
  const RadiositySolution sol = solve_radiosity(problem, so);
  ASSERT_EQ(sol.status, SolveStatus::Converged);
  const double tol =
      2.0 * worst_delta / (1.0 - worst_delta) + so.tol * problem.emission.col(0).norm() / 0.5;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    if (mesh.specular_of(i)) {
      EXPECT_EQ(sol.B(i, 0), 0.0);  // ρ_d = 0, E = 0: the mirror has no diffuse radiosity
      continue;
    }
    EXPECT_NEAR(sol.B(i, 0), 2.0, tol) << "patch " << i << " max |delta| " << worst_delta;
  }
  // Energy: the box is closed, so what escapes is only the rows' deviation (|Σ A B δ| /
  // Σ A E ≤ 2 max|δ|), and the balance closes to the solver's residual.
  const EnergyBalance& e = sol.energy[0];
  EXPECT_NEAR(e.escaped / e.emitted, 0.0, 2.0 * worst_delta);
  EXPECT_LT(e.relative_imbalance, 1e-8);
}

// A mirror that also absorbs (ρ_s = 0.9): the balance counts what it absorbs (0.1 of
// what arrives) as absorbed, not as escaped: escaped stays at the row-sum error of the
// closed box while 10 % of the light reaching the mirror is absorbed there.
TEST(ExtendedFormFactors, EnergyBalanceCountsWhatAMirrorAbsorbs) {
  Scene s = unit_cube();
  for (auto& m : s.materials) m = diffuse(0.5, 1.0);
  s.surfaces[0].material = static_cast<std::int32_t>(s.materials.size());
  s.materials.push_back(mirror(0.9));
  const PatchMesh mesh = mesh_scene(s, {0.5, 0});
  const FormFactors ff = extended(mesh, "hybrid", 2048);
  SolveOptions so;
  so.tol = 1e-10;
  const RadiositySolution sol = solve_radiosity(make_problem(mesh, ff), so);
  const EnergyBalance& e = sol.energy[0];
  EXPECT_LT(e.relative_imbalance, 1e-8);
  // Row sums of a 0.5-edge cube mesh err by ~1e-3 (hybrid's quadrature and 2048 rays);
  // 0.01 of the emitted power is 10x that, and far below the mirror's absorbed share
  // (about 0.1 · 1/6 of the light in flight, several % of the emitted power).
  EXPECT_LT(std::abs(e.escaped) / e.emitted, 0.01);
}

// Coloured specular reflectance is refused for form factors (one weight for all channels).
TEST(ExtendedFormFactors, ColouredMirrorIsRefused) {
  Scene s = mirror_over_plates(0.5);
  s.materials[s.surfaces[2].material].specular.reflectance = Eigen::Vector3d(0.9, 0.5, 0.5);
  const PatchMesh mesh = mesh_scene(s, {0.5, 0});
  EXPECT_THROW(extended(mesh, "gather", 64), SceneError);
  // With depth 0 the mirror only receives and blocks: accepted, no specular rays.
  const FormFactors ff = extended(mesh, "gather", 64, 1, 0, 0);
  EXPECT_EQ(ff.stats.specular_rays, 0);
}

// The hemicube rasterises and cannot follow rays: refused unless depth is 0.
TEST(ExtendedFormFactors, HemicubeIsRefusedWithSpecularSurfaces) {
  const PatchMesh mesh = mesh_scene(mirror_over_plates(0.5), {0.5, 0});
  EXPECT_THROW(extended(mesh, "hemicube", 64), UsageError);
  EXPECT_NO_THROW(extended(mesh, "hemicube", 64, 1, 0, 0));
}

}  // namespace lambert
