#include "geometry/formfactors/gather.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "geometry/analytic.hpp"
#include "geometry/formfactors/reciprocity.hpp"

namespace lambert {
namespace {

Material plate() { return {"plate", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()}; }

FormFactors gather(const PatchMesh& mesh, int rays, std::uint64_t seed = 1,
                   const std::string& reciprocity = "none", int threads = 0) {
  FormFactorOptions o;
  o.estimator = "gather";
  o.gather.rays = rays;
  o.run.seed = seed;
  o.run.threads = threads;
  o.reciprocity = reciprocity;
  o.run.with_stderr = rays >= 4;
  o.run.progress = false;
  return compute_form_factors(mesh, o);
}

FormFactors gather(const Scene& scene, int rays, std::uint64_t seed = 1,
                   const std::string& reciprocity = "none") {
  return gather(mesh_scene(scene, {}), rays, seed, reciprocity);
}

// Rectangle a = [0,1] x [0,2] at z = 0 (facing +z) and b = [0.5,2] x [0.3,1.1] at z = h
// (facing -z): unequal sizes and a lateral offset.
constexpr double kH = 0.7;
Scene offset_rectangles() {
  Scene s;
  add_polygon(s, "a", plate(), {{0, 0, 0}, {1, 0, 0}, {1, 2, 0}, {0, 2, 0}});
  add_polygon(s, "b", plate(), {{0.5, 0.3, kH}, {0.5, 1.1, kH}, {2, 1.1, kH}, {2, 0.3, kH}});
  return s;
}

double row_sum(const SparseF& F, Eigen::Index i) {
  double s = 0.0;
  for (SparseF::InnerIterator it(F, i); it; ++it) s += it.value();
  return s;
}

}  // namespace

// Every check against a closed form uses the estimator's own standard error (replicates,
// Student-t inflated by 1.19): 4 of them is a two-sided false alarm of < 1e-3 even for the
// t law with 15 degrees of freedom.
TEST(FormFactorGather, ParallelUnitSquaresMatchHowell) {
  const FormFactors ff = gather(parallel_squares(1.0), 4096);
  const double f = ff.F.coeff(0, 1), se = ff.stderr_F.coeff(0, 1);
  EXPECT_GT(se, 0.0);
  EXPECT_NEAR(f, kCubeOpposite, 4 * se) << "stderr " << se;
  // Reciprocal by symmetry here: the other row estimates the same factor.
  EXPECT_NEAR(ff.F.coeff(1, 0), kCubeOpposite, 4 * ff.stderr_F.coeff(1, 0));
}

TEST(FormFactorGather, PerpendicularSquaresSharingAnEdgeMatchHowell) {
  const FormFactors ff = gather(perpendicular_squares(), 4096);
  const double f = ff.F.coeff(0, 1), se = ff.stderr_F.coeff(0, 1);
  EXPECT_GT(se, 0.0);
  EXPECT_NEAR(f, kCubeAdjacent, 4 * se) << "stderr " << se;
}

TEST(FormFactorGather, UnequalOffsetRectanglesMatchTheCornerSumBothWays) {
  const double G = parallel_rectangles_G(0, 1, 0, 2, 0.5, 2, 0.3, 1.1, kH);
  const double area_a = 2.0, area_b = 1.5 * 0.8;
  for (const std::string mode : {"none", "average"}) {
    const FormFactors ff = gather(offset_rectangles(), 8192, 3, mode);
    EXPECT_NEAR(ff.F.coeff(0, 1), G / area_a, 4 * ff.stderr_F.coeff(0, 1)) << mode;
    EXPECT_NEAR(ff.F.coeff(1, 0), G / area_b, 4 * ff.stderr_F.coeff(1, 0)) << mode;
  }
}

TEST(FormFactorGather, EnclosedCubeRowsSumToOne) {
  // Inside a closed cube every ray lands on the front of another face (the faces meet
  // exactly and Embree's robust mode is watertight), so a row sums to exactly the number
  // of rays that hit, / K: 1 up to rounding of the sum of K terms of 1/K (K · 1.1e-16),
  // or lower by 1/K per ray lost through an edge. Allow 2 lost rays.
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.34, 0});  // 3x3 patches per face
  constexpr int kRays = 1024;
  const FormFactors ff = gather(mesh, kRays);
  for (Eigen::Index i = 0; i < mesh.size(); ++i) {
    const double s = row_sum(ff.F, i);
    EXPECT_LE(s, 1.0 + 1e-12) << "row " << i;
    EXPECT_GE(s, 1.0 - 2.0 / kRays) << "row " << i;
  }
  // Averaged: balancing restores every row's own sum (reciprocity.hpp), here 1, to its
  // tolerance 1e-12 plus the rounding of the row sum; the plain mean would miss it by the
  // column's noise (±2 % at this K).
  const FormFactors avg = gather(mesh, kRays, 1, "average");
  for (Eigen::Index i = 0; i < mesh.size(); ++i) {
    const double s = row_sum(avg.F, i), raw = row_sum(ff.F, i);
    EXPECT_NEAR(s, std::min(raw, 1.0), 1e-11) << "row " << i;
  }
  EXPECT_EQ(avg.stats.reciprocity_rows_scaled, 0);  // nothing left for the cap
}

