#include "geometry/formfactors/formfactors.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/reference.hpp"
#include "geometry/formfactors/visibility.hpp"

namespace lambert {
namespace {

FormFactors compute(const Scene& scene, const std::string& estimator, int samples,
                    std::uint64_t seed = 1, double max_edge = 0.0, int threads = 0) {
  FormFactorOptions o;
  o.estimator = estimator;
  o.pair.samples = samples;
  o.run.seed = seed;
  o.run.threads = threads;
  o.run.with_stderr = samples >= 4;  // replicate errors need >= 4 samples
  o.run.progress = false;
  return compute_form_factors(mesh_scene(scene, {max_edge, 0}), o);
}

// Surface-to-surface factor from surface 0 to surface 1 and its standard error (entries
// are independent, so variances add), from a mesh with several patches per surface.
std::pair<double, double> surface_factor(const PatchMesh& mesh, const FormFactors& ff) {
  double area0 = 0.0, sum = 0.0, var = 0.0;
  for (const auto& p : mesh.patches) area0 += p.surface == 0 ? p.area : 0.0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    if (mesh.patches[i].surface != 0) continue;
    for (SparseF::InnerIterator it(ff.F, i), st(ff.stderr_F, i); it; ++it, ++st) {
      if (mesh.patches[it.col()].surface != 1) continue;
      sum += mesh.patches[i].area * it.value();
      var += std::pow(mesh.patches[i].area * st.value(), 2);
    }
  }
  return {sum / area0, std::sqrt(var) / area0};
}

}  // namespace

TEST(AnalyticFactors, ClosedFormsMatchHowellTables) {
  // Howell's tabulated values to their 9 printed digits.
  EXPECT_NEAR(parallel_rectangles_factor(1, 1, 1), 0.199824896, 1e-9);
  EXPECT_NEAR(perpendicular_rectangles_factor(1, 1, 1), 0.200043776, 1e-9);
  // Coaxial disks, checked against independent formulas rather than against themselves:
  // a vanishing disk under a disk of radius R at height h sees the point-to-disk factor
  // R² / (h² + R²) (Howell B-13), up to O(r1² / h²) = 1e-8 here;
  EXPECT_NEAR(coaxial_disks_factor(1e-4, 1, 1), 0.5, 1e-7);
  EXPECT_NEAR(coaxial_disks_factor(1e-4, 2, 1), 0.8, 1e-7);
  // reciprocity A1 F12 = A2 F21 for unequal disks (to rounding);
  EXPECT_NEAR(coaxial_disks_factor(1, 2, 1.5), 4.0 * coaxial_disks_factor(2, 1, 1.5), 1e-15);
  // and Howell's tabulated 0.38197 for equal disks one radius apart (5 printed digits).
  EXPECT_NEAR(coaxial_disks_factor(1, 1, 1), 0.38197, 5e-6);
}

TEST(FormFactorMc, ParallelUnitSquaresMatchHowell) {
  const FormFactors ff = compute(parallel_squares(1.0), "mc", 4096);
  const double f = ff.F.coeff(0, 1), se = ff.stderr_F.coeff(0, 1);
  // The estimator's own standard error; 4 sigma has a two-sided false-alarm rate of 6e-5.
  EXPECT_GT(se, 0.0);
  EXPECT_NEAR(f, kCubeOpposite, 4 * se) << "stderr " << se;
}

TEST(FormFactorMc, PerpendicularSquaresSharingAnEdgeMatchHowell) {
  const FormFactors ff = compute(perpendicular_squares(), "mc", 1 << 16);
  const double f = ff.F.coeff(0, 1), se = ff.stderr_F.coeff(0, 1);
  EXPECT_NEAR(f, kCubeAdjacent, 4 * se) << "stderr " << se;
}

TEST(FormFactorHybrid, IsExactForUnoccludedPairs) {
  // No blocker: every ray is visible and the estimate is the Gauss-Legendre integral of the
  // exact point-to-patch factor. Its quadrature error is bounded by the disagreement of
  // the two sides' integrals (reported in stderr) and is < 1e-6 by the order choice.
  for (int samples : {2, 16}) {
    const FormFactors par = compute(parallel_squares(1.0), "hybrid", samples);
    EXPECT_NEAR(par.F.coeff(0, 1), kCubeOpposite, 1e-6);
    const FormFactors perp = compute(perpendicular_squares(), "hybrid", samples);
    EXPECT_NEAR(perp.F.coeff(0, 1), kCubeAdjacent, 1e-5);
  }
  // The disks are 64-gons, triangulated into 62 triangles each by the mesher.
  const PatchMesh disks = mesh_scene(coaxial_disks(0.5, 0.5, 1.0, 64), {});
  FormFactorOptions o;
  o.pair.samples = 8;
  o.run.with_stderr = true;
  o.run.progress = false;
  const auto [f, se] = surface_factor(disks, compute_form_factors(disks, o));
  // The 64-gon of equal area differs from the disk by O(1/64²) in F (measured ~2e-5).
  EXPECT_NEAR(f, coaxial_disks_factor(0.5, 0.5, 1.0), 1e-4 + 4 * se);
}

TEST(FormFactorHybrid, MeshedSquaresSumToTheSurfaceFactor) {
  for (const auto& [scene, exact] : {std::pair{parallel_squares(1.0), kCubeOpposite},
                                     std::pair{perpendicular_squares(), kCubeAdjacent}}) {
    const PatchMesh mesh = mesh_scene(scene, {0.25, 0});
    FormFactorOptions o;
    o.pair.samples = 8;
    o.run.with_stderr = true;
    o.run.progress = false;
    const FormFactors ff = compute_form_factors(mesh, o);
    const auto [f, se] = surface_factor(mesh, ff);
    // Unoccluded: quadrature error only, < 1e-5 per entry relative, plus stderr.
    EXPECT_NEAR(f, exact, 1e-5 + 4 * se);
  }
}

