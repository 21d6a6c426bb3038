// average_reciprocal (geometry/formfactors/reciprocity.hpp) against a dense reference that
// follows the header's three steps literally, and its in-place memory behaviour.

#include "geometry/formfactors/reciprocity.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "geometry/formfactors/mirror.hpp"

namespace lambert {
namespace {

TEST(MirrorCursor, FindsWhatABinarySearchFindsWhateverTheCursorHeld) {
  // A random CSR pattern (rows of 0-60 sorted distinct columns of 200), long rows beyond the
  // cursor's linear steps included. The cursor is exact for rows visited in increasing
  // order, after a pass that visited them in another order (stale cursors of an earlier
  // call), and in a new call whose rows skip about (a thread's chunks).
  const int n = 200;
  std::mt19937 rng(7);
  std::vector<int> outer{0}, col;
  for (int r = 0; r < n; ++r) {
    std::vector<int> row;
    const int len = static_cast<int>(rng() % 61);
    for (int k = 0; k < len; ++k) row.push_back(static_cast<int>(rng() % n));
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    col.insert(col.end(), row.begin(), row.end());
    outer.push_back(static_cast<int>(col.size()));
  }
  const auto expected = [&](int j, int i) -> std::int64_t {
    const int* p = std::lower_bound(col.data() + outer[j], col.data() + outer[j + 1], i);
    return p != col.data() + outer[j + 1] && *p == i ? p - col.data() : -1;
  };
  ff::MirrorCursor mirror;
  mirror.rows(n);
  std::vector<int> order(n);
  for (int k = 0; k < n; ++k) order[k] = n - 1 - k;  // decreasing: not the cursor's order
  std::uint64_t call = ff::MirrorCursor::next_call();
  for (const int i : order)
    for (int j = 0; j < n; ++j) mirror.find(col.data(), outer.data(), j, i, call);
  std::int64_t found = 0;
  for (int pass = 0; pass < 2; ++pass) {
    call = ff::MirrorCursor::next_call();
    for (int i = pass; i < n; i += 1 + pass * static_cast<int>(rng() % 5))
      for (int k = outer[i]; k < outer[i + 1]; ++k) {
        const int j = col[k];
        const std::int64_t q = mirror.find(col.data(), outer.data(), j, i, call);
        ASSERT_EQ(q, expected(j, i)) << "row " << j << " column " << i;
        found += q >= 0;
      }
  }
  EXPECT_GT(found, 100);  // the pattern has mirrors to find, not only misses
}

using Dense = Eigen::MatrixXd;

struct Reference {
  Dense F, S;  // the averaged, balanced, capped F and its standard errors
  double mean_change = 0.0, max_change = 0.0, scale_min = 0.0, scale_max = 0.0;
  std::int64_t rows_scaled = 0;
  int sweeps = 0;  // the damped balance's sweeps to its fixed point
};

// reciprocity.hpp step by step on dense matrices: G = (A F + (A F)^T) / 2, the symmetric
// Sinkhorn-Knopp balancing with the same constants (over-relaxed, falling back to the damped
// update should the residual grow), the cap by min(s_i, s_j).
// Sums run over j in increasing order like the CSR rows (absent entries add an exact 0).
Reference dense_reference(const Dense& F0, const Dense& S0, const std::vector<double>& a) {
  const auto n = F0.rows();
  Reference r;
  Dense G(n, n), E(n, n);
  std::vector<double> target(n);
  double changed = 0.0, total = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    target[i] = std::min(F0.row(i).sum(), 1.0);
    for (Eigen::Index j = 0; j < n; ++j) {
      const double gij = a[i] * F0(i, j), gji = a[j] * F0(j, i);
      G(i, j) = (gij + gji) / 2;
      const double si = a[i] * S0(i, j), sj = a[j] * S0(j, i);
      E(i, j) = std::sqrt(si * si + sj * sj) / 2;
      changed += std::abs(G(i, j) - gij);
      total += gij;
      if (gij > 0.0) r.max_change = std::max(r.max_change, std::abs(G(i, j) - gij) / gij);
    }
  }
  r.mean_change = changed / total;
  // The balance itself, not the implementation's schedule: Knight's damped update
  // d_i ← d_i (A_i t_i / (d_i Σ_j G_ij d_j))^(1/2), clamped to [1/kMaxScale, kMaxScale],
  // run to its fixed point (no d moving by more than 1e-15 relative). Where a clamp holds
  // (the random pattern's), its rows keep a residual and the others balance around them.
  std::vector<double> d(n, 1.0), c(n);
  for (r.sweeps = 0; r.sweeps < 2000; ++r.sweeps) {
    for (Eigen::Index i = 0; i < n; ++i) {
      c[i] = 0.0;
      for (Eigen::Index j = 0; j < n; ++j)
        if (G(i, j) != 0.0) c[i] += G(i, j) * d[j];
    }
    double moved = 0.0;
    for (Eigen::Index i = 0; i < n; ++i)
      if (target[i] > 0.0 && c[i] > 0.0) {
        const double next = std::clamp(d[i] * std::sqrt(a[i] * target[i] / (d[i] * c[i])),
                                       1.0 / ff::kMaxScale, ff::kMaxScale);
        moved = std::max(moved, std::abs(next - d[i]) / d[i]);
        d[i] = next;
      }
    if (moved <= 1e-15) break;
  }
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      G(i, j) *= d[i] * d[j];
      E(i, j) *= d[i] * d[j];
    }
  std::vector<double> s(n, 1.0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double sum = G.row(i).sum() / a[i];
    if (sum > 1.0 + ff::kRowSumSlack) {
      s[i] = 1.0 / sum;
      ++r.rows_scaled;
    }
  }
  r.F = r.S = Dense::Zero(n, n);
  r.scale_min = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      if (G(i, j) == 0.0) continue;
      const double m = std::min(s[i], s[j]);
      r.scale_min = std::min(r.scale_min, d[i] * d[j] * m);
      r.scale_max = std::max(r.scale_max, d[i] * d[j] * m);
      r.F(i, j) = G(i, j) * m / a[i];
      r.S(i, j) = E(i, j) * m / a[i];
    }
  return r;
}

