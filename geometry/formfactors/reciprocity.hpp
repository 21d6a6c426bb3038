#pragma once
// Reciprocity averaging of an estimated F (internal to geometry/, exposed for its tests).
//
// Estimators that compute each row on its own (gather, hemicube) give A_i F_ij ≠ A_j F_ji.
// Averaging replaces both by
//   G_ij = (A_i F_ij + A_j F_ji) / 2          (scene units²; an entry absent on one side
//                                              counts 0 there, so its mirror is created)
// and F_ij = G_ij / A_i, so the sparsity becomes symmetric. Averaging can push a row sum
// above 1 (a small patch i facing a big patch j whose row undercounts i: F_ij ← (F_ij +
// A_j F_ji / A_i) / 2). Rows with r_i = Σ_j G_ij / A_i > 1 + kRowSumSlack get s_i = 1 / r_i
// (others s_i = 1), and every pair is scaled by min(s_i, s_j): symmetric, so reciprocity
// holds, and row i's sum becomes Σ_j min(s_i, s_j) G_ij / A_i ≤ s_i r_i = 1 in one pass
// (other rows only decrease). For unbiased rows the expected sum is ≤ 1, so the scaling
// removes noise above 1 only; its size is reported.
// Standard errors (independent rows) become sqrt((A_i s_ij)² + (A_j s_ji)²) / 2 / A_i, then
// scaled like their entries.
// Complexity O(nnz) (one sparse transpose and two merged sweeps); not thread-parallel.

#include <vector>

#include "geometry/formfactors/formfactors.hpp"

namespace lambert::ff {

/// Row sums up to 1 + this are left alone: rounding of a sum of up to ~1e6 terms in double
/// precision (~1e6 · 1.1e-16 ≈ 1e-10), far below any estimator's noise.
constexpr double kRowSumSlack = 1e-10;

/// Averages A_i F_ij and A_j F_ji in place (F, and stderr_F when it has F's pattern) and
/// records the change in `stats` (the reciprocity_* members).
void average_reciprocal(SparseF& F, SparseF* stderr_F, const std::vector<double>& areas,
                        FormFactorStats& stats);

}  // namespace lambert::ff
