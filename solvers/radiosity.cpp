#include "solvers/radiosity.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "solvers/system.hpp"

namespace lambert {
namespace {

struct SolverEntry {
  const char* name;
  const char* description;
  ChannelSolver solve;
  /// The method runs on one thread (a sweep in row order): its three channels are solved
  /// side by side instead (the others spread each product over the threads).
  bool serial = false;
  /// A serial method that also solves a group of channels in one pass over F: the channels
  /// are split into min(threads, 3) groups, each swept together on its own thread.
  ChannelGroupSolver group = nullptr;
};

// The registry: a table of functions chosen by name.
const SolverEntry kSolvers[] = {
    {"jacobi", "Jacobi: B <- B + (E - K B) / diag(K), all rows from the previous iterate",
     solve_jacobi},
    {"gauss-seidel", "Gauss-Seidel gathering, one row at a time with the newest values",
     solve_gauss_seidel, true, solve_gauss_seidel_channels},
    {"sor", "successive over-relaxation of Gauss-Seidel (--omega)", solve_sor, true,
     solve_sor_channels},
    {"southwell",
     "Southwell / progressive refinement: shoot from the largest unshot power (Cohen 1988)",
     solve_southwell, true},
    {"bicgstab", "BiCGSTAB through the transport operator, --preconditioner none|diagonal|ilut",
     solve_bicgstab},
    {"gmres", "restarted GMRES(m), right-preconditioned, --restart m, --preconditioner",
     solve_gmres},
    {"cg", "conjugate gradient on the symmetric system diag(A/rho) K (needs reciprocal F)",
     solve_cg},
    {"direct",
     "Eigen SparseLU (dense LU when F is over 10% full): the reference; refused above the "
     "job's memory limit",
     solve_direct},
};

const SolverEntry& find_solver(const std::string& name) {
  for (const auto& s : kSolvers)
    if (name == s.name) return s;
  std::string names;
  for (const auto& s : kSolvers) names += std::string(names.empty() ? "" : ", ") + s.name;
  throw UsageError("unknown solver '" + name + "' (known: " + names + ")");
}

void validate_options(const SolveOptions& o) {
  if (!(o.tol > 0.0) || !(o.tol < 1.0))
    throw UsageError("--tol must be in (0, 1), got " + std::to_string(o.tol));
  if (o.max_iterations < 1) throw UsageError("--max-iter must be at least 1");
  if (!(o.omega > 0.0 && o.omega < 2.0))
    throw UsageError("--omega must be in (0, 2) for SOR to converge, got " +
                     std::to_string(o.omega));
  if (o.preconditioner != "none" && o.preconditioner != "diagonal" && o.preconditioner != "ilut")
    throw UsageError("unknown preconditioner '" + o.preconditioner +
                     "' (known: none, diagonal, ilut)");
  if (o.restart < 1) throw UsageError("--restart must be at least 1");
  if (o.solver == "cg" && o.preconditioner == "ilut")
    throw UsageError("cg needs a symmetric preconditioner: use --preconditioner none or diagonal");
}

// Refuses what the operator cannot do before any channel starts: the methods that factorise
// the assembled matrix on a matrix-free operator, and direct above the memory limit.
void check_applicable(const RadiosityProblem& p, const SolveOptions& o) {
  const bool uses_ilut =
      (o.solver == "bicgstab" || o.solver == "gmres") && o.preconditioner == "ilut";
  if ((o.solver == "direct" || uses_ilut) && p.F->matrix() == nullptr)
    throw UsageError(matrix_free_refusal(uses_ilut ? "the ilut preconditioner" : "direct"));
  if (o.solver == "direct") {
    const std::string why =
        direct_refusal(p.F->size(), p.F->entries(), o.memory_limit, o.memory_limit_source);
    if (!why.empty()) throw UsageError(why);
  }
}

// What physics bounds in F before a solve (issue 33, item 6). F_ij is the fraction of the
// power leaving i that arrives at j: finite and in [0, 1] (kEntrySlack: rounding of a
// computed or saved factor, far below any estimator's error). A row sums to at most 1 (1 in
// a closed enclosure), but estimates exceed 1 by their noise: measured on the Cornell box at
// 300 patches and the fewest samples accepted (2), max row sums 1.017 (hybrid) and 1.057
// (mc); 8 samples 1.009 and 1.011. kRowSlack = 0.25 passes any such estimate and refuses
// what no estimate of a form-factor matrix gives (row sums of 2.4 or 10, which solved to
// negative B and negative absorbed power). Below it, whether the solve is physical is
// checked on its result (solve_radiosity: B >= 0).
void check_form_factors(const RadiosityProblem& p, int threads) {
  constexpr double kEntrySlack = 1e-12, kRowSlack = 0.25;
  const TransportOperator& F = *p.F;
  const bool has_continued = p.continued.size() == p.area.size();
  // Rows are checked in parallel, each marking its first impossible entry (or -2 for an
  // impossible sum); the first marked row is reported, as a row-by-row scan would.
  std::vector<std::int64_t> bad(F.size(), -1);
  auto check_row = [&](std::int32_t i) -> std::int64_t {
    const TransportOperator::RowSpan r = F.row(i);
    double sum = 0.0;
    for (std::int64_t k = 0; k < r.count; ++k) {
      const double f = r.values[k];
      if (!(f >= 0.0 && f <= 1.0 + kEntrySlack)) return k;
      sum += f;
    }
    return sum - (has_continued ? p.continued[i] : 0.0) > 1.0 + kRowSlack ? -2 : -1;
  };
  parallel_for(F.size(), 1024, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) bad[i] = check_row(static_cast<std::int32_t>(i));
  });
  for (std::int32_t i = 0; i < F.size(); ++i) {
    if (bad[i] == -1) continue;
    const TransportOperator::RowSpan r = F.row(i);
    if (bad[i] >= 0)
      throw SceneError("form factor F(" + std::to_string(i) + ", " +
                       std::to_string(r.cols[bad[i]]) + ") = " + std::to_string(r.values[bad[i]]) +
                       " is impossible (a form factor lies in [0, 1])");
    double sum = 0.0;
    for (std::int64_t k = 0; k < r.count; ++k) sum += r.values[k];
    throw SceneError("form factors of patch " + std::to_string(i) + " sum to " +
                     std::to_string(sum - (has_continued ? p.continued[i] : 0.0)) +
                     ": impossible (a row sums to at most 1, Monte Carlo noise aside; "
                     "more samples, or the hybrid estimator)");
  }
}

