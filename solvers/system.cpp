#include "solvers/system.hpp"

#include <algorithm>

#include "core/parallel.hpp"

namespace lambert {

void multiply_f(const SparseRowMatrix& F, const Eigen::VectorXd& x, Eigen::VectorXd& y,
                int threads) {
  const std::int32_t n = static_cast<std::int32_t>(F.rows());
  y.resize(n);
  const double* values = F.valuePtr();
  const auto* inner = F.innerIndexPtr();
  const auto* outer = F.outerIndexPtr();
  const double* xs = x.data();
  double* ys = y.data();
  auto rows = [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      double s = 0.0;
      for (auto k = outer[i]; k < outer[i + 1]; ++k) s += values[k] * xs[inner[k]];
      ys[i] = s;
    }
  };
  // Threads only pay off when there is enough work per product (thread start ~50 us).
  constexpr std::int64_t kMinNonZerosPerThread = 1 << 18;
  const int workers = resolve_threads(threads);
  if (workers <= 1 || F.nonZeros() < kMinNonZerosPerThread * 2) {
    rows(0, n);
  } else {
    parallel_for(n, std::max<std::int64_t>(64, n / (8 * workers)), workers, rows);
  }
}

void ChannelSystem::apply_k(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  multiply_f(*F, x, y, threads);
  ++matvecs;
  y = x - rho.cwiseProduct(y);
}

double ChannelSystem::relative_residual_uncounted(const Eigen::VectorXd& B) const {
  Eigen::VectorXd fb;
  multiply_f(*F, B, fb, threads);
  const double r = (E - B + rho.cwiseProduct(fb)).norm();
  return e_norm > 0.0 ? r / e_norm : r;
}

double ChannelSystem::relative_residual(const Eigen::VectorXd& B) const {
  ++matvecs;
  return relative_residual_uncounted(B);
}

ChannelSystem make_channel_system(const RadiosityProblem& problem, int channel, int threads) {
  ChannelSystem s;
  s.F = problem.F;
  s.rho = problem.rho.col(channel);
  s.E = problem.emission.col(channel);
  const double e_max = s.E.cwiseAbs().maxCoeff();
  if (e_max > 0.0) {
    s.e_scale = e_max;
    s.E /= e_max;
  }
  s.area = problem.area;
  s.f_diag = problem.F->diagonal();
  s.e_norm = s.E.norm();
  s.threads = threads;
  return s;
}

SparseRowMatrix assemble_k(const ChannelSystem& system) {
  SparseRowMatrix K = -(system.rho.asDiagonal() * (*system.F));
  SparseRowMatrix I(system.size(), system.size());
  I.setIdentity();
  K += I;
  K.makeCompressed();
  return K;
}

}  // namespace lambert