SparseF sparse(const Dense& D) {
  SparseF M = D.sparseView();
  M.makeCompressed();
  return M;
}

// Six patches: (0,1) and (1,3) stored both ways; (0,2), (2,3), (1,4) one way in the upper
// triangle, (3,0) and (2,1) in the lower; row 4 is empty but its created mirror
// F_41 = A_1 F_14 / 2 / A_4 = 3 exceeds 1 and has no target, so the cap acts; patch 5 sees
// nothing and is seen by nobody.
void mixed(Dense& F, Dense& S, std::vector<double>& a) {
  a = {1.0, 2.0, 0.5, 1.5, 0.1, 1.0};
  F = S = Dense::Zero(6, 6);
  const int ij[][2] = {{0, 1}, {1, 0}, {1, 3}, {3, 1}, {0, 2}, {2, 3}, {1, 4}, {3, 0}, {2, 1}};
  const double f[] = {0.3, 0.12, 0.1, 0.2, 0.2, 0.4, 0.3, 0.25, 0.3};
  for (int k = 0; k < 9; ++k) {
    F(ij[k][0], ij[k][1]) = f[k];
    S(ij[k][0], ij[k][1]) = 0.01 * (k + 1);
  }
}

// Entry by entry against the reference. Averaging and the cap are the same operations on the
// same numbers (equal to rounding); the balance is stopped once every row is within
// kBalanceTolerance (1e-12) of its target, and on these patterns (the reference's damped
// sweeps converge at a rate below 0.9, so the linearised map's gap 1 + λ_min is above 0.2) a
// row residual r moves the factors by at most ~r / 0.2: kBalanced = 10 kBalanceTolerance
// relative (measured: 2e-14).
constexpr double kBalanced = 10 * ff::kBalanceTolerance;
// A damped rate below 0.9 moves d by less than 1e-15 from a first step below 1 within
// log(1e-15) / log(0.9) = 328 sweeps: the tests check the premise through the sweep count.
constexpr int kGapSweeps = 328;
void expect_matches(const SparseF& F, const SparseF& S, const Reference& r) {
  const Dense Fd(F), Sd(S);
  EXPECT_EQ(F.nonZeros(), (r.F.array() != 0.0).count());
  ASSERT_EQ(S.nonZeros(), F.nonZeros());
  for (Eigen::Index i = 0; i < Fd.rows(); ++i)
    for (Eigen::Index j = 0; j < Fd.cols(); ++j) {
      EXPECT_NEAR(Fd(i, j), r.F(i, j), kBalanced * r.F(i, j)) << i << "," << j;
      EXPECT_NEAR(Sd(i, j), r.S(i, j), kBalanced * r.S(i, j)) << i << "," << j;
    }
  for (Eigen::Index k = 0; k < F.nonZeros(); ++k)
    EXPECT_EQ(F.innerIndexPtr()[k], S.innerIndexPtr()[k]);
}

}  // namespace

