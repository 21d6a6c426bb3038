// --distributed in a LAMBERT_MPI build: the runs live in the module lambert_distributed.so
// beside the executable (apps/distributed_entry.hpp says why), loaded on first use.
#include <dlfcn.h>

#include <filesystem>
#include <string>

#include "apps/distributed_entry.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

// The module beside the running executable (build/bin, or wherever bin/ was copied).
std::string module_path() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw Error("--distributed: cannot find the running executable (/proc/self/exe)");
  return (exe.parent_path() / kDistributedModule).string();
}

// Loaded once, never unloaded (MPI and PETSc finalise at exit). RTLD_GLOBAL: OpenMPI's own
// plugins look up libmpi's symbols in the global scope.
const DistributedEntry& module() {
  static const DistributedEntry* entry = [] {
    const std::string path = module_path();
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_GLOBAL);
    // dlerror() names the file and why.
    if (!handle) throw Error(std::string("--distributed needs its module: ") + dlerror());
    using EntryFn = const DistributedEntry* (*)();
    auto fn = reinterpret_cast<EntryFn>(dlsym(handle, kDistributedEntrySymbol));
    if (!fn) throw Error(path + ": not a lambert module (no " + kDistributedEntrySymbol + ")");
    const DistributedEntry* e = fn();
    if (e->layout != kDistributedLayout)
      throw Error(path + ": built from another version of lambert (rebuild it with this one)");
    return e;
  }();
  return *entry;
}

}  // namespace

bool distributed_available() { return true; }

int run_formfactors_distributed(const FormFactorsOptions& opts) {
  return module().formfactors(opts);
}

int run_solve_distributed(const SolveCommandOptions& opts) { return module().solve(opts); }

int run_matrix_distributed(
    const DistributedArgs& dist, const RunArgs& run, const FormFactorArgs& ff,
    const SolveOptions& solver, const std::function<LoadedScene(const RunArgs&, bool)>& load,
    const std::function<int(const LoadedScene&, const RadiosityResult&, const Json&)>& finish) {
  return module().matrix(dist, run, ff, solver, load, finish);
}

}  // namespace lambert
