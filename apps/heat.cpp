// `lambert heat`: gray-diffuse radiative exchange (solvers/thermal.hpp) on a meshed scene with
// per-surface conditions from a JSON file (io/heat_surfaces.hpp); CSV, JSON, vertex EXR, PLY,
// VTU and a colour-mapped image.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "apps/heat_outputs.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/analysis.hpp"
#include "io/heat_surfaces.hpp"
#include "io/json.hpp"
#include "pipeline/heat_problem.hpp"
#include "pipeline/solve_stage.hpp"
#include "solvers/gebhart.hpp"
#include "solvers/thermal.hpp"

namespace lambert {

CLI::App* add_heat_command(CLI::App& app, HeatOptions& opts) {
  auto* cmd = app.add_subcommand(
      "heat", "Gray-diffuse radiative heat exchange: temperatures, net fluxes and powers");
  opts.scene.default_patches = 2000;
  opts.scene.load.warn_without_emitter = false;  // heat's sources are temperatures
  add_scene_options(cmd, opts.scene);
  add_ff_options(cmd, opts.ff);
  add_solve_options(cmd, opts.solve, true);
  add_declared(cmd, "--surfaces", opts.surfaces)->required();
  add_declared(cmd, "--ambient-temperature", opts.ambient_temperature);
  add_declared(cmd, "--length-unit", opts.length_unit);
  add_declared(cmd, "-o,--output", opts.output);
  add_declared(cmd, "--patches-csv", opts.patches_csv);
  add_declared(cmd, "--conductors", opts.conductors);
  add_heat_output_options(cmd, opts.images);
  add_run_options(cmd, opts.run);
  return cmd;
}

namespace {

// Writes the tables, the conductors, the images and the summary of `paths` that are asked
// for; returns the files written, in order.
std::vector<std::string> write_heat_outputs(const HeatPaths& paths, HeatReport& report,
                                            const Timer& total) {
  std::vector<std::string> written;
  if (!paths.surfaces_csv.empty()) {
    write_heat_surfaces_csv(paths.surfaces_csv, report);
    written.push_back(paths.surfaces_csv);
  }
  if (!paths.vtu.empty()) {
    write_heat_vtu(paths.vtu, report);
    written.push_back(paths.vtu);
  }
  if (!paths.patches_csv.empty()) {
    write_heat_patches_csv(paths.patches_csv, report);
    written.push_back(paths.patches_csv);
  }
  if (!paths.conductors_csv.empty()) {
    write_heat_conductors_csv(paths.conductors_csv, report);
    written.push_back(paths.conductors_csv);
  }
  const std::vector<std::string> images = write_heat_images(report);
  written.insert(written.end(), images.begin(), images.end());
  report.timings.total_seconds = total.seconds();
  if (!paths.json.empty()) {
    write_json_file(paths.json, heat_json(report));
    written.push_back(paths.json);
  }
  return written;
}

// The exit code of the solves: 3 (with a warning) when the exchange or a conductor solve did
// not converge.
int heat_exit_code(const std::string& solver, const ThermalSolution& sol,
                   const std::optional<RadiativeConductors>& conductors) {
  SolveStatus status = sol.radiosity.status;
  if (status == SolveStatus::Converged && conductors) status = conductors->status;
  if (status == SolveStatus::Converged) return kExitOk;
  log_warn("solver " + solver + " did not converge (" + to_string(status) +
           "); results were written anyway");
  return kExitNotConverged;
}

}  // namespace

int run_heat(const HeatOptions& opts) {
  check_options_read(opts.run,
                     {"heat", "matrix", selected_estimator(opts.ff), {opts.solve.solver}, ""});
  if (opts.solve.ambient)
    throw UsageError(
        "--ambient (southwell's display term) does not apply to heat: it would "
        "change J; --ambient-temperature sets the environment");
  check_heat_output_options(opts.images, opts.run.given);
  const Timer total;
  const HeatPaths paths = heat_paths(opts);
  JobPlan plan = job_plan(opts.run);
  plan.inputs.push_back({"--surfaces", opts.surfaces});
  add_heat_paths_to_plan(plan, paths);
  add_heat_outputs_to_plan(plan, opts.images);
  plan_form_factors(plan, opts.ff, opts.run);
  plan.direct = opts.solve.solver == "direct";
  const SurfaceConditions conditions = read_surface_conditions(opts.surfaces);
  LoadedScene loaded = load_scene(opts.scene, plan);
  const std::vector<SurfaceCondition> cond =
      resolve_surface_conditions(conditions, loaded.mesh.surface_names);
  const double load_seconds = total.seconds();

  const Timer ff_timer;
  const FormFactors ff = obtain_form_factors(loaded, opts.ff, opts.run);
  const double ff_seconds = ff_timer.seconds();
  const ThermalProblem problem = make_heat_problem(
      loaded.mesh, cond, ff.F, metres_per_unit(opts.length_unit), opts.ambient_temperature);
  refuse_floating_enclosure(loaded.mesh, problem, ff, opts.surfaces);

  SolveOptions so = opts.solve;
  so.threads = opts.run.threads;
  set_memory_limit(so, opts.run.max_memory);
  const ThermalSolution sol = solve_thermal(problem, so);
  std::vector<std::int32_t> surface_of(loaded.mesh.size());
  for (std::int32_t i = 0; i < loaded.mesh.size(); ++i)
    surface_of[i] = loaded.mesh.patches[i].surface;
  const auto n_surfaces = static_cast<std::int32_t>(loaded.mesh.surface_names.size());
  const auto surfaces = surface_heat(sol, problem.area, surface_of, n_surfaces);
  if (sol.undefined_temperatures > 0)
    log_warn(std::to_string(sol.undefined_temperatures) +
             " known-flux patch(es) are asked to lose more than they can radiate at 0 K "
             "(J - (1 - e) H < 0): their temperature is reported as null");
  std::optional<RadiativeConductors> conductors;
  if (!opts.conductors.empty())
    conductors = radiative_conductors(problem, surface_of, n_surfaces, so);

  HeatReport report{&loaded, &problem, &sol, &surfaces, &cond, &ff, &opts, nullptr, {}};
  if (conductors) report.conductors = &*conductors;
  report.timings = {load_seconds, ff_seconds, sol.radiosity.seconds, 0.0};
  const std::vector<std::string> written = write_heat_outputs(paths, report, total);
  print_heat_table(report);
  for (const auto& f : written) std::printf("wrote %s\n", f.c_str());
  return heat_exit_code(so.solver, sol, conductors);
}

}  // namespace lambert