TEST(FormFactors, UnitCubeRowsSumToOneAndReciprocityIsExact) {
  for (const std::string est : {"hybrid", "mc"}) {
    const PatchMesh mesh = mesh_scene(unit_cube(), {0.34, 0});  // 3x3 patches per face
    FormFactorOptions o;
    o.estimator = est;
    o.pair.samples = est == "mc" ? 4096 : 8;
    o.run.with_stderr = true;
    o.run.progress = false;
    const FormFactors ff = compute_form_factors(mesh, o);
    for (std::int32_t i = 0; i < mesh.size(); ++i) {
      double sum = 0.0, var = 0.0;
      for (SparseF::InnerIterator it(ff.F, i), st(ff.stderr_F, i); it; ++it, ++st) {
        sum += it.value();
        var += st.value() * st.value();
        const double aij = mesh.patches[i].area * it.value();
        const double aji = mesh.patches[it.col()].area * ff.F.coeff(it.col(), i);
        // Both come from the same G_ij divided by the areas: equal to rounding (2 ulps).
        EXPECT_NEAR(aij, aji, 4e-16 * aij);
      }
      // A closed enclosure: every ray leaving a patch lands on another. hybrid: quadrature
      // error (< 1e-5 per entry x 45 entries); mc: 5 sigma of the row's own error.
      EXPECT_NEAR(sum, 1.0, est == "hybrid" ? 2e-4 : 5 * std::sqrt(var)) << est << " row " << i;
    }
  }
}

TEST(FormFactors, FullyBlockedPairIsZero) {
  Scene s = parallel_squares(1.0);
  Material m{"plate", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "plate", m, {{-1, -1, 0.5}, {2, -1, 0.5}, {2, 2, 0.5}, {-1, 2, 0.5}});
  for (const std::string est : {"mc", "hybrid"}) {
    const FormFactors ff = compute(s, est, 64);
    // a and b see each other only through the plate: no ray gets through, exactly 0.
    EXPECT_EQ(ff.F.coeff(0, 1), 0.0) << est;
    EXPECT_EQ(ff.F.coeff(1, 0), 0.0) << est;
    // The plate faces +z: b (above it, facing down) sees its front; a is behind it.
    EXPECT_GT(ff.F.coeff(1, 2), 0.0) << est;
    EXPECT_EQ(ff.F.coeff(0, 2), 0.0) << est;
  }
}

TEST(FormFactorMc, ErrorFallsAtLeastLikeOneOverSqrtSamples) {
  // RMS error over 24 seeds at k and 16k samples: a plain MC estimator improves by
  // sqrt(16) = 4; the shifted lattice does at least as well. Allow the ratio down to 4/1.5
  // (the RMS over 24 seeds is itself uncertain by ~1/sqrt(2*24) = 15 %, doubled for safety).
  // Parallel unit squares 2 apart: farther than their diameter, so plain Monte Carlo (near
  // pairs go to the hybrid kernel, which is exact when unoccluded).
  const double exact = parallel_rectangles_factor(1, 1, 2);
  auto rms = [&](int k) {
    double s2 = 0.0;
    for (std::uint64_t seed = 1; seed <= 24; ++seed) {
      const double e = compute(parallel_squares(2.0), "mc", k, seed).F.coeff(0, 1) - exact;
      s2 += e * e;
    }
    return std::sqrt(s2 / 24);
  };
  const double e1 = rms(64), e2 = rms(1024);
  EXPECT_GT(e1 / e2, 4.0 / 1.5) << "rms(64) " << e1 << " rms(1024) " << e2;
}

