#include "solvers/gebhart.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "core/timer.hpp"

namespace lambert {
namespace {

// The system of groups first .. first + 2 emitting at σT⁴ = 1, one per channel, every patch
// with ρ = 1 − ε (a node of the network, whatever its boundary condition).
RadiosityProblem emitting_groups(const ThermalProblem& p, const std::vector<std::int32_t>& group,
                                 std::int32_t first) {
  const Eigen::Index n = p.area.size();
  RadiosityProblem r;
  r.F = p.F;
  r.area = p.area;
  r.rho = Eigen::MatrixX3d::Zero(n, 3);
  r.emission = Eigen::MatrixX3d::Zero(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    r.rho.row(i).setConstant(1.0 - p.emissivity[i]);
    const std::int32_t c = group[i] - first;
    if (c >= 0 && c < 3) r.emission(i, c) = p.emissivity[i];
  }
  return r;
}

void validate(const ThermalProblem& p, const std::vector<std::int32_t>& group,
              std::int32_t groups) {
  if (p.F == nullptr || p.F->size() != p.area.size() || p.emissivity.size() != p.area.size() ||
      static_cast<Eigen::Index>(group.size()) != p.area.size())
    throw UsageError("radiative conductors: sizes disagree");
  for (const auto g : group)
    if (g < 0 || g >= groups) throw UsageError("radiative conductors: group out of range");
  for (Eigen::Index i = 0; i < p.emissivity.size(); ++i)
    if (!(p.emissivity[i] >= 0.0 && p.emissivity[i] <= 1.0))
      throw UsageError("patch " + std::to_string(i) + ": emissivity must be in [0, 1]");
}

}  // namespace

RadiativeConductors radiative_conductors(const ThermalProblem& p,
                                         const std::vector<std::int32_t>& group,
                                         std::int32_t groups, const SolveOptions& options) {
  validate(p, group, groups);
  const Timer timer;
  const Eigen::Index n = p.area.size();
  const Eigen::VectorXd escape = (1.0 - p.F->row_sums().array()).matrix();
  const Eigen::VectorXd absorbing = p.emissivity.cwiseProduct(p.area);  // ε_j A_j
  RadiativeConductors out;
  out.GR = Eigen::MatrixXd::Zero(groups, groups);
  out.environment = Eigen::VectorXd::Zero(groups);
  out.emittance = Eigen::VectorXd::Zero(groups);
  for (Eigen::Index i = 0; i < n; ++i) out.emittance[group[i]] += absorbing[i];
  SolveOptions so = options;
  so.initial_guess.resize(0, 3);
  for (std::int32_t first = 0; first < groups; first += 3) {
    const RadiosityProblem system = emitting_groups(p, group, first);
    const RadiositySolution sol = solve_radiosity(system, so);
    ++out.solves;
    if (sol.status != SolveStatus::Converged && out.status == SolveStatus::Converged)
      out.status = sol.status;
    for (int c = 0; c < 3 && first + c < groups; ++c) {
      out.residual = std::max(out.residual, sol.channels[c].residual);
      const Eigen::VectorXd J = sol.B.col(c);
      Eigen::VectorXd H;
      p.F->apply(J, H, options.threads);
      for (Eigen::Index j = 0; j < n; ++j) out.GR(first + c, group[j]) += absorbing[j] * H[j];
      out.environment[first + c] = p.area.cwiseProduct(escape).dot(J);
    }
  }
  out.seconds = timer.seconds();
  return out;
}

}  // namespace lambert
