#pragma once
// The hierarchical method's stage, shared by `run`, `solve`, `render` and `compare`: solve a
// loaded scene with solve_hierarchical and present the leaf mesh as a LoadedScene (so the
// per-vertex, render and write stages run on it unchanged), plus its report pieces.

#include <Eigen/Core>
#include <string>

#include "geometry/hierarchical/hierarchical.hpp"
#include "io/json.hpp"
#include "pipeline/job.hpp"
#include "pipeline/method.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// A hierarchical solution: the leaves as a LoadedScene (its BVH, built on first use, is the
/// leaves'), their radiosity and what the solve did.
struct HierarchicalRun {
  LoadedScene loaded;           ///< the scene and the leaf mesh (max_edge 0: the mesh is adaptive)
  Eigen::MatrixX3d B;           ///< leaves x 3
  Eigen::VectorXd error_bound;  ///< per leaf (HierarchicalResult::error_bound)
  HierarchicalStats stats;
  HierarchicalOptions options;  ///< as used (min_area as requested; stats.min_area as used)
  double seconds = 0.0;         ///< wall time of solve_hierarchical
};

/// Solves `scene` hierarchically (taking it over) and logs a one-line summary on stderr, and
/// a warning when the sweeps did not meet the tolerance.
HierarchicalRun solve_scene_hierarchical(Scene scene, const HierarchicalOptions& options);

/// Converged when the last pass's sweeps met tol, otherwise MaxIterations.
SolveStatus hierarchical_status(const HierarchicalStats& stats);

/// {status, options {epsilon, min_area (requested; 0 = auto), link_rays, tol, max_iterations,
/// max_passes, seed, memory_limit}, faces, elements, clusters, leaves, links, cluster_links,
/// rays, passes, iterations, converged, change, memory_bytes, min_area (used), seconds
/// {build, refine, solve, total}, surface_error_bounds [{name, error_bound}]: per surface the
/// area-weighted mean of the leaves' one-bounce error bounds (W/m^2, brightest channel)}.
Json hierarchical_json(const HierarchicalRun& run);

/// One channel's power bookkeeping in energy_json's keys that apply: {emitted, absorbed,
/// escaped, relative_imbalance}.
Json hierarchical_energy_json(const HierarchicalEnergy& e);

/// One line of key=value text for image and PLY metadata: "method=hierarchical leaves=N
/// epsilon=E min_area=A link_rays=K tol=T seed=S".
std::string hierarchical_settings_text(const HierarchicalRun& run);

}  // namespace lambert
