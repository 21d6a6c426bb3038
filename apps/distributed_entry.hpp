#pragma once
// The boundary between lambert and its module lambert_distributed.so (LAMBERT_MPI builds).
// The module (apps/distributed.cpp, dist_mpi.cpp, dist_petsc.cpp) holds everything that links
// MPI and PETSc, about 100 shared libraries whose loading and relocation took 70 % of
// `lambert --version` (issue 36: start-up); apps/distributed_loader.cpp dlopens it the first
// time --distributed runs. The executable exports its symbols (ENABLE_EXPORTS), so the module
// binds to the executable's copy of the library: one log, one set of run settings.

#include <cstddef>

#include "apps/commands.hpp"
#include "apps/distributed.hpp"

namespace lambert {

/// What the module exports: the three runs of distributed.hpp. The module's C function
/// kDistributedEntrySymbol returns it.
struct DistributedEntry {
  std::size_t layout;  ///< kDistributedLayout of the module's build
  int (*formfactors)(const FormFactorsOptions& opts);
  int (*solve)(const SolveCommandOptions& opts);
  int (*matrix)(const DistributedArgs& dist, const RunArgs& run, const FormFactorArgs& ff,
                const SolveOptions& solver,
                const std::function<LoadedScene(const RunArgs& run, bool root)>& load,
                const std::function<int(const LoadedScene&, const RadiosityResult&,
                                        const Json& section)>& finish);
};

inline constexpr const char* kDistributedEntrySymbol = "lambert_distributed_entry";
inline constexpr const char* kDistributedModule = "lambert_distributed.so";

/// The sizes of what crosses the boundary, mixed: a module from another build (other struct
/// layouts) is refused instead of misread. Evaluated at compile time on each side.
inline constexpr std::size_t kDistributedLayout =
    ((((sizeof(FormFactorsOptions) * 1009 + sizeof(SolveCommandOptions)) * 1009 +
       sizeof(DistributedArgs)) *
          1009 +
      sizeof(RunArgs)) *
         1009 +
     sizeof(FormFactorArgs)) *
        1009 +
    sizeof(SolveOptions) * 31 + sizeof(LoadedScene) * 7 + sizeof(RadiosityResult);

}  // namespace lambert
