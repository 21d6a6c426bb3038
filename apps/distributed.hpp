#pragma once
// `--distributed` (docs/cluster.md): formfactors and solve over MPI ranks, the
// solve in PETSc. Declared in every build. With LAMBERT_MPI, apps/distributed_loader.cpp
// defines them by loading the module lambert_distributed.so (apps/distributed.cpp and
// dist_*.cpp, the only files linked to MPI and PETSc; apps/distributed_entry.hpp) on first
// use; without it apps/distributed_stub.cpp refuses. No MPI type appears here.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

#include "io/json.hpp"
#include "pipeline/ff_stage.hpp"
#include "pipeline/job.hpp"
#include "pipeline/render_stages.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

struct FormFactorsOptions;
struct SolveCommandOptions;

/// --distributed and --petsc-options.
struct DistributedArgs {
  bool enabled = false;       ///< --distributed: this process is one rank of an MPI job
  std::string petsc_options;  ///< --petsc-options "-ksp_type bcgs ...": passed to PETSc
};

/// Adds --distributed (and, when `with_solver`, --petsc-options) to a subcommand.
void add_distributed_options(CLI::App* cmd, DistributedArgs& args, bool with_solver);

/// True when this lambert was built with LAMBERT_MPI.
bool distributed_available();

/// `formfactors --distributed`: every rank loads the scene and computes its share of the
/// pairs; rank 0 writes F (the same file as a single-process run) and the report.
int run_formfactors_distributed(const FormFactorsOptions& opts);

/// `solve --distributed` (method matrix): distributed form factors (or --ff, each rank
/// keeping its rows), the PETSc KSP solve per channel; rank 0 writes the CSV and summary.
int run_solve_distributed(const SolveCommandOptions& opts);

/// The matrix method over the ranks, for solve and run: `load` (every rank, in a collective
/// stage; `root` tells rank 0, which alone plans outputs) loads and meshes; then F (computed
/// over the ranks, or --ff), the PETSc solve and I = F (B - E); then `finish` on rank 0 alone
/// (a collective stage) with the whole B, I, the reports and the "distributed" section.
/// Returns the exit code on every rank (`finish`'s on rank 0; 0 or 3 by the status elsewhere).
int run_matrix_distributed(const DistributedArgs& dist, const RunArgs& run,
                           const FormFactorArgs& ff, const SolveOptions& solver,
                           const std::function<LoadedScene(const RunArgs& run, bool root)>& load,
                           const std::function<int(const LoadedScene&, const RadiosityResult&,
                                                   const Json& section)>& finish);

}  // namespace lambert
