// Krylov solvers from Eigen, run matrix-free on the shared F.
//
// bicgstab, gmres: K B = E with K x = x - rho .* (F x) (one product with F per application).
// cg: the symmetrised system. A_i F_ij = A_j F_ji makes S = diag(A/rho) K symmetric, and S is
// strictly diagonally dominant with a positive diagonal (sum_j A_i F_ij <= A_i < A_i/rho_i),
// hence SPD. Patches with rho_i = 0 are handled exactly instead of refused: their row of K is
// e_i, so B_i = E_i is known; they are eliminated (their F columns move to the right-hand
// side) and kept as the decoupled rows A_i B_i = A_i E_i, so S stays SPD:
//   S x = [ A_u (x_u / rho_u - (F x_U)_u) ]_u in U,   [ A_z x_z ]_z in Z (rho = 0)
//   s   = [ A_u (E_u / rho_u + (F E_Z)_u) ]_u,        [ A_z E_z ]_z
// cg needs an exactly reciprocal F (symmetric S); with a non-reciprocal F it may stall, which
// the true-residual check reports as numerical-issue or max-iterations, never as converged.
//
// Preconditioners: none, diagonal (Jacobi: diag(K) = 1 - rho F_ii, nearly I for planar
// patches; for cg diag(S), which equilibrates the areas), ilut (bicgstab/gmres only: Eigen
// IncompleteLUT(droptol 1e-3, fill factor 1) of the assembled K of this channel; its
// factorisation time is part of the solve time).
//
// Stopping rule: Eigen iterates to its own residual estimate <= tol (BiCGSTAB: recurrence
// residual / ||E||; GMRES: preconditioned residual / initial one; CG: residual of S). The true
// ||E - K B|| / ||E|| is then computed; if still above tol, Eigen is resumed from B with a
// tolerance tightened by tol/true (at most kMaxRefinements times; then numerical-issue).
//
// History: Eigen exposes no per-iteration hook, but its solvers are deterministic, so the
// iterate after k iterations of the first run is replayed by rerunning with max k iterations
// (up to kHistoryPoints points, after the timing; replay products are not counted). Times at
// those points are interpolated as t_run * k / n (Krylov iterations have a fixed cost).
// GMRES(m) restarts every m iterations as in Eigen; an iteration is one inner step (1 product),
// a BiCGSTAB iteration costs 2 products, a CG iteration 1.

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <unsupported/Eigen/IterativeSolvers>

#include "solvers/system.hpp"

namespace lambert::detail {
class LinearOperator;
}  // namespace lambert::detail

namespace Eigen::internal {
template <>
struct traits<lambert::detail::LinearOperator>
    : public Eigen::internal::traits<Eigen::SparseMatrix<double>> {};
}  // namespace Eigen::internal

namespace lambert::detail {

/// A square operator y = op(x) given as a function, for Eigen's iterative solvers.
class LinearOperator : public Eigen::EigenBase<LinearOperator> {
 public:
  using Scalar = double;
  using RealScalar = double;
  using StorageIndex = int;
  enum {
    ColsAtCompileTime = Eigen::Dynamic,
    MaxColsAtCompileTime = Eigen::Dynamic,
    IsRowMajor = false
  };
  using Apply = std::function<void(const Eigen::VectorXd&, Eigen::VectorXd&)>;

  LinearOperator(Apply apply, Eigen::VectorXd diagonal)
      : apply_(std::move(apply)), diagonal_(std::move(diagonal)) {}
  Eigen::Index rows() const { return diagonal_.size(); }
  Eigen::Index cols() const { return diagonal_.size(); }
  /// Lazy product for Eigen's solvers.
  template <typename Rhs>
  Eigen::Product<LinearOperator, Rhs, Eigen::AliasFreeProduct> operator*(
      const Eigen::MatrixBase<Rhs>& x) const {
    return Eigen::Product<LinearOperator, Rhs, Eigen::AliasFreeProduct>(*this, x.derived());
  }
  /// y = op(x).
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const { apply_(x, y); }
  /// The operator's diagonal (for the Jacobi preconditioner).
  const Eigen::VectorXd& diagonal() const { return diagonal_; }