// Regression (issue 33, item 4): Embree's single-precision intersection tests multiply three
// coordinates, so a scene scaled by 3e10 (float overflow) or 1e-20 (underflow) lost its
// occlusion: the Cornell box gave row sums up to 1.35. The BVH now holds the scene scaled by
// a power of two into (-1, 1). A closed cube with a plate inside: at scales 2^40 and 2^-66
// every entry equals scale 1's bit for bit (power-of-two scaling is exact and F is
// dimensionless); at 1e15 and 1e-20 (rounded differently) rows still sum to 1 within the
// estimator's noise (4 stderr of the row, at most 0.05 for 8 samples), where lost occlusion
// would add the plate's shadowed part (about 0.3).
TEST(FormFactors, ScaleInvariantFromTinyToHugeScenes) {
  Scene base = unit_cube();
  Material m{"plate", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(base, "plate", m,
              {{0.3, 0.3, 0.5}, {0.7, 0.3, 0.5}, {0.7, 0.7, 0.5}, {0.3, 0.7, 0.5}});
  add_polygon(base, "plate", m,
              {{0.3, 0.3, 0.5}, {0.3, 0.7, 0.5}, {0.7, 0.7, 0.5}, {0.7, 0.3, 0.5}});
  auto scaled = [&](double k) {
    Scene s = base;
    for (auto& v : s.vertices) v *= k;
    return s;
  };
  const FormFactors one = compute(base, "hybrid", 8, 3, 0.25, 1);
  for (double k : {std::ldexp(1.0, 40), std::ldexp(1.0, -66)}) {
    const FormFactors f = compute(scaled(k), "hybrid", 8, 3, 0.25 * k, 1);
    ASSERT_EQ(f.F.nonZeros(), one.F.nonZeros()) << k;
    for (std::int64_t e = 0; e < one.F.nonZeros(); ++e)
      ASSERT_EQ(f.F.valuePtr()[e], one.F.valuePtr()[e]) << "scale " << k;
  }
  for (double k : {1e15, 1e-20}) {
    const FormFactors f = compute(scaled(k), "hybrid", 8, 3, 0.25 * k, 1);
    const Eigen::VectorXd rows = f.F * Eigen::VectorXd::Ones(f.F.cols());
    EXPECT_LT((rows.array() - 1.0).abs().maxCoeff(), 0.05) << "scale " << k;
  }
}

TEST(FormFactors, BitwiseIdenticalForAnyThreadCount) {
  Scene s = unit_cube();
  Material m{"plate", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "plate", m, {{0.3, 0.3, 0.5}, {0.7, 0.3, 0.5}, {0.7, 0.7, 0.5}, {0.3, 0.7, 0.5}});
  for (const std::string est : {"mc", "hybrid"}) {
    const FormFactors one = compute(s, est, 8, 7, 0.2, 1);
    for (int threads : {2, 3, 8}) {
      const FormFactors many = compute(s, est, 8, 7, 0.2, threads);
      ASSERT_EQ(one.F.nonZeros(), many.F.nonZeros());
      for (std::int32_t k = 0; k < one.F.nonZeros(); ++k) {
        ASSERT_EQ(one.F.valuePtr()[k], many.F.valuePtr()[k]) << est << " threads " << threads;
        ASSERT_EQ(one.F.innerIndexPtr()[k], many.F.innerIndexPtr()[k]);
      }
    }
  }
}

// Distributed form factors (docs/cluster.md) rest on this: the row ranges of
// balanced_pair_rows, computed separately, hold every entry of the whole F exactly once and
// bit for bit (row i's entries come from the range of row i or, mirrored, of row j < i).
TEST(FormFactors, RowRangesTogetherAreTheWholeFBitForBit) {
  Scene s = unit_cube();
  Material m{"plate", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "plate", m, {{0.3, 0.3, 0.5}, {0.7, 0.3, 0.5}, {0.7, 0.7, 0.5}, {0.3, 0.7, 0.5}});
  const PatchMesh mesh = mesh_scene(s, {0.25, 0});  // 100 patches: a fast test (< 2 s)
  for (const std::string est : {"mc", "hybrid"}) {
    FormFactorOptions o;
    o.estimator = est;
    o.pair.samples = 8;
    o.run.seed = 7;
    o.run.with_stderr = true;
    o.threshold = 1e-3;  // applied per pair: both entries of a pair live in one range
    o.run.progress = false;
    const FormFactors whole = compute_form_factors(mesh, o);
    for (int parts : {1, 2, 3, 7}) {
      const std::vector<std::int32_t> rows = balanced_pair_rows(mesh.size(), parts);
      ASSERT_EQ(rows.size(), static_cast<size_t>(parts) + 1);
      ASSERT_EQ(rows.front(), 0);
      ASSERT_EQ(rows.back(), mesh.size());
      std::vector<Eigen::Triplet<double, std::int64_t>> entries, errors;
      for (int r = 0; r < parts; ++r) {
        if (rows[r + 1] == rows[r]) continue;
        o.subset.row_begin = rows[r];
        o.subset.row_end = rows[r + 1];
        const FormFactors part = compute_form_factors(mesh, o);
        for (std::int32_t i = 0; i < mesh.size(); ++i)
          for (SparseF::InnerIterator it(part.F, i), e(part.stderr_F, i); it; ++it, ++e) {
            entries.emplace_back(i, it.col(), it.value());
            errors.emplace_back(i, it.col(), e.value());
          }
      }
      o.subset.row_begin = o.subset.row_end = 0;
      // setFromTriplets sums duplicates: an entry computed twice would show as a mismatch.
      SparseF F(mesh.size(), mesh.size()), err(mesh.size(), mesh.size());
      F.setFromTriplets(entries.begin(), entries.end());
      err.setFromTriplets(errors.begin(), errors.end());
      ASSERT_EQ(F.nonZeros(), whole.F.nonZeros()) << est << " parts " << parts;
      for (std::int64_t k = 0; k < F.nonZeros(); ++k) {
        ASSERT_EQ(F.innerIndexPtr()[k], whole.F.innerIndexPtr()[k]);
        ASSERT_EQ(F.valuePtr()[k], whole.F.valuePtr()[k]) << est << " parts " << parts;
        ASSERT_EQ(err.valuePtr()[k], whole.stderr_F.valuePtr()[k]);
      }
    }
  }
}

TEST(FormFactors, BalancedPairRowsSplitThePairsEvenly) {
  // Row i has n - 1 - i pairs; each part's pairs are within one row's worth (at most n - 1)
  // of the even share, since a boundary moves by whole rows.
  const std::int32_t n = 1000;
  for (int parts : {1, 2, 5, 64}) {
    const std::vector<std::int32_t> rows = balanced_pair_rows(n, parts);
    const double share = 0.5 * n * (n - 1) / parts;
    for (int r = 0; r < parts; ++r) {
      double pairs = 0.0;
      for (std::int32_t i = rows[r]; i < rows[r + 1]; ++i) pairs += n - 1 - i;
      EXPECT_NEAR(pairs, share, n - 1) << "part " << r << " of " << parts;
    }
  }
  EXPECT_EQ(balanced_pair_rows(3, 5).back(), 3);  // more parts than rows: empty parts
}

TEST(FormFactors, RowRangeRefusesRowEstimators) {
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.5, 0});
  FormFactorOptions o;
  o.estimator = "gather";
  o.subset.row_begin = 0;
  o.subset.row_end = 2;
  o.run.progress = false;
  EXPECT_THROW(compute_form_factors(mesh, o), UsageError);
}

}  // namespace lambert

namespace lambert {

// A floor running under a wall that stands on it (as the Cornell floor runs under the
// blocks): only the part in front of the wall exchanges with it, and the exact factor is
// that of perpendicular rectangles with a common edge: G = 1.3 x F_C14(l=1, w=1.3, h=1).
TEST(FormFactors, FloorRunningUnderAWallMatchesTheClosedForm) {
  Scene s;
  Material m{"m", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "floor", m, {{-0.7, 0, 0}, {-0.7, 0, 1}, {1.3, 0, 1}, {1.3, 0, 0}});  // +y
  add_polygon(s, "wall", m, {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}});             // +x
  const double exact = 1.3 * perpendicular_rectangles_factor(1, 1.3, 1) / 2.0;         // / A_floor
  // Meshings whose floor patches straddle the wall's plane (0.3, 5) and one that does not
  // (0.1). mc runs on the two coarse ones only: the straddling is what it checks, and at
  // 0.1 its 4096 rays per pair took 85 % of the suite's time.
  for (double h : {0.3, 5.0, 0.1}) {
    const PatchMesh mesh = mesh_scene(s, {h, 0});
    for (const std::string est : {"hybrid", "mc"}) {
      if (est == "mc" && h < 0.2) continue;
      FormFactorOptions o;
      o.estimator = est;
      o.pair.samples = est == "mc" ? 4096 : 4;
      o.run.with_stderr = true;
      o.run.progress = false;
      const auto [f, se] = surface_factor(mesh, compute_form_factors(mesh, o));
      // hybrid: unoccluded, quadrature error < 1e-6 per pair (quadrature_test.cpp), 1e-5
      // allowed; mc: 5 stderr of its own error (the shared-edge singularity makes its
      // variance estimate itself noisy).
      EXPECT_NEAR(f, exact, est == "hybrid" ? 1e-5 : 5 * se) << est << " h=" << h << " se=" << se;
    }
  }
}

}  // namespace lambert