TEST(FormFactorGather, ErrorFallsAtLeastLikeOneOverSqrtRays) {
  // RMS error over 16 seeds at K = 256 and 4096: an unbiased estimator with i.i.d. rays
  // improves by sqrt(16) = 4; the stratified lattice at least as fast. The RMS over 16
  // seeds is uncertain by ~1/sqrt(2·16) = 18 %; the ratio of two by ~25 %: allow 4 · 0.7.
  // A bias b would floor the RMS at K = 4096 at |b|: the ratio also bounds it.
  auto rms = [](int K) {
    double s2 = 0.0;
    for (std::uint64_t seed = 1; seed <= 16; ++seed) {
      const double e = gather(perpendicular_squares(), K, seed).F.coeff(0, 1) - kCubeAdjacent;
      s2 += e * e;
    }
    return std::sqrt(s2 / 16);
  };
  const double e1 = rms(256), e2 = rms(4096);
  EXPECT_GE(e1 / e2, 4.0 * 0.7) << "rms " << e1 << " -> " << e2;
}

TEST(FormFactorGather, BitwiseIdenticalForAnyThreadCount) {
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.2, 0});
  const FormFactors ref = gather(mesh, 256, 7, "average", 1);
  for (int threads : {2, 5}) {
    const FormFactors ff = gather(mesh, 256, 7, "average", threads);
    ASSERT_EQ(ff.F.nonZeros(), ref.F.nonZeros()) << threads;
    for (std::int64_t k = 0; k < ref.F.nonZeros(); ++k) {
      EXPECT_EQ(ff.F.valuePtr()[k], ref.F.valuePtr()[k]);
      EXPECT_EQ(ff.F.innerIndexPtr()[k], ref.F.innerIndexPtr()[k]);
      EXPECT_EQ(ff.stderr_F.valuePtr()[k], ref.stderr_F.valuePtr()[k]);
    }
    for (Eigen::Index i = 0; i <= mesh.size(); ++i)
      EXPECT_EQ(ff.F.outerIndexPtr()[i], ref.F.outerIndexPtr()[i]);
  }
}

// A row's sums go through a dense accumulator without standard errors (read back by a scan
// in column order when many patches were touched, else by sorting the touched columns) and
// through a stable sort by column with them: each entry summed in hit order either way, so F
// is bitwise the same. 2,400 patches: K = 8 rays touch few (the sort), K = 128 many (the scan).
TEST(FormFactorGather, RowsAreBitwiseTheSameWithOrWithoutErrors) {
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.05, 0});
  ASSERT_EQ(mesh.size(), 2400);
  for (const int rays : {8, 128}) {
    FormFactorOptions o;
    o.estimator = "gather";
    o.gather.rays = rays;
    o.reciprocity = "none";
    o.run.progress = false;
    o.run.with_stderr = true;
    const FormFactors with = compute_form_factors(mesh, o);
    o.run.with_stderr = false;
    const FormFactors without = compute_form_factors(mesh, o);
    ASSERT_EQ(with.F.nonZeros(), without.F.nonZeros()) << rays;
    for (std::int64_t k = 0; k < with.F.nonZeros(); ++k) {
      ASSERT_EQ(with.F.valuePtr()[k], without.F.valuePtr()[k]) << rays << " entry " << k;
      ASSERT_EQ(with.F.innerIndexPtr()[k], without.F.innerIndexPtr()[k]) << rays;
    }
    for (Eigen::Index i = 0; i <= mesh.size(); ++i)
      ASSERT_EQ(with.F.outerIndexPtr()[i], without.F.outerIndexPtr()[i]) << rays;
  }
}

