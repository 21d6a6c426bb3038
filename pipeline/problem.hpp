#pragma once
// The radiosity problem of a meshed scene: per-patch rho, E and area next to a shared F,
// and per-surface summaries of a solution.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/mesh/mesh.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// RadiosityProblem for `mesh` with a CsrOperator over F (which must outlive it). Throws SceneError
/// if F's size does not match the mesh.
RadiosityProblem make_problem(const PatchMesh& mesh, const SparseRowMatrix& F);
/// The problem over the patches and M extra unknowns after them (participating-media zones,
/// geometry/formfactors/media.hpp): F is (N + M)², and the extra unknowns' reflectance,
/// emission (M x 3) and effective area (M) follow the patches'. F must outlive the problem.
/// Throws SceneError when the sizes do not match.
RadiosityProblem make_extended_problem(const PatchMesh& mesh, const SparseRowMatrix& F,
                                       const Eigen::MatrixX3d& extra_rho,
                                       const Eigen::MatrixX3d& extra_emission,
                                       const Eigen::VectorXd& extra_area);
/// The same over a FormFactors (its specular_continued goes with it: the energy balance of
/// extended form factors).
RadiosityProblem make_problem(const PatchMesh& mesh, const FormFactors& ff);

/// The indirect irradiance of every patch, I_i = Σ_j F_ij (B_j - E_j) (N x 3, W/m²): the
/// light arriving after at least one reflection, for exact_direct_vertex_field
/// (geometry/render/vertex_field.hpp). One sparse product, O(nnz).
Eigen::MatrixX3d indirect_irradiance(const PatchMesh& mesh, const SparseRowMatrix& F,
                                     const Eigen::MatrixX3d& B);

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
