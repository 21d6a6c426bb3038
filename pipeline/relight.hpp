#pragma once
// Relighting: the solution split by light source (the .glb's COLOR_k, pipeline/viewer_stage.hpp;
// docs/viewer.md).
//
// Linearity. (I − ρF) B = E is linear in E, so with E = Σ_k E_k (E_k: one emitting surface's
// emission, the sky's or the sun's reflected first bounce, zero elsewhere) the solution is
// B = Σ_k B_k with (I − ρF) B_k = E_k, and any mix of intensities w_k has the solution
// Σ_k w_k B_k: once the bases B_k are solved, relighting is a weighted sum per vertex. The
// per-vertex values are a linear map of the patch values too when the same per-surface
// rescale is used for every basis: the area-weighted mean (with hanging vertices anchored)
// is linear, and the conservative rescale s (per surface and channel) is taken from the
// solution B and applied unchanged to each B_k, so Σ_k vertex(B_k) = vertex(B) whenever
// Σ_k B_k = B.
//
// Accuracy. Each basis is solved with the solution's solver at tolerance
// min(tol, kBasisTolerance) (relative residual); the error of Σ_k B_k against B is then that
// of B itself (|δB| / |B| ≲ cond(I − ρF) · tol, cond ≤ (1 + ρ_max) / (1 − ρ_max): 1.9e-7
// for ρ_max = 0.9 at the default tol 1e-8) and is measured and reported
// (linearity_error, max over vertices and channels of |Σ_k v_k − v| / max |v|).
//
// Bases: one per emitting surface (by its power Σ A_i E_i, largest first), the sky, the sun;
// beyond kMaxEmitterBases the smallest surfaces share one basis ("other emitters"), so the
// viewer's shader stays within WebGL's 16 vertex attributes. A scene with one source needs no
// extra solve (its basis is B).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pipeline/daylight_stage.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// At most this many bases (COLOR_1 … COLOR_12 beside COLOR_0 and POSITION: 14 of WebGL 2's
/// 16 vertex attributes).
constexpr int kMaxEmitterBases = 12;
/// The bases' solver tolerance when the solution's is looser.
constexpr double kBasisTolerance = 1e-10;
/// How closely the bases' vertex values must sum to the solution's (relative to its largest):
/// the solution's own error at the default tol 1e-8 is ≲ cond · tol ≤ 1.9e-7 (ρ_max = 0.9,
/// above) plus float32 rounding of the stored values (6e-8 each, summed over ≤ 13 of them:
/// 8e-7 in the worst case, ~2e-7 typically); 1e-6 holds at the default and flags a loose --tol.
constexpr double kLinearityTolerance = 1e-6;

/// One light source and the solution for it alone.
struct EmitterBasis {
  std::string name;  ///< the surface's name, "sky", "sun" or "other emitters"
  std::string kind;  ///< "surface", "surfaces" (several sharing a basis), "sky" or "sun"
  std::vector<std::string> surfaces;  ///< the emitting surfaces it holds (kind surface/s)
  Eigen::MatrixX3d E;                 ///< its part of E (N x 3)
  Eigen::MatrixX3d B;                 ///< the solution for E alone (N x 3)
  Eigen::Vector3d power = Eigen::Vector3d::Zero();  ///< Σ_i A_i E_i per channel
};

/// The problem's E split into its sources (above; E of the surfaces from the mesh, the sky's
/// and the sun's parts from `daylight`), B not yet solved. Empty when nothing emits.
std::vector<EmitterBasis> emitter_sources(const PatchMesh& mesh, const DaylightSources& daylight);

/// Solves every basis of `bases` over `problem` (its E replaced by each basis's E) with
/// `options` at tolerance min(options.tol, kBasisTolerance); a single basis takes `B` as it is.
/// Returns the bases' solve time (s). Throws what solve_radiosity throws.
double solve_emitter_bases(const RadiosityProblem& problem, const Eigen::MatrixX3d& B,
                           SolveOptions options, std::vector<EmitterBasis>& bases);

}  // namespace lambert
