#include "solvers/system.hpp"

#include "core/error.hpp"

namespace lambert {

void ChannelSystem::apply_f(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  F->apply(x, y, threads);
  ++matvecs;
}

void ChannelSystem::apply_k(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  apply_f(x, y);
  y = x - rho.cwiseProduct(y);
}

double ChannelSystem::relative_residual_uncounted(const Eigen::VectorXd& B) const {
  Eigen::VectorXd fb;
  F->apply(B, fb, threads);
  const double r = (E - B + rho.cwiseProduct(fb)).norm();
  return e_norm > 0.0 ? r / e_norm : r;
}

double ChannelSystem::relative_residual(const Eigen::VectorXd& B) const {
  ++matvecs;
  return relative_residual_uncounted(B);
}

ChannelSystem make_channel_system(const RadiosityProblem& problem, int channel, int threads,
                                  const Eigen::MatrixX3d& initial_guess) {
  ChannelSystem s;
  s.F = problem.F.get();
  s.rho = problem.rho.col(channel);
  s.E = problem.emission.col(channel);
  const double e_max = s.E.cwiseAbs().maxCoeff();
  if (e_max > 0.0) {
    s.e_scale = e_max;
    s.E /= e_max;
  }
  s.warm = initial_guess.rows() == s.E.rows() && s.E.rows() > 0;
  s.guess = s.warm ? Eigen::VectorXd(initial_guess.col(channel) / s.e_scale) : s.E;
  s.area = problem.area;
  s.f_diag = problem.F->diagonal();
  s.e_norm = s.E.norm();
  s.threads = threads;
  return s;
}

std::string matrix_free_refusal(const std::string& who) {
  return who +
         " needs an assembled form-factor matrix; this transport operator is matrix-free: "
         "choose an iterative solver (and --preconditioner none or diagonal)";
}

SparseRowMatrix assemble_k(const ChannelSystem& system, const char* who) {
  const SparseRowMatrix* F = system.F->matrix();
  if (F == nullptr) throw UsageError(matrix_free_refusal(who));
  SparseRowMatrix K = -(system.rho.asDiagonal() * (*F));
  SparseRowMatrix I(system.size(), system.size());
  I.setIdentity();
  K += I;
  K.makeCompressed();
  return K;
}

void record_thinned(ChannelReport& report, int& stride, int iteration, double residual,
                    double seconds, bool force) {
  if (!force && iteration % stride != 0) return;
  if (static_cast<int>(report.history_iteration.size()) >= kMaxHistoryPoints) {
    // Keep point 0 and every other point after it; future points at twice the stride.
    auto thin = [](auto& v) {
      size_t out = 1;
      for (size_t k = 2; k < v.size(); k += 2) v[out++] = v[k];
      v.resize(out);
    };
    thin(report.history_iteration);
    thin(report.residual_history);
    thin(report.time_history);
    stride *= 2;
    if (!force && iteration % stride != 0) return;
  }
  record(report, iteration, residual, seconds);
}

}  // namespace lambert
