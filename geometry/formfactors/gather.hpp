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
// Rows have at most K entries; cost O(N·K) rays, no all-pairs loop.

#include <cstdint>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert::ff {

/// Rows are traced in blocks of this many (in parallel within a block) and appended to the
/// reserved CSR after each block: the staging is one block of rows.
constexpr std::int32_t kGatherBlockRows = 4096;

/// Estimator "gather": options.gather.rays rays per patch, in replicate_count(rays) independently
/// shifted Kronecker point sets (replicates.hpp) whose spread gives the standard errors.
/// Rows are computed in parallel, a block at a time, and appended in row order to a CSR
/// reserved with room for averaging's mirrors, so F is bitwise identical for any thread
/// count and averaging runs in place. stats.rays = N·K; stats.pairs_tested = the
/// unordered pairs connected by at least one ray (either way), pairs_culled the rest.
/// Reciprocity averaging is the caller's (compute_form_factors).
FormFactors compute_gather(const PatchMesh& mesh, const FormFactorOptions& options,
                           const Bvh& bvh);

}  // namespace lambert::ff
