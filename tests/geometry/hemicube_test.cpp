#include "geometry/formfactors/hemicube.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "geometry/analytic.hpp"
#include "geometry/formfactors/kernels.hpp"

namespace lambert {
namespace {

// The hemicube origin is lifted by 1e-6 of the scene diagonal (kOffset in hemicube.cpp);
// the references below are taken at the same point so that the offset is not an error.
constexpr double kHemicubeOffset = 1e-6;

FormFactors hemicube(const PatchMesh& mesh, int resolution, std::uint64_t seed = 1,
                     int threads = 0, bool symmetrize = false) {
  FormFactorOptions o;
  o.estimator = "hemicube";
  o.hemicube.resolution = resolution;
  o.run.seed = seed;
  o.run.threads = threads;
  o.reciprocity = symmetrize ? "average" : "none";
  o.run.progress = false;
  return compute_form_factors(mesh, o);
}

// The exact point-to-patch factor F(c_i -> j) from the hemicube's origin over patch i:
// the quantity the hemicube estimates (its area average over i is another matter: the
// proximity error, shown by `lambert accuracy`).
double centre_factor(const PatchMesh& mesh, std::int32_t i, std::int32_t j) {
  const auto g = ff::patch_geometry(mesh);
  const Eigen::Vector3d c = g[i].centroid + kHemicubeOffset * mesh.scale * g[i].normal;
  return ff::point_to_patch(c, g[i].normal, g[j]);
}

// Σ over the pixels of |ΔF_midpoint - ΔF_exact|, with the exact factor of each pixel
// rectangle from the differential area at the origin (Lambert's contour formula): the
// total discretisation error of the delta form factors. `exact_total` receives Σ ΔF_exact.
double delta_factor_error(int n, double* exact_total = nullptr) {
  const ff::HemicubeDeltas d = ff::hemicube_deltas(n);
  const Eigen::Vector3d o = Eigen::Vector3d::Zero(), up = Eigen::Vector3d::UnitZ();
  auto pixel = [](const Eigen::Vector3d& p0, const Eigen::Vector3d& du, const Eigen::Vector3d& dv,
                  const Eigen::Vector3d& normal) {
    ff::PatchGeom g;
    g.n = 4;
    g.p = {p0, p0 + dv, p0 + du + dv, p0 + du};  // wound about `normal` (towards the origin)
    g.normal = normal;
    return g;
  };
  const double dx = 2.0 / d.n, dz = 1.0 / d.m;
  double err = 0.0, exact = 0.0;
  for (int r = 0; r < d.n; ++r)
    for (int c = 0; c < d.n; ++c) {
      const auto g = pixel({-1 + c * dx, -1 + r * dx, 1}, {dx, 0, 0}, {0, dx, 0}, -up);
      const double f = ff::point_to_patch(o, up, g);
      err += std::abs(d.top[r * d.n + c] - f);
      exact += f;
    }
  for (int r = 0; r < d.m; ++r)
    for (int c = 0; c < d.n; ++c) {
      const auto g = pixel({1, -1 + c * dx, r * dz}, {0, dx, 0}, {0, 0, dz}, {-1, 0, 0});
      const double f = ff::point_to_patch(o, up, g);
      err += 4.0 * std::abs(d.side[r * d.n + c] - f);
      exact += 4.0 * f;
    }
  if (exact_total) *exact_total = exact;
  return err;
}

}  // namespace

TEST(HemicubeDeltas, SumToOneWithSecondOrderDiscretisationError) {
  // Σ ΔF is the midpoint rule for ∫ cosθ/(π r²) ... over the five faces, = 1 exactly. Its
  // error is (δ²/24) ∫ ∇²f + O(δ⁴) with δ = 2/N: the ratio e_N / e_2N tends to 4. We require
  // >= 3 (the O(δ⁴) term makes it smaller at N = 8) and a strict decrease.
  double previous = 0.0;
  for (int n = 8; n <= 512; n *= 2) {
    const double e = std::abs(ff::hemicube_deltas(n).total() - 1.0);
    if (n > 8) {
      EXPECT_LE(e, previous / 3.0) << "N = " << n << ", error " << e;
    }
    previous = e;
  }
  // And it is within the per-pixel bound: |Σ ΔF - 1| <= Σ |ΔF_mid - ΔF_exact|.
  // The exact pixel factors tile the hemisphere: they sum to 1 up to the rounding of 3N²
  // contour evaluations (~1e-16 each).
  for (int n : {16, 64}) {
    double exact_total = 0.0;
    const double bound = delta_factor_error(n, &exact_total);
    EXPECT_NEAR(exact_total, 1.0, 1e-12);
    EXPECT_LE(std::abs(ff::hemicube_deltas(n).total() - 1.0), bound);
  }
}

TEST(FormFactorHemicube, ParallelSquaresWithinPixelBoundThatShrinksWithResolution) {
  // One patch each: the hemicube estimates F(c_a -> b). Bound (pixel-size argument):
  // a pixel is wrong only if (i) its delta factor is (Σ|ΔF_mid - ΔF_exact| = E_mid over all
  // pixels) or (ii) the projected boundary of b crosses it (error <= its ΔF, at most
  // ΔF_max + its own midpoint error). b projects to a unit square on the top face (at height
  // 1 from c_a, half-width 0.5: |x|,|y| <= 0.5, any rotation about the normal), perimeter
  // L = 4; a segment of length l crosses at most √2 l / δ + 2 pixels (δ = 2/N). So
  //   |err| <= 2 E_mid + (√2 L / δ + 8) ΔF_max,   ΔF_max = δ² / π (the top-face centre),
  // which falls like 1/N.
  const PatchMesh mesh = mesh_scene(parallel_squares(1.0), {});
  const double exact = centre_factor(mesh, 0, 1);
  double previous_bound = 1.0;
  for (int n : {16, 32, 64, 128, 256}) {
    const double delta = 2.0 / n;
    const double bound = 2.0 * delta_factor_error(n) +
                         (std::sqrt(2.0) * 4.0 / delta + 8.0) * delta * delta / M_PI;
    EXPECT_LT(bound, previous_bound);
    previous_bound = bound;
    for (std::uint64_t seed : {1, 2, 3}) {  // seeds turn the hemicube about the normal
      const FormFactors ff = hemicube(mesh, n, seed);
      EXPECT_NEAR(ff.F.coeff(0, 1), exact, bound) << "N = " << n << ", seed " << seed;
      EXPECT_NEAR(ff.F.coeff(1, 0), exact, bound) << "N = " << n << ", seed " << seed;
    }
  }
}

TEST(FormFactorHemicube, SharedEdgeSquaresConvergeAtLeastLinearlyInResolution) {
  // One patch each, sharing an edge: b fills one side face and part of the top face of a's
  // hemicube. The pixel-size argument above gives an error O(1/N) (boundary pixels, each
  // ΔF = O(δ²), number O(1/δ)); with the random turn about the normal the boundary errors
  // are zero-mean, so the error averaged over turns (seeds) falls at least like 1/N. We fit
  // the log-log slope of the mean |error| over N = 16..256 and require <= -0.75 (the
  // predicted -1 with a margin for the scatter of 8 turns), and every error below the
  // parallel case's form of the bound with L = 8 (b's projected outline on the unfolded
  // hemicube is shorter: 1 + √2 on the top face, <= 2 per vertical edge on the sides).
  const PatchMesh mesh = mesh_scene(perpendicular_squares(), {});
  const double exact = centre_factor(mesh, 0, 1);
  ASSERT_NEAR(exact, centre_factor(mesh, 1, 0), 1e-12);  // symmetric configuration
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int points = 0;
  for (int n : {16, 32, 64, 128, 256}) {
    const double delta = 2.0 / n;
    const double bound = 2.0 * delta_factor_error(n) +
                         (std::sqrt(2.0) * 8.0 / delta + 16.0) * delta * delta / M_PI;
    double mean = 0.0;
    const int seeds = 8;
    for (int seed = 1; seed <= seeds; ++seed) {
      const FormFactors ff = hemicube(mesh, n, seed);
      for (auto [i, j] : {std::pair{0, 1}, std::pair{1, 0}}) {
        const double err = std::abs(ff.F.coeff(i, j) - exact);
        EXPECT_LE(err, bound) << "N = " << n << ", seed " << seed;
        mean += err / (2 * seeds);
      }
    }
    const double x = std::log(n), y = std::log(mean);
    sx += x, sy += y, sxx += x * x, sxy += x * y, ++points;
  }
  const double slope = (points * sxy - sx * sy) / (points * sxx - sx * sx);
  EXPECT_LE(slope, -0.75);
}

TEST(FormFactorHemicube, ClosedCubeRowsSumToTheDeltaFactorTotal) {
  // Every direction above a face of the closed cube hits another face, so each row of F is
  // the sum of all delta factors, up to rounding at the seams: a pixel centre exactly on a
  // shared edge could be missed by both neighbours (at most a couple of pixels, each
  // <= ΔF_max = δ²/π).
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.25, 0});
  const int n = 64;
  const double total = ff::hemicube_deltas(n).total();
  const double tol = 2.0 * std::pow(2.0 / n, 2) / M_PI;
  const FormFactors ff = hemicube(mesh, n);
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    EXPECT_NEAR(ff.F.row(i).sum(), total, tol) << "row " << i;
}

