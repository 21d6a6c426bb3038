// Estimator "mc": Monte Carlo area-to-area form factors.
//
//   G_ij ≈ (1/k) Σ_s K(x_s, y_s) V(x_s, y_s) J_i(x_s) J_j(y_s),
//   K = cosθ_i cosθ_j / (π r²)  (front sides only: both cosines clamped at 0),
// with (x_s, y_s) the points of a randomly shifted 4-D Kronecker lattice mapped onto the
// two patches, in R independently shifted replicates. Unbiased; the variance comes from the
// spread of the replicates (replicates.hpp). Cost: k kernel evaluations and ≤ k rays per pair.
//
// Near pairs go to the hybrid kernel. K is unbounded where patches touch (a shared edge, a
// block standing on a floor), and so is plain Monte Carlo's variance there: on the Cornell
// box 8 samples gave entries above 1 and row sums of 2.4, which no solve can use. A pair is
// near when a corner of either patch lies closer to the other patch than the larger of their
// diameters, D (this catches every contact at a corner or along an edge; two edge interiors
// crossing is not caught). Near pairs get estimate_hybrid: the exact unoccluded factor times
// a visible fraction in [0, 1], never above the unoccluded value. Far pairs keep plain Monte
// Carlo, their kernel of order 1/(pi D²) or less.

#include <algorithm>

#include "core/sampling.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/quadrature.hpp"
#include "geometry/formfactors/replicates.hpp"

namespace lambert::ff {
namespace {

// True when some corner of either patch lies closer to the other than the larger diameter.
// Every point of a patch lies within its diameter of its centroid, so no corner of one can be
// within d of the other while the centroids are more than d + both diameters apart: then
// the eight point-to-patch distances (~10 % of a far pair's time at 16 samples) are skipped.
// The 1 % margin covers rounding and the warp of a quad (at most 1e-4 of its extent) that
// distance_to_patch measures from its first corner's plane: the answer is the same.
bool near_pair(const PatchGeom& a, const PatchGeom& b) {
  const double d = std::max(a.diameter, b.diameter);
  if ((a.centroid - b.centroid).norm() > 1.01 * (d + a.diameter + b.diameter)) return false;
  for (int k = 0; k < a.n; ++k)
    if (distance_to_patch(a.p[k], b) < d) return true;
  for (int k = 0; k < b.n; ++k)
    if (distance_to_patch(b.p[k], a) < d) return true;
  return false;
}

}  // namespace

PairEstimate estimate_mc(const PairContext& ctx, std::int32_t i, std::int32_t j) {
  const PatchGeom& a = ctx.geom[i];
  const PatchGeom& b = ctx.geom[j];
  if (near_pair(a, b)) return estimate_hybrid(ctx, i, j);
  const std::uint64_t key =
      hash_keys(ctx.seed, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(j));
  PairEstimate est;
  const int R = replicate_count(ctx.samples);
  double replicate[kReplicates];
  // The segments go to the batch with their replicate and kernel; each replicate's sum
  // adds its unblocked kernels in sample order.
  struct Ray {
    int rep;
    double kernel;
  };
  thread_local SegmentBatch<Ray> batch;
  batch.clear();
  double sum[kReplicates] = {};
  auto each = [&](const Ray& ray, bool free) {
    if (free) sum[ray.rep] += ray.kernel;
  };
  const double lift_a = end_lift(a, ctx.offset), lift_b = end_lift(b, ctx.offset);
  for (int rep = 0; rep < R; ++rep) {
    const Kronecker4 seq(hash_keys(key, static_cast<std::uint64_t>(rep)));
    for (int s = 0, k = replicate_size(ctx.samples, rep); s < k; ++s) {
      double ja, jb;
      const Eigen::Vector3d x = sample_patch(a, seq.get(s, 0), seq.get(s, 1), ja);
      const Eigen::Vector3d y = sample_patch(b, seq.get(s, 2), seq.get(s, 3), jb);
      const Eigen::Vector3d d = y - x;
      const double r2 = d.squaredNorm();
      const double ci = a.normal.dot(d), cj = -b.normal.dot(d);
      if (ci <= 0.0 || cj <= 0.0 || r2 <= 0.0) continue;
      batch.add(x, a.normal, lift_a, y, b.normal, lift_b,
                Ray{rep, ci * cj / (M_PI * r2 * r2) * ja * jb});
      if (batch.full()) est.rays += batch.flush(ctx.bvh, each);
    }
  }
  est.rays += batch.flush(ctx.bvh, each);
  double total = 0.0;
  for (int rep = 0; rep < R; ++rep) {
    total += sum[rep];
    replicate[rep] = sum[rep] / replicate_size(ctx.samples, rep);
  }
  est.G = total / ctx.samples;
  est.var = replicate_variance(replicate, R);
  return est;
}

}  // namespace lambert::ff
