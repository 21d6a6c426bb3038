#pragma once
// One options struct, one registration function and one run function per subcommand.

#include <CLI/CLI.hpp>

#include "apps/common.hpp"

namespace lambert {

/// Options of `lambert info`.
struct InfoOptions {
  SceneArgs scene;
  RunArgs run;
};
/// Registers `info` on the app.
CLI::App* add_info_command(CLI::App& app, InfoOptions& opts);
/// Prints surfaces, materials, emitters, area, bounds and patch statistics.
int run_info(const InfoOptions& opts);

}  // namespace lambert
