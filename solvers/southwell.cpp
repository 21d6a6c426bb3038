// Southwell iteration = progressive refinement radiosity (Cohen, Chen, Wallace, Greenberg
// 1988), shooting form.
//
// State: B (shot radiosity, starts at 0) and the unshot radiosity r = E - K B (starts at E);
// r is exactly the residual. Each shot picks i maximising the unshot power |r_i| A_i, adds
// delta = r_i / K_ii to B_i, zeroes r_i and distributes it: r_j += rho_j F_ji delta for every
// patch j that i sees (j receives A_i F_ij delta / A_j = F_ji delta per unit area). F is stored
// by rows, so column i comes from row i by reciprocity, F_ji = A_i F_ij / A_j: no transposed
// copy of F is made (the loop below is visit_column_by_reciprocity, operator.hpp, written out
// so that each r_j keeps its historical rounding: rho_j F_ij (delta A_i) / A_j).
// The shooter: an indexed max-heap on |r_j| A_j (max_heap.hpp), updated for i and every j a
// shot touches, so the pick is the argmax scan's (first maximum: lowest index among ties)
// without scanning. Cost per shot: O(nnz of row i * log N).
//
// Reciprocity: when F is not exactly reciprocal (Monte Carlo estimates without
// --symmetrize), the shots solve the system of the reciprocal F' instead. The true residual
// ||E - K B|| is checked whenever the unshot residual reaches tol; if it is still above, r is
// reset to the true residual and shooting continues (iterative refinement with K' as
// approximate inverse: converges when ||K'^-1 (K - K')|| < 1, i.e. F close to reciprocal).
//
// Counting: one "iteration" is N shots (the work of one sweep); matvecs counts the F entries
// touched divided by nnz(F), plus the true-residual products. History: after every N shots.
// Ambient term (--ambient, for display only): the unshot power spread uniformly,
// B_display = B + r + rho * ambient, ambient = (sum r_i A_i / sum A) / (1 - rho_avg), added
// after the solve; residual and status refer to B before it.

#include <cmath>

#include "solvers/max_heap.hpp"
#include "solvers/system.hpp"

namespace lambert {

ChannelReport solve_southwell(const ChannelSystem& system, const SolveOptions& options,
                              Eigen::VectorXd& B) {
  ChannelReport report;
  const std::int32_t n = system.size();
  const TransportOperator& F = *system.F;
  const Eigen::VectorXd& a = system.area;
  const Eigen::VectorXd& rho = system.rho;
  const double tol_abs = options.tol * system.e_norm;
  // From B = 0 (r = E), or from a warm start's guess (r = E - K B).
  Eigen::VectorXd r = system.E;
  B = Eigen::VectorXd::Zero(n);
  if (system.warm) {
    B = system.guess;
    system.apply_k(B, r);
    r = system.E - r;
  }
  double sq = r.squaredNorm();  // ||r||^2, updated per shot, recomputed per sweep
  record(report, 0, std::sqrt(sq) / system.e_norm, 0.0);
  const Timer timer;
  IndexedMaxHeap unshot(r.cwiseAbs().cwiseProduct(a));  // unshot power |r_j| A_j
  std::int64_t touched = 0;   // F entries read by shots
  std::int64_t products = 0;  // true-residual products
  int refinements = 0;
  report.status = SolveStatus::MaxIterations;
  const std::int64_t max_shots = static_cast<std::int64_t>(options.max_iterations) * n;
  std::int64_t shot = 0;
  for (;;) {
    const bool sweep_end = shot > 0 && shot % n == 0;
    if (sweep_end || sq <= tol_abs * tol_abs || shot == max_shots) {
      sq = r.squaredNorm();  // drop accumulated rounding of the incremental update
      if (sweep_end)
        record(report, static_cast<int>(shot / n), std::sqrt(sq) / system.e_norm, timer.seconds());
      if (!std::isfinite(sq)) {
        report.status = SolveStatus::NumericalIssue;
        break;
      }
      if (sq <= tol_abs * tol_abs) {
        ++products;
        Eigen::VectorXd kb;
        F.apply(B, kb, system.threads);
        const Eigen::VectorXd truth = system.E - B + rho.cwiseProduct(kb);
        if (truth.norm() <= tol_abs) {
          report.status = SolveStatus::Converged;
          break;
        }
        // F is not reciprocal: continue from the true residual (see above).
        r = truth;
        sq = r.squaredNorm();
        unshot.reset(r.cwiseAbs().cwiseProduct(a));
        ++refinements;
      }
      if (shot >= max_shots) break;
    }
    // Shoot from the patch with the largest unshot power.
    const std::int32_t i = unshot.top();
    const double delta = r[i] / (1.0 - rho[i] * system.f_diag[i]);
    B[i] += delta;
    sq -= r[i] * r[i];
    r[i] = 0.0;
    unshot.update(i, 0.0);
    const double shoot = delta * a[i];
    // r_j += rho_j F_ji delta with F_ji = A_i F_ij / A_j (reciprocity).
    const TransportOperator::RowSpan row = F.row(i);
    for (std::int64_t k = 0; k < row.count; ++k) {
      const auto j = static_cast<std::int32_t>(row.cols[k]);
      if (j == i) continue;  // the self term is in K_ii above
      const double old = r[j];
      r[j] += rho[j] * row.values[k] * shoot / a[j];
      sq += r[j] * r[j] - old * old;
      unshot.update(j, std::abs(r[j]) * a[j]);
    }
    touched += row.count;
    ++shot;
  }
  report.iterations = static_cast<int>((shot + n - 1) / n);
  report.seconds = timer.seconds();
  const std::int64_t nnz = std::max<std::int64_t>(1, F.entries());
  system.matvecs += (touched + nnz - 1) / nnz + products;
  report.residual = system.relative_residual_uncounted(B);
  if (report.history_iteration.back() != report.iterations || shot % n != 0)
    record(report, report.iterations, report.residual, report.seconds);
  report.refinements = refinements;
  if (refinements > 0)
    report.note = std::to_string(refinements) + " refinement(s): F is not exactly reciprocal";
  if (options.ambient) {
    const double rho_avg = a.dot(rho) / a.sum();
    // A lossless scene (rho_avg = 1) has no ambient estimate of this form: none is added.
    const double ambient = rho_avg < 1.0 ? a.dot(r) / a.sum() / (1.0 - rho_avg) : 0.0;
    B += r + rho * ambient;
    report.note += std::string(report.note.empty() ? "" : "; ") + "ambient term added (" +
                   std::to_string(ambient) + ")";
  }
  return report;
}

}  // namespace lambert
