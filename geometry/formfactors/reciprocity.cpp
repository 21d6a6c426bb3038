// Reciprocity averaging: see reciprocity.hpp for the equations, the balancing, the row-sum
// cap and the in-place layout.

#include "geometry/formfactors/reciprocity.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "geometry/formfactors/mirror.hpp"

namespace lambert::ff {
namespace {

using Index = SparseF::StorageIndex;

// Per-row sums of the averaging step's change (stats), reduced in row order afterwards so
// that they do not depend on the thread count.
struct RowChange {
  double changed = 0.0, total = 0.0, max_rel = 0.0;
  std::int64_t matched = 0;  // entries of the row whose mirror is stored
};

// Step 1 on F's own layout, rows in parallel: every pair stored both ways (i < j) gets
// G_ij = (A_i F_ij + A_j F_ji) / 2 in both entries (G units, divided by A_i at the end);
// an entry whose mirror is missing gets -A_i F_ij / 2, the sign marking it for
// append_mirrors (F ≥ 0; std::signbit also marks a stored 0). Standard errors likewise:
// sqrt((A_i s_ij)² + (A_j s_ji)²) / 2, or A_i s_ij / 2 one-way. Each pair is written by the
// thread of its lower row only, and column indices are only read: no races.
void average_pairs(SparseF& F, SparseF* S, const Eigen::VectorXd& a, int threads,
                   std::vector<RowChange>& change) {
  const Index* outer = F.outerIndexPtr();
  const Index* col = F.innerIndexPtr();
  double* val = F.valuePtr();
  double* err = S ? S->valuePtr() : nullptr;
  const std::uint64_t call = MirrorCursor::next_call();
  parallel_for(F.rows(), 256, threads, [&](std::int64_t begin, std::int64_t end) {
    thread_local MirrorCursor mirror;
    mirror.rows(F.rows());
    for (std::int64_t i = begin; i < end; ++i) {
      RowChange rc;
      for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) {
        const Index j = col[k];
        const double gij = a[i] * val[k];
        if (j == i) {  // its own mirror: unchanged
          val[k] = gij;
          if (err) err[k] *= a[i];
          rc.total += gij;
          ++rc.matched;
          continue;
        }
        const std::int64_t q = mirror.find(col, outer, j, static_cast<Index>(i), call);
        if (q < 0) {
          const double g = gij / 2;
          val[k] = -g;
          if (err) err[k] = a[i] * err[k] / 2;
          rc.changed += 2 * g;  // |g - G_ij| here and |g - 0| at the created mirror
          rc.total += gij;
          if (gij > 0.0) rc.max_rel = std::max(rc.max_rel, 0.5);
          continue;
        }
        ++rc.matched;
        if (j < i) continue;  // the pair was done from row j
        const double gji = a[j] * val[q];
        const double g = (gij + gji) / 2;
        val[k] = val[q] = g;
        if (err) {
          const double si = a[i] * err[k], sj = a[j] * err[q];
          err[k] = err[q] = std::sqrt(si * si + sj * sj) / 2;
        }
        // Both entries' changes are counted here, in row i's sums (a sum over pairs).
        rc.changed += std::abs(g - gij) + std::abs(g - gji);
        rc.total += gij + gji;
        if (gij > 0.0) rc.max_rel = std::max(rc.max_rel, std::abs(g - gij) / gij);
        if (gji > 0.0) rc.max_rel = std::max(rc.max_rel, std::abs(g - gji) / gji);
      }
      change[i] = rc;
    }
  });
}

// Moves every row of F (and the values of S) to its place in the union pattern, from the
// last row to the first: row i goes from old[i] to start[i] ≥ old[i] (rows before i only
// gain entries), so a row never overwrites one not yet moved. Its mirror slots follow it.
void spread_rows(SparseF& F, SparseF* S, const std::vector<std::int64_t>& old,
                 const std::vector<std::int64_t>& start) {
  Index* col = F.innerIndexPtr();
  double* val = F.valuePtr();
  double* err = S ? S->valuePtr() : nullptr;
  for (std::int64_t i = static_cast<std::int64_t>(start.size()) - 2; i >= 0; --i) {
    const std::int64_t from = old[i], count = old[i + 1] - old[i], to = start[i];
    if (to == from) break;  // rows 0..i gain nothing: already in place
    std::copy_backward(col + from, col + from + count, col + to + count);
    std::copy_backward(val + from, val + from + count, val + to + count);
    if (err) std::copy_backward(err + from, err + from + count, err + to + count);
  }
}

// The created mirrors, sequentially: the marked entry (i, j) (average_pairs) gets its
// G = A_i F_ij / 2 back, and (j, i) with the same G is appended to row j's mirror slots.
// Rows are visited in increasing i, so every row's appended run is sorted by column.
void append_mirrors(SparseF& F, SparseF* S, const std::vector<std::int64_t>& old,
                    const std::vector<std::int64_t>& start) {
  const auto n = static_cast<std::int64_t>(start.size()) - 1;
  Index* col = F.innerIndexPtr();
  double* val = F.valuePtr();
  double* err = S ? S->valuePtr() : nullptr;
  std::vector<std::int64_t> fill(n);
  for (std::int64_t i = 0; i < n; ++i) fill[i] = start[i] + (old[i + 1] - old[i]);
  for (std::int64_t i = 0; i < n; ++i) {
    for (std::int64_t k = start[i]; k < start[i] + (old[i + 1] - old[i]); ++k) {
      if (!std::signbit(val[k])) continue;
      val[k] = -val[k];
      const Index j = col[k];
      const std::int64_t at = fill[j]++;
      col[at] = static_cast<Index>(i);
      val[at] = val[k];
      if (err) err[at] = err[k];
    }
  }
  for (std::int64_t i = 0; i < n; ++i)
    LAMBERT_CHECK(fill[i] == start[i + 1], "reciprocity: mirror count mismatch");
}

// Merges each row's two sorted runs (its own entries, then its created mirrors) in place,
// rows in parallel: the shorter mirror run is copied to a per-task buffer and the two are
// merged from the back. O(nnz) time, O(longest mirror run) memory per task.
void merge_runs(SparseF& F, SparseF* S, const std::vector<std::int64_t>& old,
                const std::vector<std::int64_t>& start, int threads) {
  Index* col = F.innerIndexPtr();
  double* val = F.valuePtr();
  double* err = S ? S->valuePtr() : nullptr;
  const auto n = static_cast<std::int64_t>(start.size()) - 1;
  parallel_for(n, 256, threads, [&](std::int64_t begin, std::int64_t end) {
    std::vector<Index> bc;
    std::vector<double> bv, be;
    for (std::int64_t i = begin; i < end; ++i) {
      const std::int64_t own_end = start[i] + (old[i + 1] - old[i]);
      const std::int64_t extra = start[i + 1] - own_end;
      if (extra == 0) continue;
      bc.assign(col + own_end, col + start[i + 1]);
      bv.assign(val + own_end, val + start[i + 1]);
      if (err) be.assign(err + own_end, err + start[i + 1]);
      std::int64_t p = own_end - 1, b = extra - 1, w = start[i + 1] - 1;
      while (b >= 0) {  // once the buffer is empty the rest of the own run is in place
        if (p >= start[i] && col[p] > bc[b]) {
          col[w] = col[p];
          val[w] = val[p];
          if (err) err[w] = err[p];
          --p;
        } else {
          col[w] = bc[b];
          val[w] = bv[b];
          if (err) err[w] = be[b];
          --b;
        }
        --w;
      }
    }
  });
}

// Σ_j H_ij d_j for every row (rows in parallel; each row summed in order: deterministic).
void weighted_row_sums(const SparseF& H, const std::vector<double>& d, const char* kept,
                       int threads, std::vector<double>& c, std::vector<double>& fixed) {
  const Index* outer = H.outerIndexPtr();
  const Index* col = H.innerIndexPtr();
  const double* val = H.valuePtr();
  parallel_for(H.rows(), 1024, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      double s = 0.0, f = 0.0;
      for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) {
        if (kept && (kept[i] || kept[col[k]]))
          f += val[k];
        else
          s += val[k] * d[col[k]];
      }
      c[i] = s;
      fixed[i] = f;
    }
  });
}

