#pragma once
// `--distributed` (README "Running on a cluster"): formfactors and solve over MPI ranks, the
// solve in PETSc. Declared in every build; defined by apps/distributed.cpp when built with
// LAMBERT_MPI, else by apps/distributed_stub.cpp, which refuses. No MPI type appears here.

#include <CLI/CLI.hpp>
#include <string>

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

}  // namespace lambert
