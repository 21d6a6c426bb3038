// --distributed in a build without LAMBERT_MPI: refused with the way to get it.
#include "apps/commands.hpp"
#include "apps/distributed.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

[[noreturn]] void refuse() {
  throw UsageError(
      "--distributed needs a lambert built with MPI and PETSc (scripts/setup.sh "
      "mpi, then mpirun -np K build-mpi/bin/lambert ...; README \"Running on a "
      "cluster\")");
}

}  // namespace

bool distributed_available() { return false; }
int run_formfactors_distributed(const FormFactorsOptions&) { refuse(); }
int run_solve_distributed(const SolveCommandOptions&) { refuse(); }

}  // namespace lambert