// The symmetric balancing of reciprocity.hpp: d with Σ_j d_i d_j H_ij + K_i = A_i t_i for
// the rows with a target, K_i the sum of the row's kept pairs (a pair with a `kept` patch is
// not scaled), w_i = A_i t_i - K_i, d_i clamped to [1/kMaxScale, kMaxScale].
// The sweep is the symmetric Sinkhorn-Knopp update (Knight 2008), over-relaxed, in log
// space: x = log d, x ← G(x) = x + ω log(w / (d ∘ H d)) on the rows with a target. Near the
// fixed point its error falls per sweep by 1 - ω (1 + λ) for each eigenvalue λ in [-1, 1] of
// the normalised H (0.84 for Knight's damped ω = 1/2 on the Cornell box, 119 sweeps to 1e-12;
// ω = 0.8: 70). The sweeps are Anderson-accelerated (Walker & Ni 2011, "Anderson
// acceleration for fixed-point iterations", type II, depth kAndersonDepth): with f_k =
// G(x_k) - x_k and the differences ΔF, ΔG of the last f and G values, x_{k+1} = G(x_k) -
// ΔG γ, γ minimising ||f_k - ΔF γ||_2 (a column-pivoted QR of the N x m ΔF; O(N m²) per
// sweep, against the sweep's O(nnz)). Should the residual grow, the history is dropped
// (a restart); after kAndersonRestarts of them the sweeps go on unaccelerated with ω = 1/2,
// the damped update that converges wherever a balance exists. Every step runs serially over
// the rows in index order or through weighted_row_sums: bitwise the same d for any thread
// count.
std::vector<double> balance(const SparseF& H, const Eigen::VectorXd& a,
                            const std::vector<double>& target, const char* kept, int threads,
                            int& iterations) {
  const auto n = static_cast<std::int64_t>(target.size());
  std::vector<double> d(n, 1.0), c(n, 0.0), fixed(n, 0.0);
  std::vector<char> active(n, 0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), f(n), g(n), last_f, last_g;
  Eigen::MatrixXd dF(n, kAndersonDepth), dG(n, kAndersonDepth);
  int history = 0, next = 0, restarts = 0;  // columns held, the next one to overwrite
  double omega = kBalanceOverRelaxation, last = std::numeric_limits<double>::infinity();
  bool accelerate = true;
  for (iterations = 0; iterations < kBalanceIterations; ++iterations) {
    weighted_row_sums(H, d, kept, threads, c, fixed);
    double worst = 0.0;
    for (std::int64_t i = 0; i < n; ++i) {
      const double want = a[i] * target[i] - fixed[i];
      active[i] = target[i] > 0.0 && c[i] > 0.0 && want > 0.0;
      if (active[i]) worst = std::max(worst, std::abs(d[i] * c[i] - want) / want);
    }
    if (worst <= kBalanceTolerance) break;
    if (worst > last) {  // restart: the history no longer describes the map near x
      history = next = 0;
      last_f.resize(0);
      if (++restarts > kAndersonRestarts) {
        accelerate = false;
        omega = 0.5;
      }
    }
    last = worst;
    for (std::int64_t i = 0; i < n; ++i) {
      f[i] = active[i] ? omega * std::log((a[i] * target[i] - fixed[i]) / (d[i] * c[i])) : 0.0;
      g[i] = x[i] + f[i];
    }
    Eigen::VectorXd x_next = g;
    if (accelerate) {
      if (last_f.size() == n) {
        dF.col(next) = f - last_f;
        dG.col(next) = g - last_g;
        next = (next + 1) % kAndersonDepth;
        history = std::min(history + 1, kAndersonDepth);
      }
      last_f = f;
      last_g = g;
      if (history > 0) {
        const Eigen::VectorXd gamma = dF.leftCols(history).colPivHouseholderQr().solve(f);
        if (gamma.allFinite()) x_next -= dG.leftCols(history) * gamma;
      }
    }
    for (std::int64_t i = 0; i < n; ++i) {
      if (!active[i]) continue;
      d[i] = std::clamp(std::exp(x_next[i]), 1.0 / kMaxScale, kMaxScale);
      x[i] = std::log(d[i]);
    }
  }
  return d;
}

}  // namespace