int severity(SolveStatus s) {
  return s == SolveStatus::Converged ? 0 : s == SolveStatus::MaxIterations ? 1 : 2;
}

}  // namespace

const char* to_string(SolveStatus status) {
  switch (status) {
    case SolveStatus::Converged:
      return "converged";
    case SolveStatus::MaxIterations:
      return "max-iterations";
    case SolveStatus::NumericalIssue:
      return "numerical-issue";
  }
  return "unknown";
}

std::vector<SolverInfo> solver_registry() {
  std::vector<SolverInfo> out;
  for (const auto& s : kSolvers) out.push_back({s.name, s.description});
  return out;
}

std::vector<std::string> solver_names() {
  std::vector<std::string> out;
  for (const auto& s : kSolvers) out.emplace_back(s.name);
  return out;
}

void validate_problem(const RadiosityProblem& p, int threads) {
  if (p.F == nullptr) throw UsageError("radiosity problem without a form-factor operator");
  const Eigen::Index n = p.area.size();
  if (p.F->size() != n || p.rho.rows() != n || p.emission.rows() != n)
    throw UsageError("radiosity problem sizes disagree: F " + std::to_string(p.F->size()) + "x" +
                     std::to_string(p.F->size()) + ", " + std::to_string(n) + " areas, " +
                     std::to_string(p.rho.rows()) + " rho rows, " +
                     std::to_string(p.emission.rows()) + " emission rows");
  if (n == 0) throw UsageError("radiosity problem without patches");
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(p.area[i] > 0.0) || !std::isfinite(p.area[i]))
      throw UsageError("patch " + std::to_string(i) + " has non-positive area");
    for (int c = 0; c < 3; ++c) {
      // rho = 1 (lossless) is allowed: the system is singular only for a closed set of
      // lossless patches, which the caller rules out (analysis.hpp, find_closed_lossless).
      if (!(p.rho(i, c) >= 0.0 && p.rho(i, c) <= 1.0))
        throw UsageError("patch " + std::to_string(i) + ": rho must be in [0, 1]");
      if (!std::isfinite(p.emission(i, c)) || (!p.signed_emission && !(p.emission(i, c) >= 0.0)))
        throw UsageError("patch " + std::to_string(i) +
                         std::string(p.signed_emission ? ": emission must be finite"
                                                       : ": emission must be finite and >= 0"));
    }
  }
  check_form_factors(p, threads);
}

