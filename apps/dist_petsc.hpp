#pragma once
// The radiosity solve in PETSc (LAMBERT_MPI builds only; no PETSc type in this header).

#include <cstdint>
#include <string>
#include <vector>

#include "apps/dist_mpi.hpp"
#include "solvers/radiosity.hpp"

namespace lambert::dist {

/// A distributed solve: the solution on every rank (B whole, the reports, the global
/// energy balance) and what its products sent.
struct PetscSolve {
  RadiositySolution solution;
  /// Columns of F this rank's rows read from other ranks: each product K x receives that
  /// many values (8 bytes each); summed over the ranks.
  std::int64_t ghost_columns = 0;
  std::string ksp_type, pc_type;  ///< what PETSc ran (after --petsc-options)
};

/// Solves K_c B_c = E_c, K_c = I - diag(rho_c) F, per channel with a PETSc KSP over a
/// MATMPIAIJ whose rows are `block`'s (rows [block.begin, block.end) on this rank).
/// `problem` holds rho, E and area of every patch (its F is not read). Defaults: GMRES
/// (restart options.restart) with Jacobi (the single-process "diagonal"; block Jacobi's
/// ILU(0) costs O(nnz x row length) on F's dense-ish rows: 100 s per channel at 10^4
/// patches), right-preconditioned so that PETSc's residual is the true one; -ksp_*/-pc_* options
/// from --petsc-options or PETSC_OPTIONS override them. Stopping rule as everywhere: ||E - K B||_2
/// / ||E||_2 <= options.tol, checked on the true residual after the KSP, which is rerun from its
/// result with a tighter tolerance while it is not met (report.refinements). The energy balance is
/// energy_balance's over each rank's rows, summed. Collective.
PetscSolve solve_petsc(const RadiosityProblem& problem, const RowBlock& block,
                       const SolveOptions& options);

}  // namespace lambert::dist
