// Estimator "mc": Monte Carlo area-to-area form factors.
//
//   G_ij ≈ (1/k) Σ_s K(x_s, y_s) V(x_s, y_s) J_i(x_s) J_j(y_s),
//   K = cosθ_i cosθ_j / (π r²)  (front sides only: both cosines clamped at 0),
// with (x_s, y_s) the points of a randomly shifted 4-D Kronecker lattice mapped onto the
// two patches. Unbiased; the reported variance is the sample variance / k (conservative
// for low-discrepancy points). Variance is large for patches sharing an edge (the 1/r²
// singularity): use "hybrid" there. Cost: k kernel evaluations and ≤ k rays per pair.

#include "core/sampling.hpp"
#include "geometry/formfactors/pairwise.hpp"

namespace lambert::ff {

PairEstimate estimate_mc(const PairContext& ctx, std::int32_t i, std::int32_t j) {
  const PatchGeom& a = ctx.geom[i];
  const PatchGeom& b = ctx.geom[j];
  const Kronecker4 seq(hash_keys(ctx.seed, static_cast<std::uint64_t>(i),
                                 static_cast<std::uint64_t>(j)));
  PairEstimate est;
  double sum = 0.0, sum2 = 0.0;
  const int k = ctx.samples;
  for (int s = 0; s < k; ++s) {
    double ja, jb;
    const Eigen::Vector3d x = sample_patch(a, seq.get(s, 0), seq.get(s, 1), ja);
    const Eigen::Vector3d y = sample_patch(b, seq.get(s, 2), seq.get(s, 3), jb);
    const Eigen::Vector3d d = y - x;
    const double r2 = d.squaredNorm();
    const double ci = a.normal.dot(d), cj = -b.normal.dot(d);
    if (ci <= 0.0 || cj <= 0.0 || r2 <= 0.0) continue;
    ++est.rays;
    if (!visible(ctx.bvh, x, a.normal, y, b.normal, ctx.offset)) continue;
    const double f = ci * cj / (M_PI * r2 * r2) * ja * jb;
    sum += f;
    sum2 += f * f;
  }
  est.G = sum / k;
  est.var = k > 1 ? std::max(0.0, (sum2 / k - est.G * est.G) / (k - 1)) : 0.0;
  return est;
}

}  // namespace lambert::ff
