// direct: the reference solve of K B = E by LU factorisation of the assembled K (one
// channel at a time, so at most one copy of F's pattern besides F itself).
// Eigen SparseLU with COLAMD ordering; when F is more than kDenseFraction full (a closed
// scene with full visibility is nearly dense) a dense partial-pivoting LU is used instead,
// which is much faster than SparseLU on a dense pattern: O(N^3) time, 8 N^2 bytes.
// K is strictly row diagonally dominant (row sums of rho F are < 1), so LU without or with
// partial pivoting is stable. The true relative residual is checked; above tol the status is
// numerical-issue. Iterations: 1; matvecs: 1 (the residual check).

#include <Eigen/LU>
#include <Eigen/SparseLU>

#include "solvers/system.hpp"

namespace lambert {
namespace {
// Density above which dense LU beats SparseLU (fill-in makes the factors dense anyway).
constexpr double kDenseFraction = 0.1;
}  // namespace

ChannelReport solve_direct(const ChannelSystem& system, const SolveOptions& options,
                           Eigen::VectorXd& B) {
  ChannelReport report;
  record(report, 0, system.relative_residual_uncounted(system.E), 0.0);
  const Timer timer;
  const double n = static_cast<double>(system.size());
  const SparseRowMatrix k = assemble_k(system);
  bool ok = true;
  if (static_cast<double>(system.F->nonZeros()) > kDenseFraction * n * n) {
    const Eigen::MatrixXd dense(k);
    B = dense.partialPivLu().solve(system.E);
    report.note = "dense LU (F is over 10% full)";
  } else {
    const Eigen::SparseMatrix<double, Eigen::ColMajor, int> kc = k;
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
