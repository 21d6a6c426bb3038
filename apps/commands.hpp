#pragma once
// One options struct, one registration function and one run function per subcommand.

#include <CLI/CLI.hpp>

#include "apps/common.hpp"
#include "apps/ff_args.hpp"

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

/// Options of `lambert formfactors`.
struct FormFactorsOptions {
  SceneArgs scene;
  RunArgs run;
  FormFactorArgs ff;
  std::string output;  ///< .mtx = Matrix Market, otherwise binary; JSON for --by-surface/--point
  std::string report;  ///< diagnostics JSON
  bool with_stderr = false;
  bool by_surface = false;
  std::vector<double> point, normal;  ///< sensor point and normal (3 each) or empty
};
/// Registers `formfactors` on the app.
CLI::App* add_formfactors_command(CLI::App& app, FormFactorsOptions& opts);
/// Computes F and writes it (or surface / sensor-point view factors) plus diagnostics.
int run_formfactors(const FormFactorsOptions& opts);

}  // namespace lambert