TEST(Reciprocity, MixedPatternMatchesTheDenseReference) {
  Dense F0, S0;
  std::vector<double> a;
  mixed(F0, S0, a);
  const Reference r = dense_reference(F0, S0, a);
  SparseF F = sparse(F0), S = sparse(S0);
  FormFactorStats stats;
  ff::average_reciprocal(F, &S, a, stats);
  expect_matches(F, S, r);
  EXPECT_LT(r.sweeps, kGapSweeps);
  EXPECT_GT(r.rows_scaled, 0);  // the pattern exercises the cap
  EXPECT_EQ(stats.reciprocity_rows_scaled, r.rows_scaled);
  EXPECT_NEAR(stats.reciprocity_mean_relative_change, r.mean_change, 1e-14);
  EXPECT_NEAR(stats.reciprocity_max_relative_change, r.max_change, 1e-14);
  EXPECT_NEAR(stats.reciprocity_scale_min, r.scale_min, kBalanced * r.scale_min);
  EXPECT_NEAR(stats.reciprocity_scale_max, r.scale_max, kBalanced * r.scale_max);
  EXPECT_EQ(F.outerIndexPtr()[6], F.outerIndexPtr()[5]);  // row 5 stays empty
}

TEST(Reciprocity, RandomPatternMatchesTheReferenceForAnyThreadCount) {
  // 300 patches, each entry present with probability 0.05 independently of its mirror (so
  // most pairs are one-way, in both triangles), values and areas random.
  constexpr int n = 300;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> a(n);
  for (double& x : a) x = 0.2 + u(rng);
  Dense F0 = Dense::Zero(n, n), S0 = Dense::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (i != j && u(rng) < 0.05) {
        F0(i, j) = 0.04 * u(rng) + 1e-6;
        S0(i, j) = 0.01 * u(rng) + 1e-6;
      }
  const Reference r = dense_reference(F0, S0, a);
  EXPECT_LT(r.sweeps, kGapSweeps);
  SparseF ref_F, ref_S;
  for (int threads : {1, 2, 5}) {
    SparseF F = sparse(F0), S = sparse(S0);
    FormFactorStats stats;
    ff::average_reciprocal(F, &S, a, stats, threads);
    expect_matches(F, S, r);
    if (threads == 1) {
      ref_F = F;
      ref_S = S;
      continue;
    }
    ASSERT_EQ(F.nonZeros(), ref_F.nonZeros());
    for (Eigen::Index k = 0; k < F.nonZeros(); ++k) {
      EXPECT_EQ(F.valuePtr()[k], ref_F.valuePtr()[k]);
      EXPECT_EQ(S.valuePtr()[k], ref_S.valuePtr()[k]);
      EXPECT_EQ(F.innerIndexPtr()[k], ref_F.innerIndexPtr()[k]);
    }
  }
}

TEST(Reciprocity, RoomForTheUnionMeansNoReallocation) {
  // With storage reserved for the union (as gather does) the result is built in F's own
  // arrays: the pointers stay, and the values equal those of the reallocating path.
  Dense F0, S0;
  std::vector<double> a;
  mixed(F0, S0, a);
  SparseF F = sparse(F0), S = sparse(S0), G = sparse(F0), T = sparse(S0);
  F.reserve(F.nonZeros());  // room for 2 nnz, an upper bound on the union
  S.reserve(S.nonZeros());
  const double* fv = F.valuePtr();
  const auto* fi = F.innerIndexPtr();
  const double* sv = S.valuePtr();
  FormFactorStats stats, stats_g;
  ff::average_reciprocal(F, &S, a, stats);
  ff::average_reciprocal(G, &T, a, stats_g);
  EXPECT_EQ(F.valuePtr(), fv);
  EXPECT_EQ(F.innerIndexPtr(), fi);
  EXPECT_EQ(S.valuePtr(), sv);
  EXPECT_NE(G.valuePtr(), nullptr);
  ASSERT_EQ(F.nonZeros(), G.nonZeros());
  for (Eigen::Index k = 0; k < F.nonZeros(); ++k) {
    EXPECT_EQ(F.valuePtr()[k], G.valuePtr()[k]);
    EXPECT_EQ(S.valuePtr()[k], T.valuePtr()[k]);
  }
}

TEST(Reciprocity, WithoutErrorsAndEmpty) {
  Dense F0, S0;
  std::vector<double> a;
  mixed(F0, S0, a);
  const Reference r = dense_reference(F0, S0, a);
  SparseF F = sparse(F0);
  FormFactorStats stats;
  ff::average_reciprocal(F, nullptr, a, stats);
  const Dense Fd(F);
  for (Eigen::Index i = 0; i < 6; ++i)
    for (Eigen::Index j = 0; j < 6; ++j) EXPECT_NEAR(Fd(i, j), r.F(i, j), kBalanced * r.F(i, j));
  SparseF empty(3, 3);
  FormFactorStats es;
  ff::average_reciprocal(empty, nullptr, {1.0, 1.0, 1.0}, es);
  EXPECT_EQ(empty.nonZeros(), 0);
  EXPECT_EQ(es.reciprocity_scale_min, 1.0);
}

}  // namespace lambert
