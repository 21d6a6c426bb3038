#pragma once
// Reciprocity averaging of an estimated F (internal to geometry/, exposed for its tests).
//
// Estimators that compute each row on its own (gather, hemicube) give A_i F_ij ≠ A_j F_ji.
// Three steps, each keeping G symmetric (so A_i F_ij = A_j F_ji to rounding):
//  1. average: G_ij = (A_i F_ij + A_j F_ji) / 2 (scene units²; an entry absent on one side
//     counts 0 there, so its mirror is created and the sparsity becomes symmetric);
//  2. balance: G_ij ← d_i d_j G_ij with d chosen so that every row sums to its own sum
//     before averaging, t_i = min(1, Σ_j F_ij). Averaging mixes row i's sum (for gather
//     the fraction of i's rays that reached a front: exactly 1 in a closed scene) with
//     column i's (the other rows' noise); about half the rows of a closed scene then
//     exceed 1, and capping them alone removes the upper half of that noise: a bias of
//     ~-0.4 σ_row (measured -2 % on the unit cube at K = 256, -1 % at 1024). Balancing
//     restores each row's own sum instead, so closed scenes keep row sums of 1 and open
//     ones each patch's escape fraction. d is the fixed point of the symmetric
//     Sinkhorn-Knopp update d_i ← d_i (A_i t_i / (d_i Σ_j G_ij d_j))^ω (Knight 2008, damped
//     with ω = 1/2; over-relaxed here with ω = 0.8 and Anderson-accelerated: 119 damped
//     sweeps on the Cornell box, 70 over-relaxed, 28 accelerated), at most
//     kBalanceIterations sweeps, d_i clamped to [1/kMaxScale, kMaxScale]; rows with
//     t_i = 0 (nothing seen) keep d_i = 1. A pattern with no exact balance (two patches
//     that see only each other, A_1 t_1 ≠ A_2 t_2) converges to the geometric mean of the
//     two targets for their pair;
//  3. cap: rows still above 1 + kRowSumSlack get s_i = 1 / r_i (others s_i = 1), and every
//     pair is scaled by min(s_i, s_j): row i then sums to ≤ s_i r_i = 1 in one pass, others
//     only decrease.
// Standard errors (independent rows) become sqrt((A_i s_ij)² + (A_j s_ji)²) / 2 / A_i, then
// scaled like their entries (the balancing factors are treated as constants).
//
// In place: F's storage becomes the result, so the peak is the averaged CSR (the union of
// F's and F^T's patterns, at most 2 nnz) plus O(N). (a) Pairs stored both ways are averaged
// where they stand, rows in parallel, each pair by its lower row (its mirror found by
// binary search); an entry without a mirror is marked by its sign. (b) Row i of the union
// gains (entries of column i) − (entries of row i with a mirror); rows move to their final
// starts from the last to the first. (c) The marked entries' mirrors are appended to their
// rows in increasing source row (each appended run sorted), and (d) every row merges its
// two sorted runs from the back through a buffer of its appended run. If the storage has no
// room for the union (F.data().allocatedSize()), it is reallocated once with a copy (the old
// and new storage coexist for that moment): callers that reserve room for the union (gather)
// avoid it. Complexity O(nnz log L) for the mirror searches (L the row length), O(nnz) for
// the moves and merges, O(nnz) per balancing sweep (rows in parallel). Deterministic, and
// bitwise identical for any thread count.
//
// Statistics: the originals are not kept, so the change is reported for the averaging step
// (reciprocity_mean/max_relative_change, computed as it happens) and the balancing and cap
// as the range of their pair factors d_i d_j min(s_i, s_j) (reciprocity_scale_min/max).

#include <vector>

#include "geometry/formfactors/formfactors.hpp"

namespace lambert::ff {

/// Row sums up to 1 + this are left alone: rounding of a sum of up to ~1e6 terms in double
/// precision (~1e6 · 1.1e-16 ≈ 1e-10), far below any estimator's noise.
constexpr double kRowSumSlack = 1e-10;

/// Balancing stops when every row with a target is within this relative error of it:
/// 1e-12 is ~1e4 ulps, far below any estimator's noise; the unit cube needs a few sweeps,
/// the Cornell box (open, 2000-30000 patches, K = 64-1024) 118-135 damped, ~70 over-relaxed,
/// 26-30 Anderson-accelerated.
constexpr double kBalanceTolerance = 1e-12;
/// At most this many balancing sweeps (each O(nnz)); the cap catches what is left.
constexpr int kBalanceIterations = 200;
/// The balancing's over-relaxation ω (reciprocity.cpp's balance: 1/2 is Knight's damped
/// update; any ω < 1 converges near the fixed point; 0.8 took 40 % fewer sweeps).
constexpr double kBalanceOverRelaxation = 0.8;
/// Anderson acceleration of the balancing sweeps: the last kAndersonDepth steps are combined
/// (3-5 is the usual range; the history costs 2 N of them in doubles), and after
/// kAndersonRestarts restarts (the residual grew) the sweeps go on damped and unaccelerated.
constexpr int kAndersonDepth = 8;
constexpr int kAndersonRestarts = 4;
/// Balancing factors stay within [1/4, 4]: the correction is of the order of the rows'
/// noise (a few per cent); the clamp only bounds the unbalanceable patterns.
constexpr double kMaxScale = 4.0;

/// Averages A_i F_ij and A_j F_ji in place (F, and stderr_F when it has F's pattern),
/// balances and caps the rows (see above), and records the change in `stats` (the
/// reciprocity_* members). `threads` as for parallel_for (0 = all cores). With `kept_pairs`
/// (one flag per patch, or empty), the pairs with a flagged patch are reciprocal estimates
/// already (gather's direct light by pairs): the balance holds them as they are and scales
/// the others so that every row still meets its target.
void average_reciprocal(SparseF& F, SparseF* stderr_F, const std::vector<double>& areas,
                        FormFactorStats& stats, int threads = 0,
                        const std::vector<char>* kept_pairs = nullptr);

}  // namespace lambert::ff