double relative_residual(const RadiosityProblem& problem, const Eigen::MatrixX3d& B, int channel) {
  const ChannelSystem s = make_channel_system(problem, channel, 1);
  return s.relative_residual_uncounted(B.col(channel) / s.e_scale);
}

// Energy bookkeeping (power, W in scene units). H = F B is the irradiance: for a reciprocal
// F the power that reaches patch i is sum_j A_j B_j F_ji = A_i sum_j F_ij B_j = A_i H_i.
// Absorbed: a fraction (1 - rho_i) of it. Escaped: patch i's exitance times the fraction of
// its hemisphere that sees no patch, A_i B_i (1 - sum_j F_ij). Expanding,
//   emitted - absorbed - escaped = sum A (E + rho H - B) + (sum A B rowsum(F) - sum A H)
//                                = sum A r            + sum_ij A_i F_ij (B_i - B_j),
// the residual part (zero for an exact solution) and the non-reciprocity part: the second
// sum is sum_ij (A_j F_ji - A_i F_ij) B_j after relabelling its first half, zero when
// A_i F_ij = A_j F_ji. Both parts are computed from their definitions (not as differences),
// so each carries only the rounding of its own sums. Cost: one product with F and one pass
// for its row sums, O(nnz); no entry is looked up by (row, column).
// Extended form factors count an arrival at a specular patch and again wherever the light
// it carries on arrives: with c_i the carried-on part of row i (problem.continued), light
// that escapes is A_i B_i (1 − rowsum_i + c_i) and the absorbed part of H loses Σ A B c, so
// the two parts of the imbalance above are unchanged.
EnergyBalance energy_balance(const RadiosityProblem& problem, const Eigen::MatrixX3d& B,
                             int channel, int threads) {
  const TransportOperator& F = *problem.F;
  const Eigen::VectorXd b = B.col(channel);
  Eigen::VectorXd h, row_sum;
  F.apply(b, h, threads);
  // F 1: each row summed in storage order (x 1.0 is exact), bitwise row_sums().
  F.apply(Eigen::VectorXd::Ones(b.size()), row_sum, threads);
  const Eigen::VectorXd& a = problem.area;
  const Eigen::VectorXd rho = problem.rho.col(channel);
  const Eigen::VectorXd e_col = problem.emission.col(channel);
  const Eigen::VectorXd c =
      problem.continued.size() ? problem.continued : Eigen::VectorXd::Zero(b.size());
  EnergyBalance e;
  e.emitted = a.dot(e_col);
  e.absorbed = a.dot((1.0 - rho.array()).matrix().cwiseProduct(h)) - a.dot(b.cwiseProduct(c));
  e.escaped = a.dot(b.cwiseProduct((1.0 - row_sum.array() + c.array()).matrix()));
  const double imbalance = std::abs(e.emitted - e.absorbed - e.escaped);
  e.relative_imbalance = e.emitted > 0.0 ? imbalance / e.emitted : imbalance;
  e.residual_part = a.dot(e_col + rho.cwiseProduct(h) - b);
  e.non_reciprocity_part = a.dot(b.cwiseProduct(row_sum) - h);
  return e;
}