namespace lambert {

// Half of the receiver is shaded by a plate just in front of it, right above the emitter,
// which is the left half of the opposite square: the near (high-kernel) half of b is
// hidden. The exact G is that of the unshaded configuration a -> (right half of b), which
// hybrid computes exactly (no blocker); an area-weighted visible fraction would give 1/2 of
// G(a -> b) instead, 20 % too high here (0.04996 vs 0.04159). The plate sits 1e-3 in front of b, so
// its penumbra on b is a band < 1e-3 wide: G changes by < 1e-3 relative (the bound used).
TEST(FormFactors, PartlyShadedReceiverUsesTheKernelWeightedVisibleFraction) {
  Material m{"m", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  Scene open;
  add_polygon(open, "a", m, {{0, 0, 0}, {0.5, 0, 0}, {0.5, 1, 0}, {0, 1, 0}});  // +z
  add_polygon(open, "c", m, {{0.5, 0, 1}, {0.5, 1, 1}, {1, 1, 1}, {1, 0, 1}});  // -z
  Scene shaded;
  add_polygon(shaded, "a", m, {{0, 0, 0}, {0.5, 0, 0}, {0.5, 1, 0}, {0, 1, 0}});
  add_polygon(shaded, "b", m, {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}});
  add_polygon(shaded, "plate", m,
              {{-2, -2, 0.999}, {0.5, -2, 0.999}, {0.5, 3, 0.999}, {-2, 3, 0.999}});
  FormFactorOptions o;
  o.pair.samples = 4;
  o.run.progress = false;
  const FormFactors ref = compute_form_factors(mesh_scene(open, {}), o);
  const double exact = ref.F.coeff(0, 1) * 0.5;  // G = A_a F_ac, A_a = 0.5
  for (const std::string est : {"hybrid", "mc"}) {
    o.estimator = est;
    o.pair.samples = est == "mc" ? 1 << 16 : 256;
    o.run.with_stderr = true;
    const PatchMesh mesh = mesh_scene(shaded, {est == "mc" ? 0.0 : 0.25, 0});
    const auto [f, se] = surface_factor(mesh, compute_form_factors(mesh, o));
    EXPECT_NEAR(f * 0.5, exact, 1e-3 * exact + 4 * se * 0.5) << est << " se " << se;
  }
}

}  // namespace lambert

namespace lambert {

TEST(FormFactors, ThresholdDropsPairsTogetherAndKeepsReciprocity) {
  // Patches of very different sizes: F_ij and F_ji differ by the area ratio, so a per-entry
  // threshold would keep one and drop the other.
  Scene s;
  Material m{"m", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "big", m, {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}});
  add_polygon(s, "small", m, {{1, 1, 1}, {1, 1.1, 1}, {1.1, 1.1, 1}, {1.1, 1, 1}});
  FormFactorOptions o;
  o.pair.samples = 4;
  o.run.progress = false;
  const PatchMesh mesh = mesh_scene(s, {});
  const FormFactors all = compute_form_factors(mesh, o);
  const double f_small = all.F.coeff(1, 0), f_big = all.F.coeff(0, 1);
  ASSERT_GT(f_small, 10 * f_big);
  o.threshold = std::sqrt(f_small * f_big);  // between the two
  const FormFactors kept = compute_form_factors(mesh, o);
  EXPECT_EQ(kept.F.coeff(0, 1), f_big);
  EXPECT_EQ(kept.F.coeff(1, 0), f_small);
  o.threshold = 1.0;  // above both (distinct patches' factors are below 1)
  EXPECT_EQ(compute_form_factors(mesh, o).F.nonZeros(), 0);
}

TEST(FormFactors, WarpedQuadsKeptByTheLoaderAreNotTheirOwnBlockers) {
  // Two unit squares d apart whose corners alternate by delta = 5e-5 (3.5e-5 of their extent
  // off their plane: the OBJ loader keeps them quads). Embree traces each as two triangles
  // split along v1-v3 while the estimators sample the bilinear surface (mc) or the triangles
  // split along v0-v2 (hybrid's kernel sampler): up to delta below the traced surface on one
  // of the two squares for either sign, 50 x the rays' end offset (1e-6 of the scene). Before
  // ray ends were lifted by the patch's warp those rays hit their own patch: F came out 90 to
  // 100 % low (the atrium's courtyard floor: 3-6 %). At d = 1 mc hands the pair to hybrid
  // (a near pair); at d = 5 it samples both bilinear surfaces itself.
  for (const double d : {1.0, 5.0})
    for (const double delta : {5e-5, -5e-5}) {
      Scene s;
      Material lamp{"lamp", Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()};
      Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
      add_polygon(s, "a", lamp, {{0, 0, 0}, {1, 0, delta}, {1, 1, 0}, {0, 1, delta}});
      add_polygon(s, "b", grey, {{0, 0, d}, {0, 1, d + delta}, {1, 1, d}, {1, 0, d + delta}});
      // Flipping delta's sign gives a congruent pair (shift both by delta, turn them 90
      // degrees about their axis), so F is even in delta: the planar closed form to
      // O(delta^2) = 3e-9.
      const double exact = parallel_rectangles_factor(1, 1, d);
      // Unoccluded, hybrid is its quadrature (< 1e-6) when every ray gets through.
      EXPECT_NEAR(compute(s, "hybrid", 64).F.coeff(0, 1), exact, 1e-6) << d << " " << delta;
      const FormFactors mc = compute(s, "mc", 4096);
      // The estimator's own standard error; 4 sigma: a false alarm in 1.6e4 runs.
      EXPECT_NEAR(mc.F.coeff(0, 1), exact, 4 * mc.stderr_F.coeff(0, 1) + 1e-6) << d << " " << delta;
      // analytic integrates a warped quad on its mean plane (on its first corner's plane it
      // gave 0.1998294 and 0.1998212 for the two congruent signs at d = 1, against its stated
      // error 5.6e-7): within its stated error (2.5e-7) plus O(delta^2).
      EXPECT_NEAR(compute(s, "analytic", 1).F.coeff(0, 1), exact, 1e-6) << d << " " << delta;
      // A strip halfway, across the middle: both estimators unbiased against analytic.
      add_polygon(s, "strip", grey,
                  {{0.3, -1, d / 2}, {0.7, -1, d / 2}, {0.7, 2, d / 2}, {0.3, 2, d / 2}});
      const double shaded = compute(s, "analytic", 1).F.coeff(0, 1);
      for (const std::string est : {"mc", "hybrid"}) {
        const FormFactors ff = compute(s, est, 4096);
        EXPECT_NEAR(ff.F.coeff(0, 1), shaded, 4 * ff.stderr_F.coeff(0, 1) + 1e-6)
            << est << " " << d << " " << delta;
      }
    }
}

