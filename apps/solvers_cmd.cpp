#include <cstdio>

#include "apps/commands.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

CLI::App* add_solvers_command(CLI::App& app, SolversOptions& opts) {
  auto* cmd = app.add_subcommand("solvers", "List the radiosity solvers");
  add_run_options(cmd, opts.run);
  return cmd;
}

int run_solvers(const SolversOptions& opts) {
  apply_run_options(opts.run);
  for (const auto& s : solver_registry())
    std::printf("%-14s %s\n", s.name.c_str(), s.description.c_str());
  return 0;
}

}  // namespace lambert
