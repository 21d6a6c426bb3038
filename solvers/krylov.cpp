// Krylov solvers, written here and run through the transport operator (no Eigen solver
// objects: each loop records its own residual at every iteration).
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
// Methods (textbook forms, Saad, "Iterative Methods for Sparse Linear Systems", 2003):
//   cg:       preconditioned CG (Alg. 9.1) on S; 1 product per iteration.
//   bicgstab: right-preconditioned BiCGSTAB (van der Vorst 1992; Saad Alg. 7.7 with M^-1
//             applied to p and s); 2 products per iteration; when r0 . r collapses to
//             eps^2 ||r0||^2 the shadow residual is reset to the true residual (one product).
//             An iteration that converges at its half step (||s|| <= tol) stops there.
//   gmres:    right-preconditioned restarted GMRES(m) (Saad Alg. 9.5), modified Gram-Schmidt
//             Arnoldi, Givens rotations; 1 product per inner step (an "iteration"), plus one
//             per restart for the true residual it restarts from. Memory N (m + 1) doubles.
// Preconditioners: none, diagonal (Jacobi: diag(K) = 1 - rho F_ii, nearly I for planar
// patches; for cg diag(S), which equilibrates the areas), ilut (bicgstab/gmres only: Eigen
// IncompleteLUT(droptol 1e-3, fill factor 1) of the assembled K of this channel, so it needs
// the operator's matrix(); its factorisation time is part of the solve time).
//
// Residual history: every iteration's recurrence residual, measured in the one norm of the
// stopping rule, ||E - K B|| / ||E||: bicgstab's r and gmres's |g_{j+1}| (right
// preconditioning: both are K's own residual in exact arithmetic); cg's residual of S mapped
// back to K's, r_K = W r_S with W = rho/A on U and 1/A on Z (exact when B_Z = E_Z, which one
// diagonal-preconditioned step gives). Timestamps are the solve's clock when the point is
// taken. Thinned to at most kMaxHistoryPoints (record_thinned). At the end of each inner run
// the recorded point is replaced by the true residual.
//
// Stopping rule: a method iterates until its recurrence residual <= inner_tol (tol at first);
// the true ||E - K B|| / ||E|| then decides. If it is still above tol (the recurrence drifted
// from the truth, or F is not reciprocal for cg), the method restarts from B with inner_tol
// tightened by tol/true (at most kMaxRefinements times; then numerical-issue).

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>

#include "core/error.hpp"
#include "solvers/system.hpp"

namespace lambert {
namespace {

// Resumptions with a tightened inner tolerance before giving up (each gains >= 2x).
constexpr int kMaxRefinements = 8;

// The system a Krylov method iterates on, A x = b, and how its residual maps to K's.
struct KrylovSystem {
  std::function<void(const Eigen::VectorXd&, Eigen::VectorXd&)> apply;  ///< y = A x, counted
  Eigen::VectorXd b;
  Eigen::VectorXd diagonal;  ///< diag(A), for the Jacobi preconditioner
  Eigen::VectorXd k_weight;  ///< r_K = k_weight .* r_A; empty when A = K
  /// ||r_K||_2 of a residual r of A.
  double k_norm(const Eigen::VectorXd& r) const {
    return k_weight.size() == 0 ? r.norm() : k_weight.cwiseProduct(r).norm();
  }
};

// none / diagonal / ilut: z = M^-1 b.
class Preconditioner {
 public:
  enum class Kind { None, Diagonal, Ilut };
  // Returns false when the ILUT factorisation fails.
  bool setup(const std::string& name, const KrylovSystem& a, const ChannelSystem& sys) {
    kind_ = name == "none" ? Kind::None : name == "ilut" ? Kind::Ilut : Kind::Diagonal;
    if (kind_ == Kind::Diagonal) inverse_diagonal_ = a.diagonal.cwiseInverse();
    if (kind_ == Kind::Ilut) {
      // Eigen's IncompleteLUT works in 32-bit indices (its own factor storage and AMD
      // ordering), so K is handed over as a 32-bit column-major copy, whatever F's index.
      Eigen::SparseMatrix<double, Eigen::ColMajor, int> k32;
      {
        const SparseRowMatrix k = assemble_k(sys, "the ilut preconditioner");
        if (static_cast<std::int64_t>(k.nonZeros()) > std::numeric_limits<int>::max())
          throw UsageError("the ilut preconditioner supports at most 2^31 - 1 entries of K; "
                           "use --preconditioner diagonal");
        k32 = k;
      }
      ilut_ = std::make_unique<Eigen::IncompleteLUT<double, int>>();
      ilut_->setDroptol(1e-3);  // drops entries below 1e-3 of their row's norm
      ilut_->setFillfactor(1);  // at most the original row count per factor row
      ilut_->compute(k32);
      return ilut_->info() == Eigen::Success;
    }
    return true;
  }
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& z) const {
    switch (kind_) {
      case Kind::Diagonal:
        z = inverse_diagonal_.cwiseProduct(b);
        return;
      case Kind::Ilut:
        z = ilut_->solve(b);
        return;
      case Kind::None:
        break;
    }
    z = b;
  }