TEST(FormFactors, HybridOnCadSliversIsExactUnblockedAndUnbiasedBlocked) {
  // Fin faces as a CAD exporter writes them: two strips 100 mm x 2 mm, each two needle
  // triangles, facing each other 3 mm apart and offset by 1 mm across, the fins' gap. hybrid
  // draws its rays from coarse preview cells (up to 16 x their distance to the other patch,
  // several along a needle) and integrates the Gauss rules only when a ray gets through.
  Scene s;
  Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  const double L = 0.1, w = 0.002, gap = 0.003, shift = 0.001;
  add_polygon(s, "low1", grey, {{0, 0, 0}, {L, 0, 0}, {L, w, 0}});
  add_polygon(s, "low2", grey, {{0, 0, 0}, {L, w, 0}, {0, w, 0}});
  add_polygon(s, "up1", grey, {{0, shift, gap}, {L, shift + w, gap}, {L, shift, gap}});
  add_polygon(s, "up2", grey, {{0, shift, gap}, {0, shift + w, gap}, {L, shift + w, gap}});
  // Unblocked, every pair is its quadrature: within kQuadratureTolerance (1e-6 relative) of
  // the reference quadrature (1e-9). (analytic at its default --ff-tol 1e-6 is 9e-6 relative
  // off the 0.0647 pair, within its absolute tolerance.)
  const FormFactors ref = unoccluded_quadrature(mesh_scene(s, {0.0, 0}), 1);
  const FormFactors open = compute(s, "hybrid", 64);
  for (int i = 0; i < 2; ++i)
    for (int j = 2; j < 4; ++j)
      EXPECT_NEAR(open.F.coeff(i, j), ref.F.coeff(i, j), 1e-6 * ref.F.coeff(i, j)) << i << j;
  // A 10 mm bar across the middle of the gap shades every pair by 8-17 %: unbiased against
  // analytic to 1e-8, within 4 of hybrid's own standard errors (a false alarm in 1.6e4
  // entries; over seeds 1-3 at 1,024 and 16,384 rays the z-scores spread -2.0 .. 1.7).
  add_polygon(s, "bar", grey,
              {{0.045, -0.01, gap / 2},
               {0.055, -0.01, gap / 2},
               {0.055, 0.01, gap / 2},
               {0.045, 0.01, gap / 2}});
  FormFactorOptions o;
  o.estimator = "analytic";
  o.analytic.tol = 1e-8;
  o.run.progress = false;
  const FormFactors exact = compute_form_factors(mesh_scene(s, {0.0, 0}), o);
  const FormFactors shaded = compute(s, "hybrid", 4096);
  for (int i = 0; i < 2; ++i)
    for (int j = 2; j < 4; ++j) {
      EXPECT_LT(exact.F.coeff(i, j), 0.95 * ref.F.coeff(i, j)) << i << j;
      EXPECT_NEAR(shaded.F.coeff(i, j), exact.F.coeff(i, j), 4 * shaded.stderr_F.coeff(i, j))
          << i << j;
    }
}

TEST(FormFactors, TargetStderrSamplesEveryPairUntilItsErrorMeetsTheTarget) {
  // Two unit squares 1 apart with a strip halfway across the middle, meshed at 0.5 (4 patches
  // each): partly shaded pairs, unblocked ones and the strip's. From 4 samples per pair the
  // estimators' errors reach ~5e-2; with --target-stderr 2e-3 every stored error is at most
  // 2e-3 and every entry lies within 4 of them of the analytic estimator's (stated error
  // 2.5e-7): 4 sigma, a false alarm in 1.6e4 entries (here ~100).
  Scene s = parallel_squares(1.0);
  Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "strip", grey, {{0.3, -1, 0.5}, {0.7, -1, 0.5}, {0.7, 2, 0.5}, {0.3, 2, 0.5}});
  const PatchMesh mesh = mesh_scene(s, {0.5, 0});
  const FormFactors exact = compute(s, "analytic", 1, 1, 0.5);
  constexpr double kTarget = 2e-3;
  for (const std::string est : {"mc", "hybrid"}) {
    FormFactorOptions o;
    o.estimator = est;
    o.pair.samples = 4;
    o.run.with_stderr = true;
    o.run.progress = false;
    const FormFactors plain = compute_form_factors(mesh, o);
    set_estimator_param(o, "--target-stderr", kTarget);
    const FormFactors ff = compute_form_factors(mesh, o);
    EXPECT_EQ(ff.stats.pairs_short_of_target, 0) << est;
    EXPECT_GT(ff.stats.rays, 4 * plain.stats.rays) << est;
    double worst_plain = 0.0;
    for (std::int64_t k = 0; k < plain.stderr_F.nonZeros(); ++k)
      worst_plain = std::max(worst_plain, plain.stderr_F.valuePtr()[k]);
    EXPECT_GT(worst_plain, 5 * kTarget) << est;  // the target did raise the samples
    for (Eigen::Index i = 0; i < ff.F.rows(); ++i)
      for (SparseF::InnerIterator it(ff.F, i), st(ff.stderr_F, i); it; ++it, ++st) {
        EXPECT_LE(st.value(), kTarget) << est << " " << i << " " << it.col();
        EXPECT_NEAR(it.value(), exact.F.coeff(i, it.col()), 4 * kTarget)
            << est << " " << i << " " << it.col();
      }
  }
}