// Gather's direct light (gather.hpp): with few emitting patches each pair with an emitter is
// the hybrid kernel's, the other rays' share scaled to the rest of the hemisphere. In a
// closed cube with two of the lamp face's 25 patches emitting: the emitter entries are the
// hybrid's (no occlusion in a cube: both are the exact unoccluded integral, to quadrature:
// 1e-9 relative covers the rounding of the visible fraction), an emitter's row sums to 1
// within the quadrature's 1e-6 per pair (25 x 6 pairs: 1e-5), every other row to exactly 1
// as before (the scale s = (1 - h) / (1 - f_E) makes the rays that reach a front fill the
// rest of the hemisphere; -2/K allows two rays lost through an edge), and the result is
// bitwise the same for any thread count.
TEST(FormFactorGather, EmitterPairsAreHybridsAndClosedRowsStillSumToOne) {
  PatchMesh mesh = mesh_scene(unit_cube(), {0.2, 0});  // 5x5 patches per face
  std::vector<char> emitter(mesh.size(), 0);
  int lamps = 0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    Patch& p = mesh.patches[i];
    if (p.emission.maxCoeff() > 0 && lamps++ < 2) {
      emitter[i] = 1;
    } else {
      p.emission.setZero();
    }
  }
  constexpr int kRays = 1024;
  ASSERT_TRUE(ff::gather_direct_pairs(2, mesh.size(), kRays));
  const FormFactors g = gather(mesh, kRays, 3, "none", 1);
  FormFactorOptions ho;
  ho.estimator = "hybrid";
  ho.run.progress = false;
  const FormFactors hy = compute_form_factors(mesh, ho);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const double s = row_sum(g.F, i);
    if (emitter[i]) {
      EXPECT_NEAR(s, 1.0, 1e-5) << "emitter row " << i;
    } else {
      EXPECT_LE(s, 1.0 + 1e-12) << "row " << i;
      EXPECT_GE(s, 1.0 - 2.0 / kRays) << "row " << i;
    }
    for (std::int32_t j = 0; j < mesh.size(); ++j) {
      if (!(emitter[i] || emitter[j]) || i == j) continue;
      EXPECT_NEAR(g.F.coeff(i, j), hy.F.coeff(i, j), 1e-9 * hy.F.coeff(i, j)) << i << " " << j;
    }
  }
  // Averaged (gather's default): the emitter pairs are held, the other pairs balanced around
  // them, so every row keeps its own sum and the emitter entries stay the hybrid's. 1e-9:
  // the balance meets its 1e-12 on the rows' free parts, but rows summing to 1 are left
  // 1e-11 to 1e-10 below it here (measured; without held pairs 1e-11, EnclosedCube... above).
  // Not investigated further (issue 35 item 7 notes); far below the estimator's error.
  const FormFactors avg = gather(mesh, kRays, 3, "average", 1);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    EXPECT_NEAR(row_sum(avg.F, i), std::min(row_sum(g.F, i), 1.0), 1e-9) << "row " << i;
    for (std::int32_t j = 0; j < mesh.size(); ++j) {
      if (!(emitter[i] || emitter[j]) || i == j) continue;
      EXPECT_NEAR(avg.F.coeff(i, j), hy.F.coeff(i, j), 1e-9 * hy.F.coeff(i, j)) << i << " " << j;
    }
  }
  const FormFactors g3 = gather(mesh, kRays, 3, "none", 3);
  ASSERT_EQ(g3.F.nonZeros(), g.F.nonZeros());
  for (std::int64_t k = 0; k < g.F.nonZeros(); ++k) {
    EXPECT_EQ(g3.F.valuePtr()[k], g.F.valuePtr()[k]);
    EXPECT_EQ(g3.stderr_F.valuePtr()[k], g.stderr_F.valuePtr()[k]);
  }
}

namespace {

// The lit floor patches' light factors from gather (with `reciprocity`) against hybrid's.
void direct_light_of_lit_patches_is_exact(const std::string& reciprocity) {
  MeshOptions mo;
  mo.target_patches = 600;
  const PatchMesh mesh = mesh_scene(partial_shadow_scene(), mo);
  const FormFactors g = gather(mesh, 1024, 1, reciprocity);
  FormFactorOptions ho;
  ho.estimator = "hybrid";
  ho.run.progress = false;
  const FormFactors hy = compute_form_factors(mesh, ho);
  int lit = 0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    if (mesh.surface_names[p.surface] != "floor") continue;
    // Fully lit: beyond the shadow's far edge y = 2.7 (partial_shadow_lines).
    bool beyond = true;
    for (int k = 0; k < p.vertex_count; ++k)
      beyond = beyond && mesh.vertices[p.vertices[k]].y() > 2.7;
    if (!beyond) continue;
    double f = 0, ref = 0;
    for (std::int32_t j = 0; j < mesh.size(); ++j)
      if (mesh.surface_names[mesh.patches[j].surface] == "light") {
        f += g.F.coeff(i, j);
        ref += hy.F.coeff(i, j);
      }
    ASSERT_GT(ref, 0.0);
    EXPECT_NEAR(f, ref, 1e-9 * ref) << "floor patch " << i;
    ++lit;
  }
  EXPECT_GT(lit, 50);
}

}  // namespace