 private:
  Apply apply_;
  Eigen::VectorXd diagonal_;
};

/// none / diagonal / ilut behind one type, as Eigen's solvers take the preconditioner type.
class OperatorPreconditioner {
 public:
  enum class Kind { None, Diagonal, Ilut };
  OperatorPreconditioner() = default;
  /// Chooses the kind; for Ilut, factorises K (assembled by the caller).
  void setup(Kind kind, const SparseRowMatrix* k) {
    kind_ = kind;
    if (kind == Kind::Ilut) {
      ilut_ = std::make_shared<Eigen::IncompleteLUT<double, int>>();
      ilut_->setDroptol(1e-3);  // drops entries below 1e-3 of their row's norm
      ilut_->setFillfactor(1);  // at most the original row count per factor row
      ilut_->compute(Eigen::SparseMatrix<double, Eigen::ColMajor, int>(*k));
      info_ = ilut_->info();
    }
  }
  OperatorPreconditioner& analyzePattern(const LinearOperator&) { return *this; }
  OperatorPreconditioner& factorize(const LinearOperator& op) {
    inverse_diagonal_ = op.diagonal().cwiseInverse();
    return *this;
  }
  OperatorPreconditioner& compute(const LinearOperator& op) { return factorize(op); }
  /// z = M^-1 b.
  template <typename Rhs>
  Eigen::VectorXd solve(const Eigen::MatrixBase<Rhs>& b) const {
    switch (kind_) {
      case Kind::Diagonal:
        return inverse_diagonal_.cwiseProduct(b.derived());
      case Kind::Ilut:
        return ilut_->solve(b.derived());
      case Kind::None:
        break;
    }
    return b.derived();
  }
  Eigen::ComputationInfo info() const { return info_; }

 private:
  Kind kind_ = Kind::None;
  Eigen::VectorXd inverse_diagonal_;
  std::shared_ptr<Eigen::IncompleteLUT<double, int>> ilut_;
  Eigen::ComputationInfo info_ = Eigen::Success;
};

}  // namespace lambert::detail

namespace Eigen::internal {
template <typename Rhs>
struct generic_product_impl<lambert::detail::LinearOperator, Rhs, SparseShape, DenseShape,
                            GemvProduct>
    : generic_product_impl_base<lambert::detail::LinearOperator, Rhs,
                                generic_product_impl<lambert::detail::LinearOperator, Rhs>> {
  using Scalar = typename Product<lambert::detail::LinearOperator, Rhs>::Scalar;
  template <typename Dest>
  static void scaleAndAddTo(Dest& dst, const lambert::detail::LinearOperator& lhs, const Rhs& rhs,
                            const Scalar& alpha) {
    const Eigen::VectorXd x = rhs;
    Eigen::VectorXd y;
    lhs.apply(x, y);
    dst.noalias() += alpha * y;
  }
};
}  // namespace Eigen::internal

