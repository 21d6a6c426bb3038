#include "solvers/thermal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace lambert {
namespace {

double sigma_t4(double T) { return kStefanBoltzmann * (T * T) * (T * T); }

void validate_thermal(const ThermalProblem& p) {
  if (p.F == nullptr) throw UsageError("thermal problem without view factors");
  const Eigen::Index n = p.area.size();
  if (p.F->size() != n || p.emissivity.size() != n || p.value.size() != n ||
      static_cast<Eigen::Index>(p.boundary.size()) != n)
    throw UsageError("thermal problem sizes disagree");
  if (!(p.ambient_temperature >= 0.0) || !std::isfinite(p.ambient_temperature))
    throw UsageError("ambient temperature must be finite and >= 0 K");
  for (Eigen::Index i = 0; i < n; ++i) {
    const double e = p.emissivity[i];
    if (!(e >= 0.0 && e <= 1.0))
      throw UsageError("patch " + std::to_string(i) + ": emissivity must be in [0, 1]");
    if (!std::isfinite(p.value[i]))
      throw UsageError("patch " + std::to_string(i) + ": non-finite boundary value");
    if (p.boundary[i] == ThermalBoundary::Temperature && p.value[i] < 0.0)
      throw UsageError("patch " + std::to_string(i) + ": temperature must be >= 0 K");
    if (p.boundary[i] == ThermalBoundary::HeatFlux && !(e > 0.0))
      throw UsageError("patch " + std::to_string(i) + ": a known-flux patch needs emissivity > 0");
  }
}

}  // namespace

RadiosityProblem make_thermal_system(const ThermalProblem& p) {
  validate_thermal(p);
  const Eigen::Index n = p.area.size();
  const Eigen::VectorXd escape = (1.0 - p.F->row_sums().array()).matrix();
  const double ambient = sigma_t4(p.ambient_temperature);
  RadiosityProblem r;
  r.F = p.F;
  r.area = p.area;
  r.rho = Eigen::MatrixX3d::Zero(n, 3);
  r.emission = Eigen::MatrixX3d::Zero(n, 3);
  r.signed_emission = true;
  for (Eigen::Index i = 0; i < n; ++i) {
    const bool known_t = p.boundary[i] == ThermalBoundary::Temperature;
    const double rho = known_t ? 1.0 - p.emissivity[i] : 1.0;
    r.rho.row(i).setConstant(rho);
    const double source = known_t ? p.emissivity[i] * sigma_t4(p.value[i]) : p.value[i];
    r.emission(i, 0) = source + rho * escape[i] * ambient;
  }
  return r;
}

ThermalSolution solve_thermal(const ThermalProblem& p, const SolveOptions& options) {
  const RadiosityProblem system = make_thermal_system(p);
  ThermalSolution s;
  s.radiosity = solve_radiosity(system, options);
  const Eigen::Index n = p.area.size();
  s.J = s.radiosity.B.col(0);
  const Eigen::VectorXd escape = (1.0 - p.F->row_sums().array()).matrix();
  const double ambient = sigma_t4(p.ambient_temperature);
  p.F->apply(s.J, s.H, options.threads);
  s.H += escape * ambient;
  s.q = s.J - s.H;
  s.Q = p.area.cwiseProduct(s.q);
  s.T.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (p.boundary[i] == ThermalBoundary::Temperature) {
      s.T[i] = p.value[i];
      continue;
    }
    const double e = p.emissivity[i];
    s.max_flux_mismatch = std::max(s.max_flux_mismatch, std::abs(s.q[i] - p.value[i]));
    const double emitted = (s.J[i] - (1.0 - e) * s.H[i]) / (e * kStefanBoltzmann);
    // Overflow (a flux of 1e308, an emissivity of 1e-320 under e sigma) is no temperature:
    // an error, never T = inf in the outputs (issue 33).
    if (std::isinf(emitted) || (std::isnan(emitted) && !std::isfinite(s.J[i])))
      throw Error("patch " + std::to_string(i) + " (emissivity " + std::to_string(e) +
                  ", heat flux " + std::to_string(p.value[i]) +
                  " W/m^2): its temperature overflows double precision (sigma T^4 = " +
                  std::to_string(emitted) + "); check the surface conditions");
    if (emitted >= 0.0) {
      s.T[i] = std::sqrt(std::sqrt(emitted));
    } else {
      s.T[i] = std::numeric_limits<double>::quiet_NaN();
      ++s.undefined_temperatures;
    }
  }
  s.environment_power =
      p.area.cwiseProduct(escape).dot((Eigen::VectorXd::Constant(n, ambient) - s.J));
  s.closure = s.Q.sum() + s.environment_power;
  return s;
}

std::vector<SurfaceHeat> surface_heat(const ThermalSolution& sol, const Eigen::VectorXd& area,
                                      const std::vector<std::int32_t>& surface,
                                      std::int32_t surfaces) {
  LAMBERT_CHECK(
      static_cast<Eigen::Index>(surface.size()) == area.size() && sol.q.size() == area.size(),
      "patch surfaces and solution differ in size");
  std::vector<SurfaceHeat> out(surfaces);
  for (auto& s : out) {
    s.T_min = std::numeric_limits<double>::infinity();
    s.T_max = -std::numeric_limits<double>::infinity();
  }
  for (Eigen::Index i = 0; i < area.size(); ++i) {
    SurfaceHeat& s = out.at(surface[i]);
    s.area += area[i];
    ++s.patches;
    s.Q += sol.Q[i];
    s.J += area[i] * sol.J[i];
    s.T += area[i] * sol.T[i];
    s.T_min = std::min(s.T_min, sol.T[i]);
    s.T_max = std::max(s.T_max, sol.T[i]);
    if (std::isnan(sol.T[i])) s.T_min = s.T_max = sol.T[i];
  }
  for (auto& s : out) {
    if (s.area <= 0.0) continue;
    s.q = s.Q / s.area;
    s.J /= s.area;
    s.T /= s.area;
  }
  return out;
}

}  // namespace lambert