TEST(FormFactorHemicube, PairFullyBlockedByAPlateFromEitherSideIsZero) {
  // A 3x3 plate halfway between the unit squares hides each from the other's centre; the
  // plate is one-sided, so for one of the squares it is a back face: back faces occlude.
  Scene scene = parallel_squares(1.0);
  const Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(scene, "plate", grey, {{-1, -1, 0.5}, {2, -1, 0.5}, {2, 2, 0.5}, {-1, 2, 0.5}});
  const PatchMesh mesh = mesh_scene(scene, {});
  const FormFactors ff = hemicube(mesh, 64);
  EXPECT_EQ(ff.F.coeff(0, 1), 0.0);
  EXPECT_EQ(ff.F.coeff(1, 0), 0.0);
  EXPECT_EQ(ff.F.coeff(0, 2), 0.0);  // a sees the plate's back: only fronts receive
  EXPECT_GT(ff.F.coeff(1, 2), 0.0);  // b sees its front (the plate faces +z)
}

TEST(FormFactorHemicube, BitwiseIdenticalForAnyThreadCount) {
  Scene scene = unit_cube();
  const Material grey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};
  add_polygon(scene, "plate", grey, {{0.2, 0.2, 0.5}, {0.8, 0.2, 0.5}, {0.8, 0.8, 0.5}, {0.2, 0.8, 0.5}});
  const PatchMesh mesh = mesh_scene(scene, {0.2, 0});
  const FormFactors one = hemicube(mesh, 48, 7, 1);
  for (int threads : {2, 3}) {
    const FormFactors many = hemicube(mesh, 48, 7, threads);
    ASSERT_EQ(one.F.nonZeros(), many.F.nonZeros());
    const auto nnz = static_cast<size_t>(one.F.nonZeros());
    EXPECT_EQ(0, std::memcmp(one.F.valuePtr(), many.F.valuePtr(), nnz * sizeof(double)));
    EXPECT_EQ(0, std::memcmp(one.F.innerIndexPtr(), many.F.innerIndexPtr(), nnz * sizeof(std::int32_t)));
    EXPECT_EQ(0, std::memcmp(one.F.outerIndexPtr(), many.F.outerIndexPtr(),
                             (mesh.size() + 1) * sizeof(std::int32_t)));
  }
}

