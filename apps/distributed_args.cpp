// --distributed and --petsc-options (every build; without MPI the runs refuse).
#include "apps/distributed.hpp"
#include "apps/options.hpp"

namespace lambert {

void add_distributed_options(CLI::App* cmd, DistributedArgs& args, bool with_solver) {
  CLI::Option* distributed = add_declared(cmd, "--distributed", args.enabled);
  if (with_solver)  // read by the PETSc solve only: refused without --distributed
    add_declared(cmd, "--petsc-options", args.petsc_options)->needs(distributed);
}

}  // namespace lambert