 private:
  Kind kind_ = Kind::None;
  Eigen::VectorXd inverse_diagonal_;
  std::unique_ptr<Eigen::IncompleteLUT<double, int>> ilut_;
};

// Iteration count, history and budget of one solve, shared by the inner runs.
struct Tracker {
  ChannelReport& report;
  const Timer& timer;
  double e_norm;
  int max_iterations;
  int total = 0;   // iterations so far
  int stride = 1;  // record_thinned's state
  bool budget_left() const { return total < max_iterations; }
  // One iteration done; `k_residual` is ||r_K||_2 of its recurrence residual.
  void step(double k_residual) {
    ++total;
    record_thinned(report, stride, total, k_residual / e_norm, timer.seconds());
  }
};

// Outcome of an inner run: converged by its own estimate, out of budget, or broken down.
enum class Inner { Converged, Budget, Breakdown };

// Preconditioned CG on SPD A. Stops when ||W r||_2 <= tol_abs.
Inner run_cg(const KrylovSystem& a, const Preconditioner& m, double tol_abs, Eigen::VectorXd& x,
             Tracker& t) {
  Eigen::VectorXd r, z, q;
  a.apply(x, q);
  r = a.b - q;
  if (a.k_norm(r) <= tol_abs) return Inner::Converged;
  m.solve(r, z);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  while (t.budget_left()) {
    a.apply(p, q);
    const double pq = p.dot(q);
    if (!(pq > 0.0)) return Inner::Breakdown;  // A not SPD (or NaN)
    const double alpha = rz / pq;
    x += alpha * p;
    r -= alpha * q;
    const double res = a.k_norm(r);
    t.step(res);
    if (res <= tol_abs) return Inner::Converged;
    m.solve(r, z);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
  }
  return Inner::Budget;
}

// Right-preconditioned BiCGSTAB. Stops when ||r||_2 <= tol_abs.
Inner run_bicgstab(const KrylovSystem& a, const Preconditioner& m, double tol_abs,
                   Eigen::VectorXd& x, Tracker& t) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd r, v = Eigen::VectorXd::Zero(n), p = Eigen::VectorXd::Zero(n), y, z, s, tt;
  a.apply(x, tt);
  r = a.b - tt;
  Eigen::VectorXd r0 = r;
  double r0_sq = r0.squaredNorm();
  double rho = 1.0, alpha = 1.0, omega = 1.0;
  const double eps2 = std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon();
  double res = r.norm();
  if (res <= tol_abs) return Inner::Converged;
  while (t.budget_left()) {
    const double rho_old = rho;
    rho = r0.dot(r);
    if (std::abs(rho) < eps2 * r0_sq) {
      // The shadow residual became orthogonal to r: restart it from the true residual.
      a.apply(x, tt);
      r = a.b - tt;
      r0 = r;
      rho = r0_sq = r.squaredNorm();
      v.setZero();
      p.setZero();
      alpha = omega = 1.0;
      if (r0_sq == 0.0) return Inner::Converged;
    }
    const double beta = (rho / rho_old) * (alpha / omega);
    p = r + beta * (p - omega * v);
    m.solve(p, y);
    a.apply(y, v);
    const double r0v = r0.dot(v);
    if (!(std::abs(r0v) > 0.0) || !std::isfinite(r0v)) return Inner::Breakdown;
    alpha = rho / r0v;
    s = r - alpha * v;
    if (s.norm() <= tol_abs) {  // converged at the half step
      x += alpha * y;
      t.step(s.norm());
      return Inner::Converged;
    }
    m.solve(s, z);
    a.apply(z, tt);
    const double tt_sq = tt.squaredNorm();
    omega = tt_sq > 0.0 ? tt.dot(s) / tt_sq : 0.0;
    x += alpha * y + omega * z;
    r = s - omega * tt;
    res = r.norm();
    t.step(res);
    if (!std::isfinite(res)) return Inner::Breakdown;
    if (res <= tol_abs) return Inner::Converged;
    if (omega == 0.0) return Inner::Breakdown;
  }
  return Inner::Budget;
}

