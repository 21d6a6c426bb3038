// Reciprocity averaging: see reciprocity.hpp for the equations, the balancing and the
// row-sum cap.

#include "geometry/formfactors/reciprocity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace lambert::ff {
namespace {

using Index = SparseF::StorageIndex;

// (diag(a) M + (diag(a) M)^T) / 2 with M = F, or for standard errors the root of
// ((diag(a) S)² + ((diag(a) S)^T)²) / 4; both have the union of M's and M^T's patterns.
SparseF average_G(const SparseF& M, const Eigen::VectorXd& a, bool squares) {
  SparseF G = a.asDiagonal() * M;
  if (squares) G = G.unaryExpr([](double v) { return v * v; });  // same pattern
  const SparseF Gt = G.transpose();
  SparseF H = (G + Gt) * (squares ? 0.25 : 0.5);
  if (squares)
    for (std::int64_t k = 0; k < H.nonZeros(); ++k) H.valuePtr()[k] = std::sqrt(H.valuePtr()[k]);
  H.makeCompressed();
  return H;
}

// Σ_j H_ij d_j for every row (rows in parallel; each row summed in order: deterministic).
void weighted_row_sums(const SparseF& H, const std::vector<double>& d, int threads,
                       std::vector<double>& c) {
  const Index* outer = H.outerIndexPtr();
  const Index* col = H.innerIndexPtr();
  const double* val = H.valuePtr();
  parallel_for(H.rows(), 1024, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      double s = 0.0;
      for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) s += val[k] * d[col[k]];
      c[i] = s;
    }
  });
}

// The symmetric balancing of reciprocity.hpp: d with Σ_j d_i d_j H_ij = A_i t_i for the rows
// with a target, by the damped symmetric Sinkhorn-Knopp update (Knight 2008)
// d_i ← sqrt(d_i A_i t_i / Σ_j H_ij d_j), d_i clamped to [1/kMaxScale, kMaxScale].
std::vector<double> balance(const SparseF& H, const Eigen::VectorXd& a,
                            const std::vector<double>& target, int threads,
                            int& iterations) {
  const auto n = static_cast<std::int64_t>(target.size());
  std::vector<double> d(n, 1.0), c(n, 0.0);
  for (iterations = 0; iterations < kBalanceIterations; ++iterations) {
    weighted_row_sums(H, d, threads, c);
    double worst = 0.0;
    for (std::int64_t i = 0; i < n; ++i) {
      if (target[i] <= 0.0 || c[i] <= 0.0) continue;
      const double want = a[i] * target[i], have = d[i] * c[i];
      worst = std::max(worst, std::abs(have - want) / want);
    }
    if (worst <= kBalanceTolerance) break;
    for (std::int64_t i = 0; i < n; ++i) {
      if (target[i] <= 0.0 || c[i] <= 0.0) continue;
      d[i] = std::clamp(std::sqrt(d[i] * a[i] * target[i] / c[i]), 1.0 / kMaxScale, kMaxScale);
    }
  }
  return d;
}

}  // namespace

void average_reciprocal(SparseF& F, SparseF* stderr_F, const std::vector<double>& areas,
                        FormFactorStats& stats, int threads) {
  const auto n = static_cast<Eigen::Index>(areas.size());
  LAMBERT_CHECK(F.rows() == n && F.cols() == n, "reciprocity: F does not match the areas");
  F.makeCompressed();
  const Eigen::Map<const Eigen::VectorXd> a(areas.data(), n);
  const Index* fo = F.outerIndexPtr();
  const Index* fc = F.innerIndexPtr();
  const double* fv = F.valuePtr();
  // The targets: each row's own sum before averaging, at most 1.
  std::vector<double> target(n, 0.0);
  for (Eigen::Index i = 0; i < n; ++i) {
    double s = 0.0;
    for (std::int64_t k = fo[i]; k < fo[i + 1]; ++k) s += fv[k];
    target[i] = std::min(s, 1.0);
  }
  SparseF H = average_G(F, a, false);
  const bool with_err = stderr_F && stderr_F->nonZeros() == F.nonZeros() && F.nonZeros() > 0;
  SparseF E;
  if (with_err) {
    stderr_F->makeCompressed();
    E = average_G(*stderr_F, a, true);
    LAMBERT_CHECK(E.nonZeros() == H.nonZeros(), "reciprocity: stderr pattern differs from F");
  }
  const Index* outer = H.outerIndexPtr();
  const Index* col = H.innerIndexPtr();
  double* val = H.valuePtr();

  // Balance: H_ij ← d_i d_j H_ij (symmetric, so still reciprocal).
  int iterations = 0;
  const std::vector<double> d = balance(H, a, target, threads, iterations);
  stats.reciprocity_balance_iterations = iterations;
  for (Eigen::Index i = 0; i < n; ++i)
    for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) {
      const double s = d[i] * d[col[k]];
      val[k] *= s;
      if (with_err) E.valuePtr()[k] *= s;
    }

  // The cap: rows still above 1 (balancing stopped short, or a row without a target).
  std::vector<double> scale(n, 1.0);
  stats.reciprocity_max_row_sum = 0.0;
  stats.reciprocity_rows_scaled = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    double sum = 0.0;
    for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) sum += val[k];
    sum /= a[i];
    stats.reciprocity_max_row_sum = std::max(stats.reciprocity_max_row_sum, sum);
    if (sum > 1.0 + kRowSumSlack) {
      scale[i] = 1.0 / sum;
      ++stats.reciprocity_rows_scaled;
    }
  }

  // Scale pairs by min(s_i, s_j), compare with the old G (a merged sweep of the sorted rows
  // of H and F: F's pattern is a subset of H's), and divide by A_i.
  double changed = 0.0, total = 0.0, max_rel = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    std::int64_t f = fo[i];
    for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) {
      const Index j = col[k];
      const double s = std::min(scale[i], scale[j]);
      val[k] *= s;
      double old_g = 0.0;
      while (f < fo[i + 1] && fc[f] < j) ++f;
      if (f < fo[i + 1] && fc[f] == j) old_g = a[i] * fv[f];
      changed += std::abs(val[k] - old_g);
      total += old_g;
      if (old_g > 0.0) max_rel = std::max(max_rel, std::abs(val[k] - old_g) / old_g);
      val[k] /= a[i];
      if (with_err) E.valuePtr()[k] *= s / a[i];
    }
  }
  stats.reciprocity_max_relative_change = max_rel;
  stats.reciprocity_mean_relative_change = total > 0.0 ? changed / total : 0.0;
  F.swap(H);  // swap: Eigen 3.4 sparse matrices have no move (std::move copies)
  if (with_err) stderr_F->swap(E);
}

}  // namespace lambert::ff