// The mottle of issue 35 item 7: with K = 1024 rays a floor patch saw the light through
// some 50 of them (±10 % per patch, visible as blotches on the Cornell walls at 8,000
// patches). Now the lit floor patches of the partial-shadow scene get their light factors
// from the hybrid kernel: exact for unoccluded pairs, so they equal a hybrid run's to
// rounding (1e-9 relative), not to ±10 %; also after reciprocity averaging (gather's
// default), whose balance holds those pairs as they are.
TEST(FormFactorGather, DirectLightOfLitPatchesIsExactNotSampled) {
  for (const std::string reciprocity : {"none", "average"}) {
    SCOPED_TRACE(reciprocity);
    direct_light_of_lit_patches_is_exact(reciprocity);
  }
}

TEST(FormFactorGather, BacksAndMissesCountForNothing) {
  // b above a faces +z (away from a): a's rays hit b's back, which absorbs.
  Scene s;
  add_polygon(s, "a", plate(), {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  add_polygon(s, "b", plate(), {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}});
  const FormFactors ff = gather(s, 512);
  EXPECT_EQ(ff.F.nonZeros(), 0);
  EXPECT_EQ(ff.stats.rays, 2 * 512);
  EXPECT_EQ(ff.stats.pairs_tested, 0);
}

TEST(Reciprocity, AveragingIsReciprocalAndKeepsRowSumsAtMostOne) {
  // A small patch 0 (area 0.01) under a big one (area 4): F_01 = 0.95 and an overestimated
  // F_10 = 0.01 (true 0.0024). The plain mean G = (0.0095 + 0.04) / 2 would give
  // F_01 = 2.475 > 1. Patch 2 (area 1) sees only patch 1, one-sided: its mirror is created.
  // The pattern (0 - 1 - 2, a chain) cannot be balanced exactly (A_0 t_0 + A_2 t_2 would
  // have to equal A_1 t_1), so the cap has the last word.
  const std::vector<double> areas = {0.01, 4.0, 1.0};
  SparseF F(3, 3), S(3, 3);
  F.insert(0, 1) = 0.95;
  F.insert(1, 0) = 0.01;
  F.insert(2, 1) = 0.4;
  S.insert(0, 1) = 0.01;
  S.insert(1, 0) = 0.002;
  S.insert(2, 1) = 0.03;
  F.makeCompressed();
  S.makeCompressed();
  FormFactorStats stats;
  ff::average_reciprocal(F, &S, areas, stats);
  ASSERT_EQ(F.nonZeros(), 4);
  ASSERT_EQ(S.nonZeros(), 4);
  EXPECT_GT(F.coeff(1, 2), 0.0);  // the mirror
  for (int i = 0; i < 3; ++i) {
    EXPECT_LE(row_sum(F, i), 1.0 + 1e-15) << i;  // rounding of one division
    for (SparseF::InnerIterator it(F, i), st(S, i); it; ++it, ++st) {
      const double gij = areas[i] * it.value(), gji = areas[it.col()] * F.coeff(it.col(), i);
      EXPECT_NEAR(gij, gji, 4e-16 * gij);  // the same G divided and multiplied: 2 ulps
      EXPECT_TRUE(std::isfinite(st.value()) && st.value() > 0.0);
      // Errors follow their entries: A_i s_ij = A_j s_ji too.
      EXPECT_NEAR(areas[i] * st.value(), areas[it.col()] * S.coeff(it.col(), i),
                  4e-16 * areas[i] * st.value());
    }
  }
  EXPECT_GT(stats.reciprocity_mean_relative_change, 0.0);
  EXPECT_GT(stats.reciprocity_max_relative_change, 0.0);  // (the mean also counts created mirrors)
}

TEST(Reciprocity, BalancedPairKeepsTheMeanAndCombinesTheErrors) {
  // Equal areas, F_01 = F_10 = 0.5: the mean is already balanced (d = 1), so the values
  // stay and the errors combine as sqrt(s_01² + s_10²) / 2.
  const std::vector<double> areas = {1.0, 1.0};
  SparseF F(2, 2), S(2, 2);
  F.insert(0, 1) = 0.5;
  F.insert(1, 0) = 0.5;
  S.insert(0, 1) = 0.1;
  S.insert(1, 0) = 0.2;
  F.makeCompressed();
  S.makeCompressed();
  FormFactorStats stats;
  ff::average_reciprocal(F, &S, areas, stats);
  EXPECT_EQ(F.coeff(0, 1), 0.5);
  EXPECT_EQ(F.coeff(1, 0), 0.5);
  EXPECT_DOUBLE_EQ(S.coeff(0, 1), std::hypot(0.1, 0.2) / 2);
  EXPECT_EQ(stats.reciprocity_mean_relative_change, 0.0);
  EXPECT_EQ(stats.reciprocity_rows_scaled, 0);
}

TEST(Reciprocity, TinyPatchUnderABigOneStaysBelowOne) {
  // End to end: a 0.1 x 0.1 patch 0.05 under a 2 x 2 one (F_ab ≈ 0.9, F_ba ≈ 0.002):
  // with few rays b's row over- or undercounts a by whole rays, and the average of the
  // big G_ba pushes F_ab above 1 for some seeds. Whatever the seed, the result is
  // reciprocal to rounding and no row exceeds 1.
  Scene s;
  add_polygon(s, "a", plate(), {{0.95, 0.95, 0}, {1.05, 0.95, 0}, {1.05, 1.05, 0}, {0.95, 1.05, 0}});
  add_polygon(s, "b", plate(), {{0, 0, 0.05}, {0, 2, 0.05}, {2, 2, 0.05}, {2, 0, 0.05}});
  const PatchMesh mesh = mesh_scene(s, {});
  std::int64_t scaled = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const FormFactors ff = gather(mesh, 1024, seed, "average");
    scaled += ff.stats.reciprocity_rows_scaled;
    for (Eigen::Index i = 0; i < mesh.size(); ++i) {
      EXPECT_LE(row_sum(ff.F, i), 1.0 + 1e-12) << seed;
      for (SparseF::InnerIterator it(ff.F, i); it; ++it) {
        const double gij = mesh.patches[i].area * it.value();
        const double gji = mesh.patches[it.col()].area * ff.F.coeff(it.col(), i);
        EXPECT_NEAR(gij, gji, 4e-16 * gij);
      }
    }
  }
  EXPECT_GT(scaled, 0);  // the fix was needed for at least one seed
}