TEST(KernelSampler, WarpedNeighbourQuadClipsToAHexagonAndSamplesOnIt) {
  // A unit tile whose corners alternate between z = 0 and delta (5e-5 of it off its mean
  // plane: the OBJ loader keeps it a quad), seen from a point of a flat neighbour that lies
  // inside that warp and sees q (F > 0): the horizon crosses all four edges, 2 corners + 4
  // crossings (issue 33: one more corner than point_to_patch and KernelSampler had room for).
  const double delta = 1e-4;
  ff::PatchGeom q;
  q.n = 4;
  q.p = {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(2, 0, delta), Eigen::Vector3d(2, 1, 0),
         Eigen::Vector3d(1, 1, delta)};
  q.normal = Eigen::Vector3d::UnitZ();
  q.centroid = Eigen::Vector3d(1.5, 0.5, 0.5 * delta);
  q.area = 1.0;
  const Eigen::Vector3d x(0.75, 0.2, delta / 2), nx = Eigen::Vector3d::UnitZ();
  ff::ClippedCorners r;
  ASSERT_EQ(ff::clip_to_horizon(x, nx, q, r), ff::kMaxClippedCorners);
  // Every point of q lies within elevation alpha of x's horizon, sin alpha <= delta / 0.25
  // (heights <= delta, distances >= 0.25), and the projected solid angle of that band is
  // pi sin^2 alpha: 0 <= F <= sin^2 alpha.
  const double f = ff::point_to_patch(x, nx, q);
  EXPECT_GE(f, 0.0);
  EXPECT_LE(f, std::pow(delta / 0.25, 2));
  const ff::KernelSampler sampler(x, nx, q);
  EXPECT_EQ(sampler.factor(), f);
  ASSERT_FALSE(sampler.empty());
  // The samples lie on q: within its bounding box (rounding aside).
  Eigen::AlignedBox3d box;
  for (const auto& p : q.p) box.extend(p);
  box.extend(box.min() - Eigen::Vector3d::Constant(1e-12));
  box.extend(box.max() + Eigen::Vector3d::Constant(1e-12));
  Rng rng(7);
  for (int k = 0; k < 64; ++k) {
    bool exhausted = false;
    const Eigen::Vector3d y =
        sampler.sample(rng.uniform(), rng.uniform(), rng.uniform(), rng, exhausted);
    EXPECT_TRUE(box.contains(y)) << "sample " << k << ": " << y.transpose();
  }
}

TEST(FormFactorRegistry, EveryParameterIsDeclaredOnceWithTheOptionsDefault) {
  const std::vector<std::string> names = form_factor_estimators();
  const FormFactorOptions defaults;
  ASSERT_FALSE(estimator_params().empty());
  for (const DeclaredEstimatorParam& d : estimator_params()) {
    SCOPED_TRACE(d.param.option);
    ASSERT_FALSE(d.estimators.empty());
    for (const std::string& e : d.estimators)
      EXPECT_NE(std::find(names.begin(), names.end(), e), names.end()) << e;
    // An absent value means the declared default (the CLI's, Python's and the text's).
    EXPECT_EQ(estimator_param(defaults, d.param.option), d.param.fallback);
    EXPECT_GE(d.param.fallback, d.param.lo);
    EXPECT_LE(d.param.fallback, d.param.hi);
    // A value set through the declaration is the value the estimator reads.
    FormFactorOptions o;
    set_estimator_param(o, d.param.option, d.param.hi);
    EXPECT_EQ(estimator_param(o, d.param.option), d.param.hi);
  }
  // The first estimators' parameters live in their blocks, which the kernels read by name.
  FormFactorOptions o;
  set_estimator_param(o, "--samples", 7);
  set_estimator_param(o, "--rays", 300);
  set_estimator_param(o, "--hemicube-res", 64);
  set_estimator_param(o, "--ff-tol", 2.5e-7);
  EXPECT_EQ(o.pair.samples, 7);
  EXPECT_EQ(o.gather.rays, 300);
  EXPECT_EQ(o.hemicube.resolution, 64);
  EXPECT_EQ(o.analytic.tol, 2.5e-7);
  EXPECT_TRUE(o.params.empty());
  // One declaration per option, with every estimator that reads it.
  EXPECT_EQ(find_estimator_param("--samples")->estimators,
            (std::vector<std::string>{"hybrid", "mc"}));
  EXPECT_EQ(find_estimator_param("--rays")->estimators, std::vector<std::string>{"gather"});
  EXPECT_EQ(find_estimator_param("--ff-tol")->estimators, std::vector<std::string>{"analytic"});
  EXPECT_EQ(find_estimator_param("--threshold"), nullptr);  // every estimator's: not a parameter
}

// A CAD sliver (issue 36: a round fin tip's facet, 100 mm by 0.05 mm) 2 mm above x, its
// apex over x and its far end 50 patch-heights away. Its solid angle (~2e-5 sr to first
// order) is under kSmallSolidAngle, but K falls like 1/r³ along it: area sampling
// accepted with probability ~4e-4 (mean K 100 against a bound of 2.5e5), so a sample gave up
// after kMaxTries with probability e^(-4096 * 4e-4) = 0.2 (the heat sink's unverified pairs).
// Sampled by solid angle now: no sample gives up, every sample lies on the sliver.
TEST(KernelSampler, LongSliverNearThePointNeverGivesUp) {
  const double L = 0.1, w = 5e-5, h = 0.002;
  ff::PatchGeom b;
  b.n = 3;
  b.p = {Eigen::Vector3d(0, 0, h), Eigen::Vector3d(L, w, h), Eigen::Vector3d(L, 0, h),
         Eigen::Vector3d(L, 0, h)};
  b.normal = -Eigen::Vector3d::UnitZ();
  b.centroid = (b.p[0] + b.p[1] + b.p[2]) / 3.0;
  b.area = 0.5 * L * w;
  const Eigen::Vector3d x = Eigen::Vector3d::Zero(), nx = Eigen::Vector3d::UnitZ();
  const ff::KernelSampler sampler(x, nx, b);
  ASSERT_FALSE(sampler.empty());
  EXPECT_EQ(sampler.factor(), ff::point_to_patch(x, nx, b));
  Eigen::AlignedBox3d box;
  for (const auto& p : b.p) box.extend(p);
  box.extend(box.min() - Eigen::Vector3d::Constant(1e-9));
  box.extend(box.max() + Eigen::Vector3d::Constant(1e-9));
  Rng rng(11);
  int gave_up = 0;
  for (int k = 0; k < 256; ++k) {
    bool exhausted = false;
    const Eigen::Vector3d y =
        sampler.sample(rng.uniform(), rng.uniform(), rng.uniform(), rng, exhausted);
    gave_up += exhausted;
    EXPECT_TRUE(box.contains(y)) << "sample " << k << ": " << y.transpose();
  }
  EXPECT_EQ(gave_up, 0);
}