namespace lambert {
namespace {

using detail::LinearOperator;
using detail::OperatorPreconditioner;

// Replayed history points of the first run (bounded cost: at most this many reruns).
constexpr int kHistoryPoints = 48;
// Resumptions with a tightened inner tolerance before giving up (each gains >= 2x).
constexpr int kMaxRefinements = 8;

OperatorPreconditioner::Kind kind_of(const std::string& name) {
  if (name == "none") return OperatorPreconditioner::Kind::None;
  if (name == "ilut") return OperatorPreconditioner::Kind::Ilut;
  return OperatorPreconditioner::Kind::Diagonal;
}

std::vector<int> replay_points(int n) {
  std::vector<int> pts;
  for (int p = 1; p <= kHistoryPoints; ++p) {
    const int k = static_cast<int>(std::lround(static_cast<double>(n) * p / kHistoryPoints));
    if (k >= 1 && k < n && (pts.empty() || pts.back() != k)) pts.push_back(k);
  }
  return pts;
}

template <class Solver>
ChannelReport run_krylov(Solver& solver, const ChannelSystem& sys, const LinearOperator& op,
                         const Eigen::VectorXd& rhs, const SolveOptions& o, Eigen::VectorXd& B) {
  ChannelReport report;
  const Eigen::VectorXd guess = sys.E;
  B = guess;
  record(report, 0, sys.relative_residual_uncounted(B), 0.0);
  const Timer timer;
  std::unique_ptr<SparseRowMatrix> k;
  if (o.preconditioner == "ilut") k = std::make_unique<SparseRowMatrix>(assemble_k(sys));
  solver.preconditioner().setup(kind_of(o.preconditioner), k.get());
  k.reset();
  solver.compute(op);
  if (solver.preconditioner().info() != Eigen::Success) {
    report.status = SolveStatus::NumericalIssue;
    report.note = "preconditioner factorisation failed";
    report.residual = report.residual_history[0];
    report.seconds = timer.seconds();
    return report;
  }
  double inner_tol = o.tol;
  int total = 0, first_run = -1, refinements = 0;
  double first_seconds = 0.0;
  for (;;) {
    solver.setTolerance(inner_tol);
    solver.setMaxIterations(o.max_iterations - total);
    Eigen::VectorXd x = solver.solveWithGuess(rhs, B);
    B = x;
    total += static_cast<int>(solver.iterations());
    const double res = sys.relative_residual(B);
    if (first_run < 0) {
      first_run = total;
      first_seconds = timer.seconds();
    }
    record(report, total, res, timer.seconds());
    report.residual = res;
    if (res <= o.tol) {
      report.status = SolveStatus::Converged;
      break;
    }
    if (!std::isfinite(res) || solver.info() == Eigen::NumericalIssue) {
      report.status = SolveStatus::NumericalIssue;
      break;
    }
    if (total >= o.max_iterations) {
      report.status = SolveStatus::MaxIterations;
      break;
    }
    if (++refinements > kMaxRefinements) {
      report.status = SolveStatus::NumericalIssue;
      report.note = "inner solver converged but the true residual stalls above tol";
      break;
    }
    inner_tol *= std::min(0.5, o.tol / res);
  }
  report.iterations = total;
  report.seconds = timer.seconds();
  if (refinements > 0 && report.note.empty())
    report.note = std::to_string(refinements) + " resumption(s) with a tighter inner tolerance";

  if (o.record_history && first_run > 1) {
    const std::int64_t counted = sys.matvecs;
    ChannelReport replay;
    for (int kk : replay_points(first_run)) {
      solver.setTolerance(o.tol);
      solver.setMaxIterations(kk);
      const Eigen::VectorXd x = solver.solveWithGuess(rhs, guess);
      record(replay, static_cast<int>(solver.iterations()), sys.relative_residual_uncounted(x),
             first_seconds * static_cast<double>(solver.iterations()) / first_run);
    }
    sys.matvecs = counted;
    // Splice the replayed points between the guess (point 0) and the first run's end.
    auto at = [](auto& v) { return v.begin() + 1; };
    report.history_iteration.insert(at(report.history_iteration), replay.history_iteration.begin(),
                                    replay.history_iteration.end());
    report.residual_history.insert(at(report.residual_history), replay.residual_history.begin(),
                                   replay.residual_history.end());
    report.time_history.insert(at(report.time_history), replay.time_history.begin(),
                               replay.time_history.end());
  }
  return report;
}

LinearOperator k_operator(const ChannelSystem& sys) {
  return LinearOperator([&sys](const Eigen::VectorXd& x, Eigen::VectorXd& y) { sys.apply_k(x, y); },
                        1.0 - sys.rho.cwiseProduct(sys.f_diag).array());
}

}  // namespace

ChannelReport solve_bicgstab(const ChannelSystem& system, const SolveOptions& options,
                             Eigen::VectorXd& B) {
  const LinearOperator op = k_operator(system);
  Eigen::BiCGSTAB<LinearOperator, OperatorPreconditioner> solver;
  return run_krylov(solver, system, op, system.E, options, B);
}

ChannelReport solve_gmres(const ChannelSystem& system, const SolveOptions& options,
                          Eigen::VectorXd& B) {
  const LinearOperator op = k_operator(system);
  Eigen::GMRES<LinearOperator, OperatorPreconditioner> solver;
  solver.set_restart(options.restart);
  return run_krylov(solver, system, op, system.E, options, B);
}

ChannelReport solve_cg(const ChannelSystem& system, const SolveOptions& options,
                       Eigen::VectorXd& B) {
  const Eigen::VectorXd& a = system.area;
  const Eigen::VectorXd& rho = system.rho;
  const Eigen::ArrayXd known = (rho.array() == 0.0).cast<double>();  // 1 on Z (rho = 0)
  // a / rho on U; 0 on Z (never divides by zero).
  const Eigen::VectorXd a_over_rho = ((1.0 - known) * a.array() / (rho.array() + known)).matrix();
  Eigen::VectorXd diagonal =
      (a_over_rho.array() - (1.0 - known) * a.array() * system.f_diag.array() + known * a.array())
          .matrix();
  auto apply = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    const Eigen::VectorXd xu = ((1.0 - known) * x.array()).matrix();
    multiply_f(*system.F, xu, y, system.threads);
    ++system.matvecs;
    y = (a_over_rho.array() * x.array() - (1.0 - known) * a.array() * y.array() +
         known * a.array() * x.array())
            .matrix();
  };
  const LinearOperator op(apply, std::move(diagonal));
  Eigen::VectorXd fez;
  multiply_f(*system.F, (known * system.E.array()).matrix(), fez, system.threads);
  const Eigen::VectorXd rhs =
      (a_over_rho.array() * system.E.array() + (1.0 - known) * a.array() * fez.array() +
       known * a.array() * system.E.array())
          .matrix();
  Eigen::ConjugateGradient<LinearOperator, Eigen::Lower | Eigen::Upper, OperatorPreconditioner>
      solver;
  return run_krylov(solver, system, op, rhs, options, B);
}

}  // namespace lambert
