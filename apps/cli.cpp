#include "apps/cli.hpp"

#include <CLI/CLI.hpp>
#include <functional>
#include <iostream>
#include <vector>

#include "apps/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace lambert {

int run_cli(int argc, const char* const* argv) {
  CLI::App app{"lambert: radiosity and form factors for Lambertian scenes"};
  app.set_version_flag("--version", std::string("lambert ") + LAMBERT_VERSION);
  app.require_subcommand(1, 1);

  // Each entry: the subcommand and the function that runs it once parsed.
  std::vector<std::pair<CLI::App*, std::function<int()>>> commands;
  InfoOptions info;
  commands.emplace_back(add_info_command(app, info), [&] { return run_info(info); });
  RenderOptions render;
  commands.emplace_back(add_render_command(app, render), [&] { return run_render(render); });
  RunOptions run_opts;
  commands.emplace_back(add_run_command(app, run_opts), [&] { return run_run(run_opts); });
  SolveCommandOptions solve;
  commands.emplace_back(add_solve_command(app, solve), [&] { return run_solve(solve); });
  CompareOptions compare;
  commands.emplace_back(add_compare_command(app, compare), [&] { return run_compare(compare); });
  SolversOptions solvers;
  commands.emplace_back(add_solvers_command(app, solvers), [&] { return run_solvers(solvers); });
  FormFactorsOptions formfactors;
  commands.emplace_back(add_formfactors_command(app, formfactors),
                        [&] { return run_formfactors(formfactors); });
  HeatOptions heat;
  commands.emplace_back(add_heat_command(app, heat), [&] { return run_heat(heat); });
  AccuracyOptions accuracy;
  commands.emplace_back(add_accuracy_command(app, accuracy), [&] { return run_accuracy(accuracy); });
  OptionsOptions options;
  commands.emplace_back(add_options_command(app, options), [&] { return run_options(options); });

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "lambert: " << e.what() << " (see lambert --help)\n";
    return kExitUsage;
  }
  try {
    for (auto& [cmd, run] : commands)
      if (cmd->parsed()) {
        // A command's files are replaced as one set, when it ends (core/atomic_file.hpp).
        OutputSet outputs;
        const int code = run();
        outputs.commit();
        return code;
      }
    return kExitUsage;
  } catch (const UsageError& e) {
    std::cerr << "lambert: " << e.what() << '\n';
    return kExitUsage;
  } catch (const Error& e) {
    std::cerr << "lambert: " << e.what() << '\n';
    return kExitFailure;
  } catch (const std::bad_alloc&) {
    std::cerr << "lambert: out of memory\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "lambert: " << e.what() << '\n';
    return kExitFailure;
  }
}

}  // namespace lambert
