#pragma once
// Gebhart absorption factors and radiative conductors between groups of patches (surfaces):
// the grey-body exchange matrix GR_ST = Σ_{k∈S} ε_k A_k 𝓑_kT that thermal network tools
// (ESATAN, SINDA, Modelica) take. Sees F (a transport operator), vectors and areas only.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "solvers/thermal.hpp"

namespace lambert {

/// Radiative conductors between groups of patches, in m² (multiply by σ(T_S⁴ − T_T⁴) for W).
struct RadiativeConductors {
  Eigen::MatrixXd GR;  ///< groups x groups: GR_ST = Σ_{k∈S} ε_k A_k 𝓑_kT (m²), diagonal included
  /// GR_S,env = Σ_k A_k (1 − Σ_j F_kj) J_k^(S): what escapes to the environment (m²); with
  /// the matrix row Σ_T GR_ST + GR_S,env = ε_S A_S (every emitted watt ends somewhere).
  Eigen::VectorXd environment;
  Eigen::VectorXd emittance;  ///< ε_S A_S per group (m²): the row sums of a closed enclosure
  SolveStatus status = SolveStatus::Converged;  ///< worst over the solves
  int solves = 0;                               ///< radiosity solves (three groups each)
  double residual = 0.0;                        ///< largest relative residual of a channel
  double seconds = 0.0;
};

/// The conductors of `problem`'s patches grouped by `group[i]` in [0, groups), independent of
/// the boundary conditions (every patch is a network node with ρ = 1 − ε).
///
/// Gebhart factor 𝓑_kj: the fraction of patch k's emission absorbed by patch j, directly and
/// after diffuse reflections, 𝓑 = (I − Fρ)⁻¹ F ε. Computed per emitting group S (three per
/// solve, one per colour channel): J^(S) solves (I − ρF) J = ε 1_S (S emits at σT⁴ = 1, all
/// else at 0 K), then H = F J and GR_ST = Σ_{j∈T} ε_j A_j H_j: the power S sends to T per unit
/// σT_S⁴. For a reciprocal F, GR is symmetric and Q_S = Σ_T GR_ST σ(T_S⁴ − T_T⁴) +
/// GR_S,env σ(T_S⁴ − T_amb⁴) for isothermal surfaces. Accuracy: the solver's tolerance on
/// each J^(S) (relative to ‖ε 1_S‖) and F's error. Cost: ⌈groups/3⌉ solves plus one product
/// per group. Throws UsageError for sizes that disagree or a group out of range.
RadiativeConductors radiative_conductors(const ThermalProblem& problem,
                                         const std::vector<std::int32_t>& group,
                                         std::int32_t groups, const SolveOptions& options);

}  // namespace lambert
