// direct: the reference solve of K B = E by LU factorisation of the assembled K (one
// channel at a time, so at most one copy of F's pattern besides F itself).
// Eigen SparseLU with COLAMD ordering; when F is more than kDenseFraction full (a closed
// scene with full visibility is nearly dense) a dense partial-pivoting LU is used instead,
// which is much faster than SparseLU on a dense pattern: O(N^3) time, 8 N^2 bytes (factorised
// in place: no second copy).
// K is strictly row diagonally dominant (row sums of rho F are < 1; extended form factors
// may break this, where partial pivoting keeps the factorisation stable), so LU without or
// with partial pivoting is stable. The true relative residual is checked; above tol the status is
// numerical-issue. Iterations: 1; matvecs: 1 (the residual check).
//
// Memory (direct_memory_bytes, checked by solve_radiosity against SolveOptions::memory_limit
// before any work): K itself, (8 + index) bytes per entry for nnz(F) + N entries, plus
//   dense:  8 N^2 for the matrix factorised in place (and 4 N for the pivots);
//   sparse: the column-major copy SparseLU takes (12 bytes per entry) plus the factors,
//           estimated at kSparseFill entries of L + U per entry of K (12 bytes each: value
//           and row index), capped at the N^2 entries of dense factors. This is an estimate:
//           COLAMD fill depends on the pattern; the fill factor 10 is what the sparse path
//           (at most 10% full) can reach before its factors are as large as dense ones, so
//           the estimate errs towards refusing only jobs that would be near-dense anyway.

#include <Eigen/LU>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cstdio>

#include "core/memory.hpp"
#include "solvers/system.hpp"

namespace lambert {
namespace {
// Density above which dense LU beats SparseLU (fill-in makes the factors dense anyway).
constexpr double kDenseFraction = 0.1;
// Entries of L + U per entry of K assumed for SparseLU (see above).
constexpr double kSparseFill = 10.0;

bool dense_path(double n, double nnz) { return nnz > kDenseFraction * n * n; }

double k_bytes(double n, double nnz) {
  constexpr double kIndex = sizeof(SparseRowMatrix::StorageIndex);
  return (8.0 + kIndex) * (nnz + n) + kIndex * (n + 1.0);
}
}  // namespace

double direct_memory_bytes(std::int32_t patches, std::int64_t nonzeros) {
  const double n = patches, nnz = static_cast<double>(nonzeros);
  if (dense_path(n, nnz)) return k_bytes(n, nnz) + 8.0 * n * n + 4.0 * n;
  const double k_entries = nnz + n;
  return k_bytes(n, nnz) + 12.0 * k_entries + 12.0 * std::min(n * n, kSparseFill * k_entries);
}

std::string direct_refusal(std::int32_t n, std::int64_t nnz, double limit,
                           const std::string& source) {
  const double need = direct_memory_bytes(n, nnz);
  if (!(limit > 0.0) || need <= limit) return "";
  const bool dense = dense_path(n, static_cast<double>(nnz));
  return std::string("direct: a ") + (dense ? "dense" : "sparse") + " LU of " +
         std::to_string(n) + " patches needs " + (dense ? "" : "about ") + format_bytes(need) +
         ", above the " + format_bytes(limit) + " this job may use" +
         (source.empty() ? "" : " (" + source + ")") +
         ": raise it with --max-memory or LAMBERT_MAX_MEMORY, or choose an iterative solver";
}

ChannelReport solve_direct(const ChannelSystem& system, const SolveOptions& options,
                           Eigen::VectorXd& B) {
  ChannelReport report;
  record(report, 0, system.relative_residual_uncounted(system.E), 0.0);
  const Timer timer;
  const double n = static_cast<double>(system.size());
  bool ok = true;
  if (dense_path(n, static_cast<double>(system.F->entries()))) {
    Eigen::MatrixXd dense;
    {
      const SparseRowMatrix k = assemble_k(system, "direct");
      dense = k;  // K is released before the factorisation
    }
    const Eigen::PartialPivLU<Eigen::Ref<Eigen::MatrixXd>> lu(dense);  // in place
    B = lu.solve(system.E);
    report.note = "dense LU (F is over 10% full)";
  } else {
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> kc;
    kc = assemble_k(system, "direct");
    Eigen::SparseLU<Eigen::SparseMatrix<double, Eigen::ColMajor, int>, Eigen::COLAMDOrdering<int>>
        lu;
    lu.compute(kc);
    ok = lu.info() == Eigen::Success;
    if (ok)
      B = lu.solve(system.E);
    else
      B = system.E;
    if (!ok) report.note = "SparseLU failed: " + lu.lastErrorMessage();
  }
  report.iterations = 1;
  report.residual = system.relative_residual(B);
  report.status =
      ok && report.residual <= options.tol ? SolveStatus::Converged : SolveStatus::NumericalIssue;
  report.seconds = timer.seconds();
  record(report, 1, report.residual, report.seconds);
  return report;
}

}  // namespace lambert