RadiositySolution solve_radiosity(const RadiosityProblem& problem, const SolveOptions& options) {
  const SolverEntry& entry = find_solver(options.solver);
  validate_options(options);
  validate_problem(problem, options.threads);
  check_applicable(problem, options);
  if (options.initial_guess.size() > 0 && options.initial_guess.rows() != problem.area.size())
    throw UsageError("initial guess has " + std::to_string(options.initial_guess.rows()) +
                     " rows for " + std::to_string(problem.area.size()) + " patches");
  const Timer timer;
  const Eigen::Index n = problem.area.size();
  RadiositySolution sol;
  sol.B = Eigen::MatrixX3d::Zero(n, 3);
  // One channel: its own system, report and column (independent of the others, so the
  // channels of a serial method run side by side with the same results).
  auto solve_channel = [&](int c, int threads) {
    const ChannelSystem system = make_channel_system(problem, c, threads, options.initial_guess);
    ChannelReport& report = sol.channels[c];
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
    if (system.e_norm == 0.0) {
      // Nothing emitted in this channel: B = 0 solves K B = 0 exactly.
      record(report, 0, 0.0, 0.0);
    } else {
      report = entry.solve(system, options, b);
      report.matvecs = system.matvecs;
    }
    sol.B.col(c) = b * system.e_scale;
  };
  if (entry.group) {
    // Channels grouped over the threads (1 thread: all three in one pass over F per sweep;
    // 2: one alone and two together; 3 or more: one each). Every channel is bitwise the
    // same in any grouping.
    std::vector<ChannelSystem> systems;
    for (int c = 0; c < 3; ++c)
      systems.push_back(make_channel_system(problem, c, 1, options.initial_guess));
    std::vector<Eigen::VectorXd> b(3, Eigen::VectorXd::Zero(n));
    std::vector<int> emitting;
    for (int c = 0; c < 3; ++c) {
      if (systems[c].e_norm > 0.0)
        emitting.push_back(c);
      else
        record(sol.channels[c], 0, 0.0, 0.0);  // nothing emitted: B = 0 solves K B = 0 exactly
    }
    const int groups =
        std::min<int>(resolve_threads(options.threads), static_cast<int>(emitting.size()));
    parallel_for(groups, 1, groups, [&](std::int64_t begin, std::int64_t end) {
      for (auto g = begin; g < end; ++g) {
        // Group g takes the emitting channels g, g + groups, ... (2 threads: {0, 2} and {1}).
        std::vector<const ChannelSystem*> s;
        std::vector<Eigen::VectorXd*> x;
        std::vector<ChannelReport*> r;
        for (size_t q = static_cast<size_t>(g); q < emitting.size();
             q += static_cast<size_t>(groups)) {
          s.push_back(&systems[emitting[q]]);
          x.push_back(&b[emitting[q]]);
          r.push_back(&sol.channels[emitting[q]]);
        }
        entry.group(s, options, x, r);
      }
    });
    for (int c = 0; c < 3; ++c) {
      sol.channels[c].matvecs = systems[c].matvecs;
      sol.B.col(c) = b[c] * systems[c].e_scale;
    }
  } else if (entry.serial) {
    parallel_for(3, 1, options.threads, [&](std::int64_t begin, std::int64_t end) {
      for (auto c = begin; c < end; ++c) solve_channel(static_cast<int>(c), 1);
    });
  } else {
    for (int c = 0; c < 3; ++c) solve_channel(c, options.threads);
  }
  for (int c = 0; c < 3; ++c)
    if (severity(sol.channels[c].status) > severity(sol.status))
      sol.status = sol.channels[c].status;
  sol.seconds = timer.seconds();
  // After the solve: B is finite, and for E >= 0 (an M-matrix K, check_form_factors) B >= 0
  // up to the solve's own error, tol ||E||_2 / (1 - rho_max) per entry (STYLE.md's bound,
  // rho_max < 1; for rho_max = 1 the bound scales with max B instead). Otherwise the result is
  // a numerical issue, never reported as converged; a non-finite B is an Error.
  for (int c = 0; c < 3; ++c)  // never handed on: an error, not a status
    if (!sol.B.col(c).allFinite())
      throw Error("solver " + options.solver + ": the radiosity of channel " + std::to_string(c) +
                  " is not finite (" + to_string(sol.channels[c].status) + " after " +
                  std::to_string(sol.channels[c].iterations) +
                  " iterations): the problem's scale is beyond double precision" +
                  (options.initial_guess.size() > 0 ? ", or the initial guess is" : ""));
  if (!problem.signed_emission && n > 0) {
    for (int c = 0; c < 3; ++c) {
      const double rho_max = problem.rho.col(c).maxCoeff();
      const double e_norm = problem.emission.col(c).norm();
      const double bound =
          10.0 * options.tol * (rho_max < 1.0 ? e_norm / (1.0 - rho_max) : sol.B.col(c).maxCoeff());
      if (sol.B.col(c).minCoeff() < -bound) sol.status = SolveStatus::NumericalIssue;
    }
  }
  for (int c = 0; c < 3; ++c) sol.energy[c] = energy_balance(problem, sol.B, c, options.threads);
  return sol;
}

}  // namespace lambert