// The contour kernel's atan-free series (kernels.hpp: contour_edge_term) against closed
// forms. Unit roundoff u = 2^-53; glibc's atan, sqrt and division are within 1 ulp (2u).
namespace {
constexpr double kUnitRoundoff = 0x1p-53;
}  // namespace

// atan_ratio_series(s) against atan(√s) / √s over its whole domain [0, 1/16]. The reference
// rounds √s (u), atan (2u) and the division (u), and atan(t) / t changes by a relative
// 2t² / 3 <= 1/24 of a relative change of t: <= 4u. The series truncates below 1e-17
// (8.3e-18 / 0.98, kernels.hpp) and its Estrin evaluation rounds 9 times, each a relative
// u of a partial sum whose weight in the result is <= 1: <= 9u + 0.1u. Together 14u.
TEST(ContourKernel, SeriesMatchesAtanOverItsDomain) {
  double worst = 0.0;
  for (int k = 0; k <= 4096; ++k) {
    const double s = k / 4096.0 / ff::kContourSeriesMin;
    const double t = std::sqrt(s), exact = k ? std::atan(t) / t : 1.0;
    const double err = std::abs(ff::atan_ratio_series(s) - exact) / exact;
    EXPECT_LE(err, 14 * kUnitRoundoff) << "s " << s;
    worst = std::max(worst, err);
  }
  std::printf("worst relative error %.2f u\n", worst / kUnitRoundoff);
}

// atan2_upper(y, x) against atan2l (64-bit mantissa: its own error, ~2^-64, is 1/2000 of u)
// over angles in (0, π] at three scales, 400,000 angles a scale (every sixteenth's
// interval of the table, both sides of its edges, both reflections), plus tiny angles and
// the axes. kernels.hpp derives <= 9.4u; the reference's error and the rounding of y and x
// (which it sees as they are) add nothing: 10u.
TEST(ContourKernel, Atan2UpperMatchesLongDouble) {
  double worst = 0.0;
  auto check = [&](double y, double x) {
    const long double ref = std::atan2(static_cast<long double>(y), static_cast<long double>(x));
    const double err =
        static_cast<double>(std::abs(static_cast<long double>(ff::atan2_upper(y, x)) - ref) / ref);
    EXPECT_LE(err, 10 * kUnitRoundoff) << "y " << y << " x " << x;
    worst = std::max(worst, err);
  };
  constexpr int kAngles = 400000;
  for (double r : {1.0, 3.7e-5, 2.9e4})
    for (int k = 1; k <= kAngles; ++k) {
      const double theta = M_PI * k / kAngles, y = r * std::sin(theta), x = r * std::cos(theta);
      if (y > 0.0) check(y, x);
    }
  for (double tiny : {1e-300, 1e-20, 1e-8}) {
    check(tiny, 1.0);
    check(tiny, -1.0);
    check(1.0, tiny);
    check(1.0, -tiny);
  }
  check(1.0, 0.0);
  check(1.0, 1.0);
  check(1.0, -1.0);
  std::printf("worst relative error %.2f u\n", worst / kUnitRoundoff);
}

