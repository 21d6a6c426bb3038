#pragma once
// One colour channel of the radiosity system, K = I - diag(rho) F, applied through the shared
// transport operator F, and the pieces every solver shares (residual, history). Internal to
// solvers/.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/sparse.hpp"
#include "core/timer.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// One channel c: K = I - diag(rho) F with the shared F; counts the products it performs.
struct ChannelSystem {
  const TransportOperator* F = nullptr;
  Eigen::VectorXd rho;     ///< rho_c per patch
  /// E_c per patch divided by e_scale: K B = E is linear, so the solvers work on a system
  /// whose emission is at most 1 and B is multiplied back by e_scale. Unscaled, ||E||_2
  /// and ||r||_2 overflow to inf for any E above ~1e154 (their squares pass DBL_MAX).
  Eigen::VectorXd E;
  Eigen::VectorXd guess;   ///< initial guess, scaled like E (E unless warm-started)
  bool warm = false;       ///< the guess is a warm start (SolveOptions::initial_guess)
  double e_scale = 1.0;    ///< max_i |E_c,i| (1 when nothing is emitted)
  Eigen::VectorXd area;    ///< A per patch
  Eigen::VectorXd f_diag;  ///< F_ii (0 for planar patches; kept for generality)
  double e_norm = 0.0;     ///< ||E||_2 of the scaled E
  int threads = 1;
  mutable std::int64_t matvecs = 0;  ///< products with F performed so far

  std::int32_t size() const { return static_cast<std::int32_t>(E.size()); }
  /// y = F x with the system's threads; one counted product.
  void apply_f(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  /// y = K x = x - rho .* (F x); one counted product.
  void apply_k(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  /// ||E - K B||_2 / ||E||_2 (the one stopping rule); one counted product.
  double relative_residual(const Eigen::VectorXd& B) const;
  /// The same, without counting (for reports outside the timing).
  double relative_residual_uncounted(const Eigen::VectorXd& B) const;
};

/// Builds channel c of the problem; `initial_guess` (N x 3, or empty for E) is its guess.
ChannelSystem make_channel_system(const RadiosityProblem& problem, int channel, int threads,
                                  const Eigen::MatrixX3d& initial_guess = Eigen::MatrixX3d());

/// Appends history points to a report.
inline void record(ChannelReport& report, int iteration, double residual, double seconds) {
  report.history_iteration.push_back(iteration);
  report.residual_history.push_back(residual);
  report.time_history.push_back(seconds);
}

/// The per-channel solver functions. Each starts from its own initial guess (documented in
/// its source), writes the solution to B (size N) and returns the report with history point
/// 0 (the initial guess). The caller copies system.matvecs into the report.
using ChannelSolver = ChannelReport (*)(const ChannelSystem& system, const SolveOptions& options,
                                        Eigen::VectorXd& B);

ChannelReport solve_jacobi(const ChannelSystem& system, const SolveOptions& options,
                           Eigen::VectorXd& B);  ///< jacobi
ChannelReport solve_gauss_seidel(const ChannelSystem& system, const SolveOptions& options,
                                 Eigen::VectorXd& B);  ///< gauss-seidel (omega 1)
ChannelReport solve_sor(const ChannelSystem& system, const SolveOptions& options,
                        Eigen::VectorXd& B);  ///< sor (options.omega)
/// A solver of several channels of one problem at once (they share F): systems[c] solves
/// into *B[c] and reports into *reports[c] (at most 3 channels).
using ChannelGroupSolver = void (*)(const std::vector<const ChannelSystem*>& systems,
                                    const SolveOptions& options,
                                    const std::vector<Eigen::VectorXd*>& B,
                                    const std::vector<ChannelReport*>& reports);
/// Gauss-Seidel and SOR on a group of channels: one pass over F's rows per sweep updates
/// every channel still iterating, each with its own stopping rule and report, and each
/// bitwise what it is when solved alone (solve_gauss_seidel, solve_sor).
void solve_gauss_seidel_channels(const std::vector<const ChannelSystem*>& systems,
                                 const SolveOptions& options,
                                 const std::vector<Eigen::VectorXd*>& B,
                                 const std::vector<ChannelReport*>& reports);
void solve_sor_channels(const std::vector<const ChannelSystem*>& systems,
                        const SolveOptions& options, const std::vector<Eigen::VectorXd*>& B,
                        const std::vector<ChannelReport*>& reports);
ChannelReport solve_southwell(const ChannelSystem& system, const SolveOptions& options,
                              Eigen::VectorXd& B);  ///< southwell / progressive refinement
ChannelReport solve_bicgstab(const ChannelSystem& system, const SolveOptions& options,
                             Eigen::VectorXd& B);  ///< bicgstab
ChannelReport solve_gmres(const ChannelSystem& system, const SolveOptions& options,
                          Eigen::VectorXd& B);  ///< gmres
ChannelReport solve_cg(const ChannelSystem& system, const SolveOptions& options,
                       Eigen::VectorXd& B);  ///< cg on diag(A/rho) K
ChannelReport solve_direct(const ChannelSystem& system, const SolveOptions& options,
                           Eigen::VectorXd& B);  ///< direct (SparseLU)

/// The refusal of `who` (direct, ILUT) on an operator without an assembled matrix.
std::string matrix_free_refusal(const std::string& who);

/// K = I - diag(rho) F assembled (one channel at a time; for direct and ILUT only). Throws
/// UsageError naming `who` when the operator has no assembled matrix.
SparseRowMatrix assemble_k(const ChannelSystem& system, const char* who);

/// Appends history point k unless the history holds kMaxHistoryPoints already, in which case
/// every other point (all but the first) is dropped first and the stride doubles: at most
/// kMaxHistoryPoints points, evenly spaced over the iterations, first and last kept (the
/// caller records the last one with `force`). `stride` is the caller's state, starting at 1.
void record_thinned(ChannelReport& report, int& stride, int iteration, double residual,
                    double seconds, bool force = false);

/// Bound of record_thinned (a plot needs no more; memory stays O(1) in max-iter).
constexpr int kMaxHistoryPoints = 1000;

}  // namespace lambert
