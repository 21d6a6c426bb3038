// Estimator "hybrid": exact unoccluded factor x an unbiased Monte Carlo visible fraction.
//
// With a the smaller patch of the pair (by area) and b the other,
//   G_ab = ∫_a F(x -> b) vis(x) dA_x,  vis(x) = ∫_b K V dA_y / ∫_b K dA_y,
// F(x -> b) the exact point-to-patch factor (Lambert's contour formula, horizon clipped)
// and K = cosθ_x cosθ_y / r². The unoccluded G0 = ∫_a F(x -> b) dA_x comes from the
// adaptive quadrature (quadrature.hpp: relative error < 1e-6 for any size ratio and
// distance). Ray r picks a cell c of that quadrature with probability G_c / G0 (the
// lattice's first coordinate, so cells are stratified), a point x_r uniform in it, and a
// point y_r of b with density ∝ K(x_r, ·) (visibility.hpp), so V_r = V(x_r, y_r) is a
// Bernoulli sample of vis(x_r) and
//   G ≈ G0 Σ_r w_r V_r / Σ_r w_r,   w_r = F(x_r -> b) A_c / G_c  (≈ 1: cells are small
// against their distance to b, so F varies little within one).
// Unoccluded pairs get G0 exactly (V = 1) and fully blocked ones exactly 0. The ratio of
// weights is consistent with a bias O(Var(w) / k), far below the statistical error (w
// varies by ~10 % within a cell). The standard error comes from R independent replicates
// (replicates.hpp) plus the quadrature's error bound, 1e-6 G0 (kQuadratureTolerance). Cost per pair: the quadrature nodes (9 .. ~500 contour evaluations) + k rays.

#include <algorithm>

#include "core/sampling.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/quadrature.hpp"
#include "geometry/formfactors/replicates.hpp"
#include "geometry/formfactors/visibility.hpp"

namespace lambert::ff {
namespace {

// A point uniform in area on a cell (triangle, or planar quad as two triangles); u picks
// the triangle, (s, t) place the point in it.
Eigen::Vector3d uniform_in_cell(const PatchGeom& g, double u, double s, double t) {
  Eigen::Vector3d a = g.p[0], b = g.p[1], c = g.p[2];
  if (g.n == 4) {
    const double first = 0.5 * (g.p[1] - g.p[0]).cross(g.p[2] - g.p[0]).norm();
    if (u * g.area >= first) {
      b = g.p[2];
      c = g.p[3];
    }
  }
  const double r = std::sqrt(s);
  return (1.0 - r) * a + r * (1.0 - t) * b + r * t * c;
}

}  // namespace

PairEstimate estimate_hybrid(const PairContext& ctx, std::int32_t i, std::int32_t j) {
  const bool i_small = ctx.geom[i].area <= ctx.geom[j].area;
  const PatchGeom& a = ctx.geom[i_small ? i : j];
  const PatchGeom& b = ctx.geom[i_small ? j : i];
  PairEstimate est;
  thread_local std::vector<QuadCell> cells;
  thread_local std::vector<double> cdf;
  const double G0 = integrate_unoccluded(a, b, kEstimatorAccuracy, cells);
  if (!(G0 > 0.0)) return est;
  cdf.clear();
  for (const QuadCell& c : cells) cdf.push_back((cdf.empty() ? 0.0 : cdf.back()) + c.G);
  const std::uint64_t key =
      hash_keys(ctx.seed, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(j));
  const int R = replicate_count(ctx.samples);
  double replicate[kReplicates];
  double num = 0.0, den = 0.0;
  bool unverified = false;
  for (int rep = 0; rep < R; ++rep) {
    const Kronecker4 seq(hash_keys(key, static_cast<std::uint64_t>(rep)));
    Rng rng(hash_keys(key, static_cast<std::uint64_t>(rep), 1));
    double rnum = 0.0, rden = 0.0;
    for (int r = 0, k = replicate_size(ctx.samples, rep); r < k; ++r) {
      const double pick = seq.get(r, 0) * cdf.back();
      const size_t c = std::min<size_t>(
          std::lower_bound(cdf.begin(), cdf.end(), pick) - cdf.begin(), cells.size() - 1);
      const double lo = c ? cdf[c - 1] : 0.0;
      const double within = std::clamp((pick - lo) / cells[c].G, 0.0, 1.0);
      const Eigen::Vector3d x = uniform_in_cell(cells[c].g, within, seq.get(r, 1), seq.get(r, 2));
      const double w = point_to_patch(x, a.normal, b) * cells[c].g.area / cells[c].G;
      if (!(w > 0.0)) continue;
      const KernelSampler sampler(x, a.normal, b);
      if (sampler.empty()) continue;
      bool exhausted;
      const Eigen::Vector3d y = sampler.sample(seq.get(r, 3), rng.uniform(), rng.uniform(), rng, exhausted);
      unverified = unverified || exhausted;
      ++est.rays;
      const bool v = visible(ctx.bvh, x, a.normal, y, b.normal, ctx.offset);
      rnum += v ? w : 0.0;
      rden += w;
    }
    num += rnum;
    den += rden;
    replicate[rep] = rden > 0.0 ? G0 * rnum / rden : G0;
  }
  if (!(den > 0.0)) {
    // No ray could be traced: report the unoccluded value, flagged (the driver warns).
    est.G = G0;
    est.unverified = true;
    return est;
  }
  est.G = G0 * num / den;
  // Sampling variance plus the quadrature's error bound (kQuadratureTolerance of G0, the
  // worst case measured by the sweep in tests/geometry/quadrature_test.cpp), so that the
  // error bar of an unoccluded pair (no sampling error) is not zero.
  const double quad = kQuadratureTolerance * G0;
  est.var = replicate_variance(replicate, R) + quad * quad;
  est.unverified = unverified;
  return est;
}

}  // namespace lambert::ff