// patch_geometry flags the quads whose opposite sides are equal vectors (a rectangle, a
// sheared parallelogram; not a trapezoid or a triangle), and sample_patch maps those linearly
// with J = A: on a parallelogram the bilinear map is that linear map, so the points agree
// with the bilinear formula to rounding (1e-14 of the size covers a few ulps of the corner
// coordinates, ~3) and A = |dx/du x dx/dv| to the same. A trapezoid keeps the bilinear J,
// linear in (u, v), whose mean over a midpoint grid is exactly A (to 1e-12: the sum's
// rounding).
TEST(SamplePatch, ParallelogramsMapLinearlyWithTheirArea) {
  Scene s;
  const Material m{"plate", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(s, "rectangle", m, {{0, 0, 0}, {3, 0, 0}, {3, 0.7, 0}, {0, 0.7, 0}});
  add_polygon(s, "sheared", m, {{0, 0, 1}, {2, 0, 1.5}, {2.9, 1.1, 1.5}, {0.9, 1.1, 1}});
  add_polygon(s, "trapezoid", m, {{0, 0, 3}, {2, 0, 3}, {1.5, 1, 3}, {0.5, 1, 3}});
  add_polygon(s, "triangle", m, {{0, 0, 5}, {1, 0, 5}, {0, 1, 5}});
  const PatchMesh mesh = mesh_scene(s, {100.0, 0});
  ASSERT_EQ(mesh.size(), 4);
  const std::vector<ff::PatchGeom> geom = ff::patch_geometry(mesh);
  const bool expected[4] = {true, true, false, false};
  for (int i = 0; i < 4; ++i) {
    const ff::PatchGeom& g = geom[i];
    EXPECT_EQ(g.parallelogram, expected[i]) << i;
    if (g.n != 4) continue;
    constexpr int kGrid = 16;
    double mean_j = 0.0;
    for (int a = 0; a < kGrid; ++a)
      for (int b = 0; b < kGrid; ++b) {
        const double u = (a + 0.5) / kGrid, v = (b + 0.5) / kGrid;
        double j;
        const Eigen::Vector3d x = ff::sample_patch(g, u, v, j);
        const Eigen::Vector3d bilinear = (1 - u) * (1 - v) * g.p[0] + u * (1 - v) * g.p[1] +
                                         u * v * g.p[2] + (1 - u) * v * g.p[3];
        EXPECT_LE((x - bilinear).norm(), 1e-14 * g.diameter) << i;
        const Eigen::Vector3d du = (1 - v) * (g.p[1] - g.p[0]) + v * (g.p[2] - g.p[3]);
        const Eigen::Vector3d dv = (1 - u) * (g.p[3] - g.p[0]) + u * (g.p[2] - g.p[1]);
        EXPECT_NEAR(j, du.cross(dv).norm(), 1e-14 * g.area) << i;
        mean_j += j / (kGrid * kGrid);
      }
    EXPECT_NEAR(mean_j, g.area, 1e-12 * g.area) << i;
  }
}

// cos_sin_turn against long double over a dense sweep of [0, 1] (every quarter-turn
// boundary, where the reduction switches, on a grid point): each value within 3 ulps of
// 1 (the polynomials' truncation < 5e-17 plus the rounding of x = 2π (v - q/4), 1u relative
// in x, and of Horner's ~8 operations; sines near 0 are compared absolutely, in ulps of 1,
// since a direction's components are), and c² + s² within 6u of 1.
TEST(CosSinTurn, MatchesLongDouble) {
  double worst = 0.0;
  constexpr int kSteps = 1 << 20;
  for (int k = 0; k <= kSteps; ++k) {
    const double v = static_cast<double>(k) / kSteps;
    double c, s;
    ff::cos_sin_turn(v, c, s);
    const long double phi = 2.0L * 3.14159265358979323846264338327950288L * v;
    const double ec = static_cast<double>(std::abs(c - std::cos(phi)));
    const double es = static_cast<double>(std::abs(s - std::sin(phi)));
    ASSERT_LE(std::max(ec, es), 3 * kUnitRoundoff) << "v " << v;
    ASSERT_LE(std::abs(c * c + s * s - 1.0), 6 * kUnitRoundoff) << "v " << v;
    worst = std::max({worst, ec, es});
  }
  std::printf("worst error %.2f u\n", worst / kUnitRoundoff);
}

// The point factor of a rectangle a x b parallel to the point's plane at height h, the
// normal through a corner (Howell's catalogue B-3):
//   F = 1/(2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))],  X = a/h, Y = b/h.
// Both terms are positive: it rounds to a relative 16u (8 operations of <= 2u each).
namespace {
double corner_point_factor(double a, double b, double h) {
  const double X = a / h, Y = b / h, sx = std::sqrt(1 + X * X), sy = std::sqrt(1 + Y * Y);
  return (X / sx * std::atan(Y / sx) + Y / sy * std::atan(X / sy)) / (2 * M_PI);
}
}  // namespace

// point_to_patch (contour_sum of contour_edge_term) against the closed form, for points
// below a corner and below an inner point of a 1 x 0.5 rectangle (the sum of the four
// rectangles at that point: no cancellation in the reference), from 1e-3 to 1e3 of its size
// above: near edges take atan2, far ones (from ~4 sizes) the series. Error bound of the
// contour sum: r_k = p_k - x rounds by u|r_k| and each component of c = r_a x r_b by
// 2u|r_a||r_b| (|r_a,y r_b,z| + |r_a,z r_b,y| <= |r_a||r_b|), so |δc| <= 4√3 u |r_a||r_b|
// and c's direction turns by <= 4√3 u / sin θ: the term θ n·c/|c| moves by <= 4√3 u θ / sin θ.
// Its own evaluation (series: above; atan2 form: atan2_upper's 9.4u and 3 roundings) adds
// <= 16u θ. So
// |δF| <= Σ_k (4√3 θ_k / sin θ_k + 16 θ_k) u / 2π over the edges, plus the reference's 16u F.
TEST(ContourKernel, PointFactorMatchesTheParallelRectangleClosedForm) {
  const double a = 1.0, b = 0.5;
  int series_edges = 0, atan2_edges = 0;
  double worst = 0.0;
  for (double h : {1e-3, 1e-2, 0.1, 0.3, 1.0, 3.0, 10.0, 100.0, 1e3})
    for (const Eigen::Vector2d& at : {Eigen::Vector2d(0, 0), Eigen::Vector2d(0.3, 0.1)}) {
      ff::PatchGeom g;  // at z = h facing down, wound as point_to_patch expects
      g.n = 4;
      g.p = {Eigen::Vector3d(0, 0, h), Eigen::Vector3d(0, b, h), Eigen::Vector3d(a, b, h),
             Eigen::Vector3d(a, 0, h)};
      g.normal = -Eigen::Vector3d::UnitZ();
      g.area = a * b;
      const Eigen::Vector3d x(at.x(), at.y(), 0), n = Eigen::Vector3d::UnitZ();
      double exact = 0.0;  // the four corner rectangles around x's foot
      for (double u : {at.x(), a - at.x()})
        for (double v : {at.y(), b - at.y()})
          if (u > 0 && v > 0) exact += corner_point_factor(u, v, h);
      double bound = 16 * kUnitRoundoff * exact;
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d ra = g.p[k] - x, rb = g.p[(k + 1) % 4] - x, c = ra.cross(rb);
        const double theta = std::atan2(c.norm(), ra.dot(rb));
        bound += (4 * std::sqrt(3.0) * theta / std::sin(theta) + 16 * theta) * kUnitRoundoff /
                 (2 * M_PI);
        const double d = ra.dot(rb);
        (d > 0 && d * d >= ff::kContourSeriesMin * c.squaredNorm() ? series_edges : atan2_edges)++;
      }
      const double f = ff::point_to_patch(x, n, g);
      EXPECT_NEAR(f, exact, bound) << "h " << h << " at " << at.transpose();
      worst = std::max(worst, std::abs(f - exact) / bound);
    }
  EXPECT_GT(series_edges, 0);  // both branches of contour_edge_term were checked
  EXPECT_GT(atan2_edges, 0);
  std::printf("worst error %.3f of its bound; %d series edges, %d atan2 edges\n", worst,
              series_edges, atan2_edges);
}

}  // namespace lambert
