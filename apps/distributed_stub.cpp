// --distributed in a build without LAMBERT_MPI: refused with the way to get it.
#include "apps/commands.hpp"
#include "apps/distributed.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

[[noreturn]] void refuse() {
  throw UsageError(
      "--distributed needs a lambert built with MPI and PETSc (scripts/setup.sh "
      "mpi, then mpirun -np K build-mpi/bin/lambert ...; docs/cluster.md \"Running on a "
      "cluster\")");
}

}  // namespace

bool distributed_available() { return false; }
int run_formfactors_distributed(const FormFactorsOptions&) { refuse(); }
int run_solve_distributed(const SolveCommandOptions&) { refuse(); }
int run_matrix_distributed(
    const DistributedArgs&, const RunArgs&, const FormFactorArgs&, const SolveOptions&,
    const std::function<LoadedScene(const RunArgs&, bool)>&,
    const std::function<int(const LoadedScene&, const RadiosityResult&, const Json&)>&) {
  refuse();
}

}  // namespace lambert