TEST(FormFactorAuto, PicksHybridBelowAndGatherAtTheThreshold) {
  EXPECT_EQ(auto_estimator(1, false), "hybrid");
  EXPECT_EQ(auto_estimator(kAutoGatherPatches - 1, false), "hybrid");
  EXPECT_EQ(auto_estimator(kAutoGatherPatches, false), "gather");
  // An error target asks for the one estimator that honours it, up to its size limit.
  EXPECT_EQ(auto_estimator(1, true), "analytic");
  EXPECT_EQ(auto_estimator(kAutoAnalyticMaxPatches, true), "analytic");
  EXPECT_EQ(auto_estimator(kAutoAnalyticMaxPatches + 1, true), "hybrid");
  EXPECT_EQ(auto_estimator(kAutoGatherPatches, true), "gather");
  FormFactorOptions o;  // the defaults: auto estimator, auto reciprocity
  const FormFactorOptions small = resolve_form_factor_options(o, 100);
  EXPECT_EQ(small.estimator, "hybrid");
  EXPECT_EQ(small.estimator_requested, "auto");
  EXPECT_EQ(small.reciprocity, "none");
  const FormFactorOptions big = resolve_form_factor_options(o, kAutoGatherPatches);
  EXPECT_EQ(big.estimator, "gather");
  EXPECT_EQ(big.reciprocity, "average");
  o.estimator = "hemicube";
  EXPECT_EQ(resolve_form_factor_options(o, 100).reciprocity, "none");
  EXPECT_EQ(resolve_form_factor_options(o, 100).estimator_requested, "");
  // The memory bound sees the resolved estimator: gather's rows hold at most K entries.
  FormFactorOptions g;
  g.estimator = "gather";
  EXPECT_EQ(form_factor_peak_bytes(kAutoGatherPatches, FormFactorOptions()),
            form_factor_peak_bytes(kAutoGatherPatches, g));
  FormFactorOptions h;
  h.estimator = "hybrid";
  EXPECT_LT(form_factor_peak_bytes(100000, g), form_factor_peak_bytes(100000, h) / 10);
}

}  // namespace lambert