// Right-preconditioned GMRES(m). Stops when the least-squares residual |g_{j+1}| <= tol_abs.
Inner run_gmres(const KrylovSystem& a, const Preconditioner& m, int restart, double tol_abs,
                Eigen::VectorXd& x, Tracker& t) {
  const Eigen::Index n = x.size();
  Eigen::MatrixXd V(n, restart + 1);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(restart + 1, restart);
  Eigen::VectorXd g(restart + 1), cs(restart), sn(restart), w, z, ax;
  while (t.budget_left()) {
    a.apply(x, ax);
    w = a.b - ax;
    const double beta = w.norm();
    if (!std::isfinite(beta)) return Inner::Breakdown;
    if (beta <= tol_abs) return Inner::Converged;
    V.col(0) = w / beta;
    g.setZero();
    g[0] = beta;
    H.setZero();
    int k = 0;  // Arnoldi vectors used in this cycle
    bool done = false;
    while (k < restart && t.budget_left()) {
      const int j = k;
      m.solve(V.col(j), z);
      a.apply(z, w);
      for (int i = 0; i <= j; ++i) {  // modified Gram-Schmidt
        H(i, j) = w.dot(V.col(i));
        w -= H(i, j) * V.col(i);
      }
      H(j + 1, j) = w.norm();
      const bool happy = !(H(j + 1, j) > 0.0);  // exact solution in the subspace
      if (!happy) V.col(j + 1) = w / H(j + 1, j);
      for (int i = 0; i < j; ++i) {  // previous rotations on the new column
        const double h = cs[i] * H(i, j) + sn[i] * H(i + 1, j);
        H(i + 1, j) = -sn[i] * H(i, j) + cs[i] * H(i + 1, j);
        H(i, j) = h;
      }
      const double rr = std::hypot(H(j, j), H(j + 1, j));
      cs[j] = rr > 0.0 ? H(j, j) / rr : 1.0;
      sn[j] = rr > 0.0 ? H(j + 1, j) / rr : 0.0;
      H(j, j) = rr;
      H(j + 1, j) = 0.0;
      g[j + 1] = -sn[j] * g[j];
      g[j] = cs[j] * g[j];
      ++k;
      const double res = std::abs(g[j + 1]);
      t.step(res);
      if (!std::isfinite(res)) return Inner::Breakdown;
      if (res <= tol_abs || happy) {
        done = true;
        break;
      }
    }
    if (k > 0) {
      // x += M^-1 V_k y with H_k y = g_k (upper triangular after the rotations).
      const Eigen::VectorXd yk =
          H.topLeftCorner(k, k).triangularView<Eigen::Upper>().solve(g.head(k));
      const Eigen::VectorXd update = V.leftCols(k) * yk;
      m.solve(update, z);
      x += z;
    }
    if (done) return Inner::Converged;
  }
  return Inner::Budget;
}

using InnerMethod = std::function<Inner(const KrylovSystem&, const Preconditioner&, double,
                                        Eigen::VectorXd&, Tracker&)>;