TEST(FormFactorHemicube, SymmetrizeMakesReciprocityHoldToRounding) {
  // G = (A_i F_ij + A_j F_ji)/2 is symmetric by construction; F_ij = G_ij / A_i and the
  // check A_i F_ij multiplies back: two roundings of relative size 2^-53 each, so
  // |A_i F_ij - A_j F_ji| <= 4 ε max(A_i F_ij, A_j F_ji).
  const PatchMesh mesh = mesh_scene(perpendicular_squares(), {0.3, 0});
  const FormFactors raw = hemicube(mesh, 32);
  const FormFactors sym = hemicube(mesh, 32, 1, 0, true);
  double raw_residual = 0.0;
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    for (SparseF::InnerIterator it(sym.F, i); it; ++it) {
      const std::int32_t j = static_cast<std::int32_t>(it.col());
      const double aij = mesh.patches[i].area * it.value();
      const double aji = mesh.patches[j].area * sym.F.coeff(j, i);
      EXPECT_NEAR(aij, aji, 4 * std::numeric_limits<double>::epsilon() * std::max(aij, aji));
      raw_residual = std::max(raw_residual, std::abs(mesh.patches[i].area * raw.F.coeff(i, j) -
                                                     mesh.patches[j].area * raw.F.coeff(j, i)));
    }
  EXPECT_GT(raw_residual, 0.0);  // the plain hemicube is not reciprocal
}

}  // namespace lambert
