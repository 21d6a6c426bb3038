#pragma once
// Estimator "gather" (internal to geometry/, exposed for its tests and benchmark).
//
// The classic ray-traced form factor: from each patch i, K rays leave stratified points x_s
// on i in cosine-distributed directions ω_s (density cosθ / π), and
//   F_ij ≈ (1/K) Σ_s w_s [the closest hit of (x_s, ω_s) is the front of patch j],
//   w_s = J(x_s) / A_i   (the area sampling weight, kernels.hpp's sample_patch: 1 on
//                         triangles and parallelograms),
// an unbiased estimate of (1/A_i) ∫_{A_i} ∫_{Ω} V cosθ / π [front of j] dω dA, which is
// F_ij. Hits on backs, on i itself, and misses (an open scene) count for nothing, so a row
// sum is the fraction of rays that reach a front. Not reciprocal: see reciprocity.hpp.
// Rows have at most K entries; cost O(N·K) rays, no all-pairs loop. The direct light (pairs
// with an emitting patch) comes from the hybrid kernel when there are few emitters (below).

#include <cstdint>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert::ff {

/// Rows are traced in blocks of this many (in parallel within a block) and appended to the
/// reserved CSR after each block: the staging is one block of rows.
constexpr std::int32_t kGatherBlockRows = 4096;

/// Visibility rays per emitter pair of gather's direct light (the hybrid kernel's samples):
/// its unoccluded factor is exact, so these only sample the visible fraction in penumbrae.
constexpr int kGatherDirectSamples = 16;

/// Whether gather estimates the pairs with an emitting patch by the hybrid kernel: when
/// there are some, at most an eighth of the patches, and at most K / 4 of them. A pair
/// estimate (a quadrature and 16 rays) costs about 10 of gather's rays (measured on the
/// Cornell box at 8,012 patches: 336k pairs added 4.6 CPU s to 8.2M rays' 11), so a row's
/// pairs cost at most ~2.5x its K rays; the Cornell box's light stays within the bound up
/// to about 49,000 patches at the default K.
inline bool gather_direct_pairs(std::int64_t emitters, std::int64_t patches, std::int64_t rays) {
  return emitters > 0 && 8 * emitters <= patches && 4 * emitters <= rays;
}

/// The patches whose pairs gather estimates by the hybrid kernel with K rays per patch (the
/// emitting ones, when gather_direct_pairs holds), one flag per patch; empty otherwise.
/// Reciprocity averaging keeps those pairs as they are (reciprocity.hpp).
std::vector<char> gather_direct_patches(const PatchMesh& mesh, std::int64_t rays);

/// Estimator "gather": options.gather.rays rays per patch, in replicate_count(rays) independently
/// shifted Kronecker point sets (replicates.hpp) whose spread gives the standard errors.
/// Rows are computed in parallel, a block at a time, and appended in row order to a CSR
/// reserved with room for averaging's mirrors, so F is bitwise identical for any thread
/// count and averaging runs in place. With gather_direct_pairs, the pairs with an emitter
/// are the hybrid kernel's (kGatherDirectSamples rays each), an emitter's row is its pairs
/// alone, and another row's ray estimates are scaled by (1 - h_i) / (1 - f_i) (h_i its
/// emitters' summed factor, f_i the share of its rays that hit them: the rest of its
/// hemisphere), so a closed scene's rows still sum to the fraction of rays that reach a
/// front. stats.rays = N·K (less the emitters' rows, plus the pairs' rays); stats.pairs_tested =
/// the unordered pairs connected by at least one ray (either way), pairs_culled the rest.
/// Reciprocity averaging is the caller's (compute_form_factors).
FormFactors compute_gather(const PatchMesh& mesh, const FormFactorOptions& options,
                           const Bvh& bvh);

}  // namespace lambert::ff
