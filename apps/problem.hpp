#pragma once
// The radiosity problem of a meshed scene: per-patch rho, E and area next to a shared F,
// and per-surface summaries of a solution.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geometry/mesh.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// RadiosityProblem for `mesh` with a CsrOperator over F (which must outlive it). Throws SceneError if
/// F's size does not match the mesh.
RadiosityProblem make_problem(const PatchMesh& mesh, const SparseRowMatrix& F);

/// Area-weighted average radiosity of each surface: sum_i A_i B_i / sum_i A_i over its patches.
struct SurfaceRadiosity {
  std::string name;
  double area = 0.0;
  int patches = 0;
  Eigen::Vector3d average = Eigen::Vector3d::Zero();
};
/// Per-surface averages of B (surfaces without patches are listed with zero area).
std::vector<SurfaceRadiosity> surface_averages(const PatchMesh& mesh, const Eigen::MatrixX3d& B);

}  // namespace lambert
