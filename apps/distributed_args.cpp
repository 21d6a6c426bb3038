// --distributed and --petsc-options (every build; without MPI the runs refuse).
#include "apps/distributed.hpp"

namespace lambert {

void add_distributed_options(CLI::App* cmd, DistributedArgs& args, bool with_solver) {
  CLI::Option* distributed = cmd->add_flag(
      "--distributed", args.enabled,
      std::string("Run as one rank of an MPI job (mpirun -np K lambert ...): F's rows "
                  "split over the ranks") +
          (with_solver ? ", solved with PETSc" : "") +
          (distributed_available() ? "" : " (needs the mpi build: docs/cluster.md)"));
  if (with_solver)
    cmd->add_option("--petsc-options", args.petsc_options,
                    "With --distributed: PETSc options for the solve, e.g. \"-ksp_type bcgs "
                    "-pc_type jacobi\" (default GMRES with Jacobi)")
        ->needs(distributed);  // read by the PETSc solve only: refused without it
}

}  // namespace lambert