void average_reciprocal(SparseF& F, SparseF* stderr_F, const std::vector<double>& areas,
                        FormFactorStats& stats, int threads, const std::vector<char>* kept_pairs) {
  LAMBERT_CHECK(!kept_pairs || kept_pairs->empty() || kept_pairs->size() == areas.size(),
                "reciprocity: kept patches do not match the areas");
  const char* kept = kept_pairs && !kept_pairs->empty() ? kept_pairs->data() : nullptr;
  const auto n = static_cast<Eigen::Index>(areas.size());
  LAMBERT_CHECK(F.rows() == n && F.cols() == n, "reciprocity: F does not match the areas");
  F.makeCompressed();
  const Eigen::Map<const Eigen::VectorXd> a(areas.data(), n);
  const bool with_err = stderr_F && stderr_F->nonZeros() == F.nonZeros() && F.nonZeros() > 0;
  SparseF* S = with_err ? stderr_F : nullptr;
  if (S) {
    S->makeCompressed();
    LAMBERT_CHECK(std::equal(F.outerIndexPtr(), F.outerIndexPtr() + n + 1, S->outerIndexPtr()) &&
                      std::equal(F.innerIndexPtr(), F.innerIndexPtr() + F.nonZeros(),
                                 S->innerIndexPtr()),
                  "reciprocity: stderr pattern differs from F");
  }
  // The targets: each row's own sum before averaging, at most 1.
  std::vector<double> target(n, 0.0);
  std::vector<std::int64_t> old(F.outerIndexPtr(), F.outerIndexPtr() + n + 1);
  parallel_for(n, 1024, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      double s = 0.0;
      for (std::int64_t k = old[i]; k < old[i + 1]; ++k) s += F.valuePtr()[k];
      target[i] = std::min(s, 1.0);
    }
  });

  // 1. Average in F's own layout; row i of the union gains the entries of column i whose
  // mirror is missing: (entries in column i) - (entries of row i with a mirror).
  std::vector<RowChange> change(n);
  average_pairs(F, S, a, threads, change);
  std::vector<std::int64_t> start(n + 1, 0);
  for (std::int64_t k = 0; k < F.nonZeros(); ++k) ++start[F.innerIndexPtr()[k] + 1];
  double changed = 0.0, total = 0.0, max_rel = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    start[i + 1] += start[i] - change[i].matched + (old[i + 1] - old[i]);
    changed += change[i].changed;
    total += change[i].total;
    max_rel = std::max(max_rel, change[i].max_rel);
  }
  stats.reciprocity_max_relative_change = max_rel;
  stats.reciprocity_mean_relative_change = total > 0.0 ? changed / total : 0.0;
  std::vector<RowChange>().swap(change);

  // The union's storage: within the allocation resizeNonZeros only moves the end (no copy,
  // pointers kept; callers that reserved room, like gather, take this path). Otherwise it
  // reallocates once, copying: the old and the new storage coexist for that moment.
  const std::int64_t union_nnz = start[n];
  F.resizeNonZeros(union_nnz);
  if (S) S->resizeNonZeros(union_nnz);
  spread_rows(F, S, old, start);
  append_mirrors(F, S, old, start);
  merge_runs(F, S, old, start, threads);
  std::copy(start.begin(), start.end(), F.outerIndexPtr());
  if (S) {
    std::copy(start.begin(), start.end(), S->outerIndexPtr());
    std::copy(F.innerIndexPtr(), F.innerIndexPtr() + union_nnz, S->innerIndexPtr());
  }
  std::vector<std::int64_t>().swap(old);

  const Index* outer = F.outerIndexPtr();
  const Index* col = F.innerIndexPtr();
  double* val = F.valuePtr();
  double* err = S ? S->valuePtr() : nullptr;

  // 2. Balance: G_ij ← d_i d_j G_ij (symmetric, so still reciprocal).
  int iterations = 0;
  const std::vector<double> d = balance(F, a, target, kept, threads, iterations);
  stats.reciprocity_balance_iterations = iterations;
  auto pair_scale = [&](Eigen::Index i, Index j) {
    return kept && (kept[i] || kept[j]) ? 1.0 : d[i] * d[j];
  };
  // 3. The cap: rows still above 1 after balancing (it stopped short, or a row without a
  // target). Each row's balanced sum is taken first (rows in parallel, each summed in order),
  // then pairs are scaled by d_i d_j min(s_i, s_j) and divided by A_i in one pass.
  std::vector<double> scale(n, 1.0), row_max(n, 0.0);
  parallel_for(n, 1024, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      double sum = 0.0;
      for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) sum += val[k] * pair_scale(i, col[k]);
      sum /= a[i];
      row_max[i] = sum;
      if (sum > 1.0 + kRowSumSlack) scale[i] = 1.0 / sum;
    }
  });
  stats.reciprocity_max_row_sum = 0.0;
  stats.reciprocity_rows_scaled = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    stats.reciprocity_max_row_sum = std::max(stats.reciprocity_max_row_sum, row_max[i]);
    if (scale[i] < 1.0) ++stats.reciprocity_rows_scaled;
  }

  // The per-row range of the factors d_i d_j min(s_i, s_j) (kept per row, reduced after: the
  // same for any thread count).
  std::vector<double> row_lo(n, std::numeric_limits<double>::infinity()), row_hi(n, 0.0);
  parallel_for(n, 1024, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
      for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) {
        const Index j = col[k];
        const double balance_factor = pair_scale(i, j);
        const double s = std::min(scale[i], scale[j]);
        lo = std::min(lo, balance_factor * s);
        hi = std::max(hi, balance_factor * s);
        val[k] *= balance_factor;
        val[k] *= s;
        val[k] /= a[i];
        if (err) {
          err[k] *= balance_factor;
          err[k] *= s / a[i];
        }
      }
      row_lo[i] = lo;
      row_hi[i] = hi;
    }
  });
  const double lo = n > 0 ? *std::min_element(row_lo.begin(), row_lo.end()) : 1.0;
  const double hi = n > 0 ? *std::max_element(row_hi.begin(), row_hi.end()) : 1.0;
  stats.reciprocity_scale_min = F.nonZeros() > 0 ? lo : 1.0;
  stats.reciprocity_scale_max = F.nonZeros() > 0 ? hi : 1.0;
}

}  // namespace lambert::ff
