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

#include "core/error.hpp"
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

// One in-place SOR sweep (omega = 1: Gauss-Seidel) of C channels over F's rows together:
// each row is read once and gathered into C sums, each summed in storage order exactly as
// a one-channel sweep sums it (so every channel is bitwise what it is alone). sq[c]
// receives channel c's squared sweep residual.
template <int C>
void sor_sweep(const ChannelSystem* const* s, double omega, Eigen::VectorXd* const* B, double* sq) {
  const TransportOperator& F = *s[0]->F;
  const std::int32_t n = s[0]->size();
  double* b[C];
  for (int c = 0; c < C; ++c) {
    b[c] = B[c]->data();
    sq[c] = 0.0;
  }
  for (std::int32_t i = 0; i < n; ++i) {
    const TransportOperator::RowSpan row = F.row(i);
    double gather[C] = {};
    for (std::int64_t k = 0; k < row.count; ++k) {
      const double v = row.values[k];
      const auto j = row.cols[k];
      for (int c = 0; c < C; ++c) gather[c] += v * b[c][j];
    }
    for (int c = 0; c < C; ++c) {
      const double d = 1.0 - s[c]->rho[i] * s[c]->f_diag[i];
      const double r = s[c]->E[i] + s[c]->rho[i] * gather[c] - b[c][i];  // row i of E - K B
      sq[c] += r * r;
      b[c][i] += omega * r / d;
    }
  }
  for (int c = 0; c < C; ++c) ++s[c]->matvecs;
}

// One channel's state in a fused run.
struct SorChannel {
  const ChannelSystem* system;
  Eigen::VectorXd* B;
  ChannelReport* report;
  double check_below;  // sweep residual that triggers a true-residual check
  bool done = false;
};

void sor_channels(const std::vector<const ChannelSystem*>& systems, const SolveOptions& options,
                  double omega, const std::vector<Eigen::VectorXd*>& B,
                  const std::vector<ChannelReport*>& reports) {
  constexpr int kMaxChannels = 3;
  LAMBERT_CHECK(systems.size() == B.size() && systems.size() == reports.size() &&
                    systems.size() <= kMaxChannels,
                "solve_sor_channels: one system, solution and report per channel, at most 3");
  std::vector<SorChannel> ch;
  for (size_t c = 0; c < systems.size(); ++c) {
    *reports[c] = ChannelReport();
    *B[c] = systems[c]->guess;
    record(*reports[c], 0, systems[c]->relative_residual_uncounted(*B[c]), 0.0);
    reports[c]->status = SolveStatus::MaxIterations;
    ch.push_back({systems[c], B[c], reports[c], options.tol});
  }
  const Timer timer;
  for (int k = 1; k <= options.max_iterations; ++k) {
    const ChannelSystem* s[kMaxChannels];
    Eigen::VectorXd* b[kMaxChannels];
    SorChannel* live[kMaxChannels];
    int count = 0;
    for (SorChannel& c : ch)
      if (!c.done) {
        s[count] = c.system;
        b[count] = c.B;
        live[count++] = &c;
      }
    if (count == 0) break;
    double sq[kMaxChannels];
    if (count == 1) sor_sweep<1>(s, omega, b, sq);
    if (count == 2) sor_sweep<2>(s, omega, b, sq);
    if (count == 3) sor_sweep<3>(s, omega, b, sq);
    for (int q = 0; q < count; ++q) {
      SorChannel& c = *live[q];
      ChannelReport& report = *c.report;
      const double sweep = std::sqrt(sq[q]) / c.system->e_norm;
      report.iterations = k;
      report.residual = sweep;
      if (!std::isfinite(sweep)) {
        report.status = SolveStatus::NumericalIssue;
        record(report, k, sweep, timer.seconds());
        c.done = true;
      } else if (sweep <= c.check_below || k == options.max_iterations) {
        const double truth = c.system->relative_residual(*c.B);
        report.residual = truth;
        record(report, k, truth, timer.seconds());
        if (truth <= options.tol) {
          report.status = SolveStatus::Converged;
          c.done = true;
        }
        // Expect the true residual to fall in proportion to the sweep residual.
        c.check_below = sweep * options.tol / truth;
      } else {
        record(report, k, sweep, timer.seconds());
      }
      if (c.done || k == options.max_iterations) report.seconds = timer.seconds();
    }
  }
}

ChannelReport sor_iterate(const ChannelSystem& system, const SolveOptions& options, double omega,
                          Eigen::VectorXd& B) {
  ChannelReport report;
  sor_channels({&system}, options, omega, {&B}, {&report});
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

void solve_gauss_seidel_channels(const std::vector<const ChannelSystem*>& systems,
                                 const SolveOptions& options,
                                 const std::vector<Eigen::VectorXd*>& B,
                                 const std::vector<ChannelReport*>& reports) {
  sor_channels(systems, options, 1.0, B, reports);
}

void solve_sor_channels(const std::vector<const ChannelSystem*>& systems,
                        const SolveOptions& options, const std::vector<Eigen::VectorXd*>& B,
                        const std::vector<ChannelReport*>& reports) {
  sor_channels(systems, options, options.omega, B, reports);
}

}  // namespace lambert
