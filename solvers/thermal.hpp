#pragma once
// Gray-diffuse radiative heat exchange between patches (net-radiation method): radiosities J
// from known temperatures or known net fluxes, solved as a radiosity system through the
// existing solvers, then per-patch net flux, temperature and power, and the environment's
// share. Sees F (a transport operator), vectors and areas only, like every solver.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "solvers/radiosity.hpp"

namespace lambert {

/// Stefan–Boltzmann constant σ, W m⁻² K⁻⁴ (CODATA 2018, exact to the digits given).
constexpr double kStefanBoltzmann = 5.670374419e-8;

/// What a patch's boundary condition fixes.
enum class ThermalBoundary { Temperature, HeatFlux };

/// The exchange problem: per patch a gray-diffuse emissivity ε and either its temperature T
/// (kelvin) or its net radiative heat flux q (W/m², leaving the surface as radiation: the
/// power per area that must be supplied to it; 0 = re-radiating/adiabatic). Areas in m², so
/// that Q = A q is in watts. The environment (whatever a patch does not see, 1 − Σ_j F_ij) is
/// a black body at `ambient_temperature` (0 K: escaping radiation is simply lost).
struct ThermalProblem {
  std::shared_ptr<const TransportOperator> F;  ///< N x N view factors (dimensionless)
  Eigen::VectorXd area;                        ///< m² per patch
  Eigen::VectorXd emissivity;                  ///< in [0, 1]; > 0 on HeatFlux patches
  std::vector<ThermalBoundary> boundary;       ///< per patch
  Eigen::VectorXd value;                       ///< T (K, >= 0) or q (W/m²) per patch
  double ambient_temperature = 0.0;            ///< K
};

/// The solution, per patch (W/m² and W; T in K).
struct ThermalSolution {
  Eigen::VectorXd J;  ///< radiosity (W/m²): emitted + reflected
  Eigen::VectorXd H;  ///< irradiance (W/m²): Σ_j F_ij J_j + (1 − Σ_j F_ij) σ T_amb⁴
  Eigen::VectorXd q;  ///< net flux J − H (W/m²)
  Eigen::VectorXd Q;  ///< net power A q (W)
  Eigen::VectorXd T;  ///< temperature (K): given, or from J and H; NaN where undefined
  /// Net power the environment sends in (W): Σ_i A_i (1 − Σ_j F_ij)(σ T_amb⁴ − J_i). With a
  /// reciprocal F, Σ_i Q_i = −environment_power identically (`closure` measures it).
  double environment_power = 0.0;
  double closure = 0.0;            ///< Σ_i Q_i + environment_power (W): 0 up to rounding
                                   ///< and F's non-reciprocity
  double max_flux_mismatch = 0.0;  ///< max over HeatFlux patches of |q_i − q_given| (W/m²):
                                   ///< the solver residual seen in the boundary condition
  std::int32_t undefined_temperatures = 0;  ///< HeatFlux patches whose q admits no T ≥ 0
  RadiositySolution radiosity;              ///< the solver's report (channel 0 carries the system)
};

/// The radiosity system of the problem (channel 0; channels 1 and 2 emit nothing and are
/// solved trivially): on a Temperature patch J − (1 − ε) Σ F J = ε σ T⁴, on a HeatFlux patch
/// J − Σ F J = q, and the environment adds ρ_i (1 − Σ_j F_ij) σ T_amb⁴ to E_i (ρ = 1 − ε,
/// resp. 1). E may be negative (q < 0 removes heat), so `signed_emission` is set. Throws
/// UsageError for out-of-range ε, T or sizes.
RadiosityProblem make_thermal_system(const ThermalProblem& problem);

/// Solves the exchange with `options` (any solver of the registry; with ρ = 1 rows every
/// solver still converges as long as the system is nonsingular: some patch absorbs (ε > 0 on
/// a Temperature patch) or the scene is open, which the caller checks on F). Then
/// q = J − H, and on HeatFlux patches T = ((J − (1 − ε) H) / (ε σ))^¼ (NaN, counted, when
/// that is negative: the requested q cannot be). O(solver + nnz).
ThermalSolution solve_thermal(const ThermalProblem& problem, const SolveOptions& options);

/// Totals of one surface (a set of patches).
struct SurfaceHeat {
  double area = 0.0;  ///< m²
  std::int32_t patches = 0;
  double Q = 0.0;                   ///< net power Σ A_i q_i (W)
  double q = 0.0;                   ///< Q / area (W/m²)
  double J = 0.0;                   ///< area-weighted mean radiosity (W/m²)
  double T = 0.0;                   ///< area-weighted mean temperature (K; NaN if any patch's is)
  double T_min = 0.0, T_max = 0.0;  ///< extremes over its patches (K)
};

/// Sums the solution per surface: `surface[i]` is patch i's surface in [0, surfaces).
std::vector<SurfaceHeat> surface_heat(const ThermalSolution& sol, const Eigen::VectorXd& area,
                                      const std::vector<std::int32_t>& surface,
                                      std::int32_t surfaces);

}  // namespace lambert
