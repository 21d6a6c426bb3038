// Stationary iterations on K B = E, K = I - diag(rho) F, d_i = K_ii = 1 - rho_i F_ii.
//
// Jacobi:        B_i <- B_i + r_i / d_i with r = E - K B from the previous iterate.
// Gauss-Seidel:  the gathering sweep, in place: for i = 0..N-1,
//                g_i = (E_i + rho_i sum_{j != i} F_ij B_j) / d_i  (newest B_j),  B_i <- g_i.
// SOR:           B_i <- (1 - omega) B_i + omega g_i, omega in (0, 2).
// Convergence: since ||diag(rho) F||_inf <= rho_max < 1 (row sums of F are <= 1), all three
// converge for omega in (0, 1]; for omega > 1 SOR converges on the symmetrisable radiosity
// systems (K is similar to an SPD matrix, Ostrowski-Reich). Extended form factors (mirrors,
// glass) have rows above 1; there the spectral radius of diag(rho) F stays below 1 because
// light is absorbed (a scene that absorbs nothing is refused at load), not the row sums. Cost per iteration: one pass
// over F, O(nnz). Initial guess B = E (or SolveOptions::initial_guess).
//
// Stopping rule (the one rule): ||E - K B||_2 / ||E||_2 <= tol on the true residual.
// Jacobi gets the true residual of the current iterate for free (it is the update).
// Gauss-Seidel/SOR accumulate the "sweep residual" sum_i (d_i (g_i - B_i_old))^2, row i's
// residual at the moment it is updated; the history records it. When it reaches tol the
// true residual of the iterate is computed (one extra product) and decides.
// Thread safety: sequential sweeps (Jacobi's product may use options.threads). Rows come
// from the transport operator (one call per row, the entries looped over in place).

#include <algorithm>
#include <cmath>

#include "solvers/system.hpp"

namespace lambert {

ChannelReport solve_jacobi(const ChannelSystem& system, const SolveOptions& options,
                           Eigen::VectorXd& B) {
  ChannelReport report;
  const Timer timer;
  const Eigen::VectorXd d = 1.0 - system.rho.cwiseProduct(system.f_diag).array();
  B = system.guess;
  Eigen::VectorXd kb;
  for (int k = 0;; ++k) {
    system.apply_k(B, kb);
    const double res = (system.E - kb).norm() / system.e_norm;
    record(report, k, res, timer.seconds());
    report.iterations = k;
    report.residual = res;
    if (!std::isfinite(res)) {
      report.status = SolveStatus::NumericalIssue;
      break;
    }
    if (res <= options.tol) {
      report.status = SolveStatus::Converged;
      break;
    }
    if (k == options.max_iterations) {
      report.status = SolveStatus::MaxIterations;
      break;
    }
    B += (system.E - kb).cwiseQuotient(d);
  }
  report.seconds = timer.seconds();
  return report;
}

namespace {

// One in-place SOR sweep (omega = 1: Gauss-Seidel); returns the sweep residual norm.
double sor_sweep(const ChannelSystem& s, double omega, Eigen::VectorXd& B) {
  double sq = 0.0;
  for (std::int32_t i = 0; i < s.size(); ++i) {
    const TransportOperator::RowSpan row = s.F->row(i);
    double gather = 0.0;
    for (std::int64_t k = 0; k < row.count; ++k) gather += row.values[k] * B[row.cols[k]];
    const double d = 1.0 - s.rho[i] * s.f_diag[i];
    const double r = s.E[i] + s.rho[i] * gather - B[i];  // row i of E - K B, newest values
    sq += r * r;
    B[i] += omega * r / d;
  }
  ++s.matvecs;
  return std::sqrt(sq);
}

ChannelReport sor_iterate(const ChannelSystem& system, const SolveOptions& options, double omega,
                          Eigen::VectorXd& B) {
  ChannelReport report;
  B = system.guess;
  record(report, 0, system.relative_residual_uncounted(B), 0.0);
  const Timer timer;
  double check_below = options.tol;  // sweep residual that triggers a true-residual check
  report.status = SolveStatus::MaxIterations;
  for (int k = 1; k <= options.max_iterations; ++k) {
    const double sweep = sor_sweep(system, omega, B) / system.e_norm;
    report.iterations = k;
    report.residual = sweep;
    if (!std::isfinite(sweep)) {
      report.status = SolveStatus::NumericalIssue;
      record(report, k, sweep, timer.seconds());
      break;
    }
    if (sweep <= check_below || k == options.max_iterations) {
      const double truth = system.relative_residual(B);
      report.residual = truth;
      record(report, k, truth, timer.seconds());
      if (truth <= options.tol) {
        report.status = SolveStatus::Converged;
        break;
      }
      // Expect the true residual to fall in proportion to the sweep residual.
      check_below = sweep * options.tol / truth;
    } else {
      record(report, k, sweep, timer.seconds());
    }
  }
  report.seconds = timer.seconds();
  return report;
}

}  // namespace

ChannelReport solve_gauss_seidel(const ChannelSystem& system, const SolveOptions& options,
                                 Eigen::VectorXd& B) {
  return sor_iterate(system, options, 1.0, B);
}

ChannelReport solve_sor(const ChannelSystem& system, const SolveOptions& options,
                        Eigen::VectorXd& B) {
  return sor_iterate(system, options, options.omega, B);
}

}  // namespace lambert
