// The radiosity solve in PETSc: one MATMPIAIJ K = I - diag(rho_c) F per channel (rows where
// F's rows were computed), a KSP, lambert's stopping rule on the true residual.
#include "apps/dist_petsc.hpp"

#include <petscksp.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/timer.hpp"
#include "solvers/operator.hpp"

namespace lambert::dist {
namespace {

void check(PetscErrorCode code, const char* what) {
  if (code)
    throw Error(std::string("PETSc: ") + what + " failed (error " + std::to_string(code) + ")");
}

// Owners of PETSc objects (destroyed on every path, exceptions included).
struct MatOwner {
  Mat m = nullptr;
  ~MatOwner() { MatDestroy(&m); }
};
struct VecOwner {
  Vec v = nullptr;
  ~VecOwner() { VecDestroy(&v); }
};
struct KspOwner {
  KSP k = nullptr;
  ~KspOwner() { KSPDestroy(&k); }
};

// K's rows of this rank in local CSR arrays (row pointers from 0, global columns), the
// diagonal 1 - rho_i F_ii merged in at its sorted place.
void assemble_k(const RowBlock& block, const Eigen::VectorXd& rho, std::int32_t n, Mat& K) {
  const auto* outer = block.F.outerIndexPtr();
  const std::int32_t m = block.end - block.begin;
  std::vector<PetscInt> ia(static_cast<size_t>(m) + 1, 0), ja;
  std::vector<PetscScalar> va;
  ja.reserve(static_cast<size_t>(outer[block.end] - outer[block.begin] + m));
  va.reserve(ja.capacity());
  for (std::int32_t i = block.begin; i < block.end; ++i) {
    bool diagonal = false;
    for (std::int64_t k = outer[i]; k <= outer[i + 1]; ++k) {
      const std::int64_t j = k < outer[i + 1] ? block.F.innerIndexPtr()[k] : n;
      if (!diagonal && j >= i) {
        ja.push_back(i);
        va.push_back(1.0);
        diagonal = true;
      }
      if (k == outer[i + 1]) break;
      const double value = -rho[i] * block.F.valuePtr()[k];
      if (j == i)
        va.back() += value;
      else
        ja.push_back(static_cast<PetscInt>(j)), va.push_back(value);
    }
    ia[i - block.begin + 1] = static_cast<PetscInt>(ja.size());
  }
  check(
      MatCreateMPIAIJWithArrays(PETSC_COMM_WORLD, m, m, n, n, ia.data(), ja.data(), va.data(), &K),
      "MatCreateMPIAIJWithArrays");
}

// ||E - K x||_2 / ||E||_2 (collective).
double true_residual(Mat K, Vec x, Vec e, double e_norm) {
  VecOwner r;
  check(VecDuplicate(e, &r.v), "VecDuplicate");
  check(MatMult(K, x, r.v), "MatMult");
  check(VecAYPX(r.v, -1.0, e), "VecAYPX");
  PetscReal norm = 0.0;
  check(VecNorm(r.v, NORM_2, &norm), "VecNorm");
  return norm / e_norm;
}

struct Monitor {
  ChannelReport* report;
  const Timer* timer;
  double e_norm;
  int offset;  // iterations of earlier KSP runs (refinements)
};

PetscErrorCode monitor(KSP, PetscInt it, PetscReal rnorm, void* ctx) {
  auto* m = static_cast<Monitor*>(ctx);
  if (it == 0 && m->offset > 0) return 0;  // a refinement's start is the last point again
  m->report->history_iteration.push_back(m->offset + static_cast<int>(it));
  m->report->residual_history.push_back(rnorm / m->e_norm);
  m->report->time_history.push_back(m->timer->seconds());
  return 0;
}

// At most this many reruns with a tighter tolerance when PETSc's own test stopped with the
// true residual above tol (preconditioned norms, rounding of the recurrence): each aims a
// factor 10 below what is still missing, so two are normally enough.
constexpr int kMaxRefinements = 5;

ChannelReport solve_channel(Mat K, Vec e, Vec x, double e_norm, const SolveOptions& o,
                            PetscSolve& out) {
  ChannelReport report;
  const Timer timer;
  KspOwner ksp;
  check(KSPCreate(PETSC_COMM_WORLD, &ksp.k), "KSPCreate");
  check(KSPSetOperators(ksp.k, K, K), "KSPSetOperators");
  check(KSPSetType(ksp.k, KSPGMRES), "KSPSetType");
  check(KSPGMRESSetRestart(ksp.k, o.restart), "KSPGMRESSetRestart");
  PC pc;
  check(KSPGetPC(ksp.k, &pc), "KSPGetPC");
  check(PCSetType(pc, PCJACOBI), "PCSetType");
  check(KSPSetPCSide(ksp.k, PC_RIGHT), "KSPSetPCSide");
  check(KSPSetNormType(ksp.k, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
  check(KSPSetTolerances(ksp.k, o.tol, 0.0, PETSC_DEFAULT, o.max_iterations), "KSPSetTolerances");
  Monitor mon{&report, &timer, e_norm, 0};
  check(KSPMonitorSet(ksp.k, monitor, &mon, nullptr), "KSPMonitorSet");
  if (KSPSetFromOptions(ksp.k))  // the user's options: an unknown type, a bad value
    throw UsageError("--petsc-options / PETSC_OPTIONS: PETSc refused the KSP or PC options");
  KSPType ksp_type;
  PCType pc_type;
  check(KSPGetType(ksp.k, &ksp_type), "KSPGetType");
  check(PCGetType(pc, &pc_type), "PCGetType");
  out.ksp_type = ksp_type, out.pc_type = pc_type;
  check(VecCopy(e, x), "VecCopy");  // the guess B = E, as the single-process solvers
  check(KSPSetInitialGuessNonzero(ksp.k, PETSC_TRUE), "KSPSetInitialGuessNonzero");
  double rtol = o.tol;
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  for (int run = 0;; ++run) {
    check(KSPSolve(ksp.k, e, x), "KSPSolve");
    PetscInt its = 0;
    check(KSPGetIterationNumber(ksp.k, &its), "KSPGetIterationNumber");
    check(KSPGetConvergedReason(ksp.k, &reason), "KSPGetConvergedReason");
    report.iterations += static_cast<int>(its);
    report.matvecs += its + 2;  // one per iteration, the initial residual, the check below
    report.residual = true_residual(K, x, e, e_norm);
    if (reason <= 0 || report.residual <= o.tol || run == kMaxRefinements ||
        report.iterations >= o.max_iterations)
      break;
    // PETSc's test is relative to its initial residual: aim below what is still missing.
    rtol *= 0.1 * o.tol / report.residual;
    check(KSPSetTolerances(ksp.k, rtol, 0.0, PETSC_DEFAULT, o.max_iterations - report.iterations),
          "KSPSetTolerances");
    ++report.refinements;
    mon.offset = report.iterations;
  }
  report.status = report.residual <= o.tol                   ? SolveStatus::Converged
                  : reason == KSP_DIVERGED_ITS || reason > 0 ? SolveStatus::MaxIterations
                                                             : SolveStatus::NumericalIssue;
  report.note = std::string("petsc ") + ksp_type + "/" + pc_type + ", KSP reason " +
                KSPConvergedReasons[reason];
  report.seconds = timer.seconds();
  return report;
}

int severity(SolveStatus s) {
  return s == SolveStatus::Converged ? 0 : s == SolveStatus::MaxIterations ? 1 : 2;
}

}  // namespace

PetscSolve solve_petsc(const RadiosityProblem& problem, const RowBlock& block,
                       const SolveOptions& options) {
  const Timer timer;
  const auto n = static_cast<std::int32_t>(problem.area.size());
  const std::int32_t m = block.end - block.begin;
  int size = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  std::vector<std::int32_t> rows(static_cast<size_t>(size) + 1, n);  // first rows, for gathers
  MPI_Allgather(&block.begin, 1, MPI_INT32_T, rows.data(), 1, MPI_INT32_T, PETSC_COMM_WORLD);
  PetscSolve out;
  RadiositySolution& sol = out.solution;
  sol.B = Eigen::MatrixX3d::Zero(n, 3);
  for (int c = 0; c < 3; ++c) {
    MatOwner K;
    assemble_k(block, problem.rho.col(c), n, K.m);
    if (c == 0) {
      Mat diag_part, off_part;
      const PetscInt* colmap = nullptr;
      check(MatMPIAIJGetSeqAIJ(K.m, &diag_part, &off_part, &colmap), "MatMPIAIJGetSeqAIJ");
      PetscInt ghost_rows = 0, ghosts = 0;
      check(MatGetSize(off_part, &ghost_rows, &ghosts), "MatGetSize");
      out.ghost_columns = sum(static_cast<std::int64_t>(ghosts));
    }
    VecOwner e, x;
    check(MatCreateVecs(K.m, &x.v, &e.v), "MatCreateVecs");
    PetscScalar* pe = nullptr;
    check(VecGetArray(e.v, &pe), "VecGetArray");
    for (std::int32_t k = 0; k < m; ++k) pe[k] = problem.emission(block.begin + k, c);
    check(VecRestoreArray(e.v, &pe), "VecRestoreArray");
    PetscReal e_norm = 0.0;
    check(VecNorm(e.v, NORM_2, &e_norm), "VecNorm");
    ChannelReport& report = sol.channels[c];
    if (e_norm == 0.0) {  // nothing emitted: B = 0 exactly
      report.history_iteration = {0};
      report.residual_history = {0.0};
      report.time_history = {0.0};
    } else {
      report = solve_channel(K.m, e.v, x.v, e_norm, options, out);
      const PetscScalar* px = nullptr;
      check(VecGetArrayRead(x.v, &px), "VecGetArrayRead");
      const std::vector<double> local(px, px + m);
      check(VecRestoreArrayRead(x.v, &px), "VecRestoreArrayRead");
      const std::vector<double> all = allgather_rows(local, rows);
      sol.B.col(c) = Eigen::Map<const Eigen::VectorXd>(all.data(), n);
    }
    if (severity(report.status) > severity(sol.status)) sol.status = report.status;
  }
  sol.seconds = timer.seconds();
  // Energy balance: energy_balance's sums restricted to this rank's rows (area 0 elsewhere;
  // its every term is a sum over rows i weighted by A_i), then summed over the ranks.
  RadiosityProblem local = problem;
  local.F = std::make_shared<CsrOperator>(block.F);
  for (std::int32_t i = 0; i < n; ++i)
    if (i < block.begin || i >= block.end) local.area[i] = 0.0;
  for (int c = 0; c < 3; ++c) {
    EnergyBalance e = energy_balance(local, sol.B, c);
    e.emitted = sum(e.emitted), e.absorbed = sum(e.absorbed), e.escaped = sum(e.escaped);
    e.residual_part = sum(e.residual_part);
    e.non_reciprocity_part = sum(e.non_reciprocity_part);
    const double imbalance = std::abs(e.emitted - e.absorbed - e.escaped);
    e.relative_imbalance = e.emitted > 0.0 ? imbalance / e.emitted : imbalance;
    sol.energy[c] = e;
  }
  return out;
}

}  // namespace lambert::dist