// The shared driver: guess B = E (or the warm start), preconditioner setup, inner runs until the true residual
// meets tol (see the header comment).
ChannelReport run_krylov(const ChannelSystem& sys, const KrylovSystem& a, const SolveOptions& o,
                         const InnerMethod& method, Eigen::VectorXd& B) {
  ChannelReport report;
  B = sys.guess;
  record(report, 0, sys.relative_residual_uncounted(B), 0.0);
  const Timer timer;
  Preconditioner m;
  if (!m.setup(o.preconditioner, a, sys)) {
    report.status = SolveStatus::NumericalIssue;
    report.note = "preconditioner factorisation failed";
    report.residual = report.residual_history[0];
    report.seconds = timer.seconds();
    return report;
  }
  Tracker t{report, timer, sys.e_norm, o.max_iterations};
  double inner_tol = o.tol;
  int refinements = 0;
  for (;;) {
    const Inner outcome = method(a, m, inner_tol * sys.e_norm, B, t);
    const double res = sys.relative_residual(B);
    // The run's last point becomes the true residual.
    if (report.history_iteration.back() == t.total) {
      report.residual_history.back() = res;
      report.time_history.back() = timer.seconds();
    } else {
      record_thinned(report, t.stride, t.total, res, timer.seconds(), true);
    }
    report.residual = res;
    if (res <= o.tol) {
      report.status = SolveStatus::Converged;
      break;
    }
    if (!std::isfinite(res) || outcome == Inner::Breakdown) {
      report.status = SolveStatus::NumericalIssue;
      break;
    }
    if (!t.budget_left()) {
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
  report.iterations = t.total;
  report.seconds = timer.seconds();
  if (refinements > 0 && report.note.empty())
    report.note = std::to_string(refinements) + " resumption(s) with a tighter inner tolerance";
  return report;
}

KrylovSystem k_system(const ChannelSystem& sys) {
  KrylovSystem a;
  a.apply = [&sys](const Eigen::VectorXd& x, Eigen::VectorXd& y) { sys.apply_k(x, y); };
  a.b = sys.E;
  a.diagonal = 1.0 - sys.rho.cwiseProduct(sys.f_diag).array();
  return a;
}

}  // namespace

ChannelReport solve_bicgstab(const ChannelSystem& system, const SolveOptions& options,
                             Eigen::VectorXd& B) {
  return run_krylov(system, k_system(system), options, run_bicgstab, B);
}

ChannelReport solve_gmres(const ChannelSystem& system, const SolveOptions& options,
                          Eigen::VectorXd& B) {
  const int restart = options.restart;
  return run_krylov(
      system, k_system(system), options,
      [restart](const KrylovSystem& a, const Preconditioner& m, double tol_abs, Eigen::VectorXd& x,
                Tracker& t) { return run_gmres(a, m, restart, tol_abs, x, t); },
      B);
}

ChannelReport solve_cg(const ChannelSystem& system, const SolveOptions& options,
                       Eigen::VectorXd& B) {
  const Eigen::VectorXd& a = system.area;
  const Eigen::VectorXd& rho = system.rho;
  const Eigen::ArrayXd known = (rho.array() == 0.0).cast<double>();  // 1 on Z (rho = 0)
  // a / rho on U; 0 on Z (never divides by zero).
  const Eigen::VectorXd a_over_rho = ((1.0 - known) * a.array() / (rho.array() + known)).matrix();
  KrylovSystem s;
  s.diagonal =
      (a_over_rho.array() - (1.0 - known) * a.array() * system.f_diag.array() + known * a.array())
          .matrix();
  s.apply = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    const Eigen::VectorXd xu = ((1.0 - known) * x.array()).matrix();
    system.apply_f(xu, y);
    y = (a_over_rho.array() * x.array() - (1.0 - known) * a.array() * y.array() +
         known * a.array() * x.array())
            .matrix();
  };
  Eigen::VectorXd fez;
  system.F->apply((known * system.E.array()).matrix(), fez, system.threads);
  s.b = (a_over_rho.array() * system.E.array() + (1.0 - known) * a.array() * fez.array() +
         known * a.array() * system.E.array())
            .matrix();
  // r_K = W r_S: on U, K's row is S's divided by A/rho; on Z, by A.
  s.k_weight = ((1.0 - known) * rho.array() / a.array() + known / a.array()).matrix();
  return run_krylov(system, s, options, run_cg, B);
}

}  // namespace lambert
