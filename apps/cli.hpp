#pragma once
// The lambert command-line interface.

namespace lambert {

/// Exit codes of the CLI (docs/commands.md, "Exit codes").
enum ExitCode : int {
  kExitOk = 0,           ///< success (and --help / --version)
  kExitFailure = 1,      ///< runtime or input failure
  kExitUsage = 2,        ///< usage error
  kExitNotConverged = 3  ///< a solver did not converge (results still written)
};

/// Parses argv and runs one subcommand; returns the process exit code. Never throws.
int run_cli(int argc, const char* const* argv);

}  // namespace lambert
