#pragma once
// The radiosity system K_c B_c = E_c with K_c = I - diag(rho_c) F, per colour channel c,
// and the registry of solvers. Sees a matrix, vectors and areas only.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/sparse.hpp"
#include "solvers/operator.hpp"

namespace lambert {

/// Outcome of an iterative solve (like Eigen's ComputationInfo).
enum class SolveStatus { Converged, MaxIterations, NumericalIssue };

/// "converged", "max-iterations" or "numerical-issue".
const char* to_string(SolveStatus status);

/// The problem: one shared transport operator F and per-patch, per-channel rho and E, and
/// patch areas.
struct RadiosityProblem {
  /// N x N form factors (row i: F_ij), e.g. a CsrOperator over an assembled F (which must
  /// outlive the problem).
  std::shared_ptr<const TransportOperator> F;
  Eigen::MatrixX3d rho;                ///< N x 3 reflectance, each in [0, 1]
  Eigen::MatrixX3d emission;           ///< N x 3 emitted radiosity E (W/m^2)
  Eigen::VectorXd area;                ///< N patch areas
  /// Extended form factors (through mirrors and glass): per row, the part of its row sum
  /// that arrived and was carried on specularly (counted again further on); empty = none.
  /// The energy balance needs it: row sum − continued is what ends somewhere.
  Eigen::VectorXd continued;
  /// E may be negative (thermal exchange: a known net flux q < 0 removes heat, thermal.hpp);
  /// otherwise validate_problem refuses E < 0 (light is never negative).
  bool signed_emission = false;
};

/// Solver settings; one stopping rule for all: ||E - K B||_2 / ||E||_2 <= tol.
struct SolveOptions {
  std::string solver = "gauss-seidel";  ///< a name from solver_names()
  double tol = 1e-8;
  int max_iterations = 10000;
  double omega = 1.5;                       ///< SOR relaxation factor
  std::string preconditioner = "diagonal";  ///< bicgstab: "none", "diagonal" or "ilut"
  int restart = 30;                         ///< gmres restart length
  bool ambient = false;                     ///< southwell: add the ambient term for display
  int threads = 1;                          ///< threads for F x products (Gauss-Seidel/SOR/
                                            ///< Southwell sweeps are sequential); 0 = all cores
  /// Bytes the job may use (0 = no limit): direct refuses a factorisation above it.
  double memory_limit = 0.0;
  /// Where memory_limit comes from, for messages (e.g. "--max-memory 512M").
  std::string memory_limit_source;
  /// The iterative solvers' initial guess B (N x 3; empty = E, the default): a warm start
  /// from a previous solution (adaptive meshing). `direct` ignores it.
  Eigen::MatrixX3d initial_guess;
};

/// Per-channel solver report.
struct ChannelReport {
  SolveStatus status = SolveStatus::Converged;
  int iterations = 0;
  std::int64_t matvecs = 0;              ///< matrix-vector products (or equivalent row sweeps)
  double residual = 0.0;                 ///< final relative residual ||E - K B|| / ||E||
  std::vector<double> residual_history;  ///< relative residual at history point k
  std::vector<double> time_history;      ///< seconds since the start at history point k
  std::vector<int> history_iteration;    ///< iteration count at history point k (0 = guess)
  double seconds = 0.0;
  std::string note;  ///< solver remark (refinements, ambient, fallback)
  int refinements = 0;  ///< southwell: restarts from the true residual (F not reciprocal)
};

/// Power bookkeeping of a solution, per channel (W in scene units).
struct EnergyBalance {
  double emitted = 0.0;   ///< sum_i A_i E_i
  double absorbed = 0.0;  ///< sum_i A_i (1 - rho_i) H_i, H = F B the irradiance (see below)
  double escaped = 0.0;   ///< power leaving through open boundaries: sum_i A_i B_i (1 - sum_j F_ij)
  double relative_imbalance = 0.0;  ///< |emitted - absorbed - escaped| / emitted
  /// The imbalance emitted - absorbed - escaped split into its two causes (W, signed; they
  /// add up to it to rounding):
  double residual_part = 0.0;         ///< sum_i A_i r_i, r = E + rho H - B: the solver's share
  double non_reciprocity_part = 0.0;  ///< sum_ij (A_i F_ij B_i - A_i F_ij B_j): F's share,
                                      ///< 0 when A_i F_ij = A_j F_ji
};

/// The solution of all three channels.
struct RadiositySolution {
  Eigen::MatrixX3d B;  ///< N x 3 radiosity
  std::array<ChannelReport, 3> channels;
  std::array<EnergyBalance, 3> energy;
  SolveStatus status = SolveStatus::Converged;  ///< worst over channels
  double seconds = 0.0;
};

/// Name and one-line description of each solver.
struct SolverInfo {
  std::string name;
  std::string description;
};

/// All solvers: jacobi, gauss-seidel, sor, southwell, bicgstab, gmres, cg, direct.
std::vector<SolverInfo> solver_registry();
/// Just the names, for CLI validation.
std::vector<std::string> solver_names();

/// ||E_c - K_c B_c||_2 / ||E_c||_2 for channel c of B (0 when E_c = 0 and B_c = 0).
double relative_residual(const RadiosityProblem& problem, const Eigen::MatrixX3d& B, int channel);

/// Power bookkeeping of channel c of B. With H = F B (irradiance, by reciprocity
/// A_i H_i = sum_j A_j F_ji B_j is the power arriving at i): emitted sum A_i E_i,
/// absorbed sum A_i (1 - rho_i) H_i, escaped sum A_i B_i (1 - sum_j F_ij). Always
/// emitted - absorbed - escaped = residual_part + non_reciprocity_part: sum_i A_i r_i with
/// r = E - K B the residual (0 for an exact solution), plus
/// sum_i A_i B_i sum_j F_ij - sum_i A_i H_i (0 for a reciprocal F, A_i F_ij = A_j F_ji).
/// Its two products with F run on `threads` (bitwise the same for any count).
EnergyBalance energy_balance(const RadiosityProblem& problem, const Eigen::MatrixX3d& B,
                             int channel, int threads = 1);

/// Checks sizes and ranges of a problem (N x N F, rho in [0, 1], E >= 0, A > 0); throws
/// UsageError naming what is wrong. F's rows are checked on `threads`.
void validate_problem(const RadiosityProblem& problem, int threads = 1);

/// Peak bytes of `direct` on an N-patch F with `nnz` entries: the assembled K plus a dense
/// LU (8 N^2) above 10% fill, else the SparseLU estimate (see direct.cpp).
double direct_memory_bytes(std::int32_t n, std::int64_t nnz);

/// The one-line refusal of `direct` when direct_memory_bytes exceeds `limit` bytes ("" when
/// it fits or limit is 0); `source` names where the limit comes from.
std::string direct_refusal(std::int32_t n, std::int64_t nnz, double limit,
                           const std::string& source);

/// Solves every channel with the chosen solver. Throws UsageError for an unknown solver or
/// a solver that does not apply (cg with ilut; direct or ilut on a matrix-free operator;
/// direct above options.memory_limit).
RadiositySolution solve_radiosity(const RadiosityProblem& problem, const SolveOptions& options);

}  // namespace lambert
