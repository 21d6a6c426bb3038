#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <utility>

#include "apps/cli.hpp"
#include "apps/command_outputs.hpp"
#include "apps/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/json.hpp"
#include "pipeline/hierarchical_stage.hpp"
#include "pipeline/problem.hpp"
#include "pipeline/solve_stage.hpp"

namespace lambert {
namespace {

// B.csv -> B.json, another name gets .json appended; none beside a device such as /dev/null.
std::string summary_path(const std::string& csv) { return summary_beside(csv); }

// Writes the summary unless -o is a device (no path); prints what was written.
void write_summary(const std::string& csv, const std::string& json_path, const Json& j) {
  if (json_path.empty()) {
    std::printf("wrote %s\n", csv.c_str());
    return;
  }
  write_json_file(json_path, j);
  std::printf("wrote %s and %s\n", csv.c_str(), json_path.c_str());
}

void write_radiosity_csv(const std::string& path, const PatchMesh& mesh,
                         const Eigen::MatrixX3d& B) {
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "patch,surface,area,R,G,B\n";
    for (std::int32_t i = 0; i < mesh.size(); ++i) {
      const Patch& p = mesh.patches[i];
      out << i << ',' << csv_field(mesh.surface_names.at(p.surface)) << ',' << csv_number(p.area)
          << ',' << csv_number(B(i, 0)) << ',' << csv_number(B(i, 1)) << ',' << csv_number(B(i, 2))
          << '\n';
    }
  });
}

Json channel_json(const ChannelReport& r, const EnergyBalance& e, int c) {
  Json j = {{"channel", channel_name(c)},  {"status", to_string(r.status)},
            {"iterations", r.iterations},  {"matvecs", r.matvecs},
            {"residual", r.residual},      {"seconds", r.seconds},
            {"refinements", r.refinements}};
  if (!r.note.empty()) j["note"] = r.note;
  j["energy"] = energy_json(e);
  j["history"] = {{"iteration", r.history_iteration},
                  {"seconds", r.time_history},
                  {"residual", r.residual_history}};
  return j;
}

// --method matrix: mesh, F, one solver.
int run_solve_matrix(const SolveCommandOptions& opts) {
  const std::shared_ptr<const Medium> medium = make_medium(opts.medium);
  if (medium && opts.adapt.active())
    throw UsageError("--adapt does not combine with a participating medium yet");
  const Timer total;
  JobPlan plan = job_plan(opts.run);
  plan.outputs = {{"-o", opts.output}, {"the summary", summary_path(opts.output)}};
  plan_form_factors(plan, opts.ff, opts.run);
  plan.medium = medium.get();
  plan.medium_rays = opts.medium.rays;
  plan.direct = opts.solve.solver == "direct";
  LoadedScene loaded = load_scene(opts.scene, plan);
  const double load_seconds = total.seconds();
  const Timer ff_timer;
  SolveOptions so = opts.solve;
  so.threads = opts.run.threads;
  set_memory_limit(so, opts.run.max_memory);
  FormFactors ff;
  RadiositySolution sol;
  std::vector<AdaptRound> rounds;
  double ff_seconds = 0.0;
  std::optional<MediumResult> medium_result;
  std::int64_t nonzeros = 0;
  DaylightSources daylight;
  if (medium) {
    check_medium_scene(loaded.mesh, nullptr);
    ff = obtain_form_factors(loaded, opts.ff, opts.run, false, medium.get());
    RadiosityResult r;
    medium_result = solve_scene_with_medium(loaded, ff, medium, opts.medium, so, opts.run, r);
    ff_seconds = ff_timer.seconds() - r.solve_seconds;
    sol = r.solution;  // patches, then zones: the CSV and the averages read the patches
    nonzeros = medium_result->entries;
  } else if (opts.adapt.active()) {
    rounds = adapt_scene(loaded, opts.ff, so, opts.run, opts.adapt, ff, sol);
    daylight = daylight_sources(loaded, ff, opts.run.seed, opts.run.threads);
    ff_seconds = ff_timer.seconds() - sol.seconds;
    warn_about_lighting(loaded.mesh, ff.F);
  } else {
    ff = obtain_form_factors(loaded, opts.ff, opts.run);
    ff_seconds = ff_timer.seconds();
    const RadiosityProblem problem =
        make_lit_problem(loaded, ff, opts.run.seed, opts.run.threads, &daylight);
    warn_about_lighting(loaded.mesh, ff.F);
    check_closed_lossless(loaded.mesh, ff);
    sol = solve_radiosity(problem, so);
    warn_about_non_reciprocity(sol, ff.options);
  }
  if (!medium) nonzeros = ff.F.nonZeros();
  MatrixSolveResult result;
  result.options = so;
  result.solution = std::move(sol);
  result.ff_options = ff.options;
  result.load_seconds = load_seconds;
  result.ff_seconds = ff_seconds;
  result.nonzeros = nonzeros;
  result.medium = std::move(medium_result);
  result.rounds = std::move(rounds);
  result.daylight = std::move(daylight);
  return write_solve_outputs(opts, loaded, result);
}

// --method hierarchical: load (no meshing), solve hierarchically; the leaves are the patches.
int run_solve_hierarchical(const SolveCommandOptions& opts) {
  const Timer total;
  JobPlan plan = job_plan(opts.run);
  const std::string json_path = summary_path(opts.output);
  plan.outputs = {{"-o", opts.output}, {"the summary", json_path}};
  Scene scene = load_checked_scene(opts.scene, plan);
  const double load_seconds = total.seconds();
  const HierarchicalRun h = solve_scene_hierarchical(
      std::move(scene), make_hierarchical_options(opts.method, opts.method.hierarchical.epsilon,
                                                  opts.solve, opts.run));
  const HierarchicalStats& st = h.stats;
  const SolveStatus status = hierarchical_status(st);
  write_radiosity_csv(opts.output, h.loaded.mesh, h.B);
  Json j = {{"scene", h.loaded.scene.source},
            {"method", "hierarchical"},
            {"patches", h.loaded.mesh.size()},
            {"status", to_string(status)},
            {"iterations", st.iterations},
            {"change", st.change},
            {"timings",
             {{"load_seconds", load_seconds},
              {"build_seconds", st.build_seconds},
              {"refine_seconds", st.refine_seconds},
              {"solve_seconds", st.solve_seconds}}},
            {"hierarchical", hierarchical_json(h)}};
  Json& channels = j["channels"] = Json::array();
  for (int c = 0; c < 3; ++c)
    channels.push_back({{"channel", channel_name(c)},
                        {"status", to_string(status)},
                        {"energy", hierarchical_energy_json(st.energy[c])}});
  j["surfaces"] = surface_averages_json(surface_averages(h.loaded.mesh, h.B));

  std::printf(
      "method hierarchical: %s; %lld leaves, %lld links, %d passes, %d sweeps (change "
      "%.3e)\n",
      to_string(status), static_cast<long long>(st.leaves), static_cast<long long>(st.links),
      st.passes, st.iterations, st.change);
  for (int c = 0; c < 3; ++c) {
    const HierarchicalEnergy& e = st.energy[c];
    std::printf("  %s: energy emitted %.6g absorbed %.6g escaped %.6g (imbalance %.2e)\n",
                channel_name(c), e.emitted, e.absorbed, e.escaped, e.relative_imbalance);
  }
  write_summary(opts.output, json_path, j);
  if (status != SolveStatus::Converged) {
    log_warn(std::string("hierarchical status ") + to_string(status) +
             ": results were written anyway");
    return kExitNotConverged;
  }
  return kExitOk;
}

}  // namespace

int write_solve_outputs(const SolveCommandOptions& opts, const LoadedScene& loaded,
                        const MatrixSolveResult& r) {
  const SolveOptions& so = r.options;
  const RadiositySolution& sol = r.solution;
  const std::optional<MediumResult>& medium_result = r.medium;
  const std::string json_path = summary_path(opts.output);
  write_radiosity_csv(opts.output, loaded.mesh, sol.B);
  const auto surfaces = surface_averages(loaded.mesh, sol.B);
  int iterations = 0;
  double residual = 0.0;
  for (const auto& cr : sol.channels) {
    iterations = std::max(iterations, cr.iterations);
    residual = std::max(residual, cr.residual);
  }
  Json j = {{"scene", loaded.scene.source},
            {"method", "matrix"},
            {"patches", loaded.mesh.size()},
            {"solver", so.solver},
            {"status", to_string(sol.status)},
            {"options",
             {{"tol", so.tol},
              {"max_iterations", so.max_iterations},
              {"omega", so.omega},
              {"preconditioner", so.preconditioner},
              {"restart", so.restart},
              {"ambient", so.ambient}}},
            {"iterations", iterations},
            {"residual", residual},
            {"timings",
             {{"load_and_mesh_seconds", r.load_seconds},
              {"form_factors_seconds", r.ff_seconds},
              {"form_factors_source", opts.ff.ff_file.empty() ? "computed" : opts.ff.ff_file},
              {"solve_seconds", sol.seconds}}},
            {"form_factors", ff_settings_json(r.ff_options, opts.ff.ff_file)},
            {"form_factor_nonzeros", r.nonzeros}};
  if (medium_result) j["medium"] = medium_json(*medium_result);
  Json& channels = j["channels"] = Json::array();
  for (int c = 0; c < 3; ++c) channels.push_back(channel_json(sol.channels[c], sol.energy[c], c));
  j["surfaces"] = surface_averages_json(surfaces);
  if (!r.rounds.empty()) j["adapt"] = adapt_json(r.rounds);
  if (loaded.scene.daylight.any()) j["daylight"] = daylight_json(loaded.scene.daylight, r.daylight);
  if (!r.distributed.is_null()) j["distributed"] = r.distributed;

  std::printf("solver %s: %s\n", so.solver.c_str(), to_string(sol.status));
  for (int c = 0; c < 3; ++c) {
    const ChannelReport& cr = sol.channels[c];
    std::printf(
        "  %s: %-15s %6d iterations %8lld matvecs  residual %.3e  %.4fs  energy "
        "emitted %.6g absorbed %.6g escaped %.6g (imbalance %.2e: %s)\n",
        channel_name(c), to_string(cr.status), cr.iterations, static_cast<long long>(cr.matvecs),
        cr.residual, cr.seconds, sol.energy[c].emitted, sol.energy[c].absorbed,
        sol.energy[c].escaped, sol.energy[c].relative_imbalance,
        energy_split_text(sol.energy[c]).c_str());
  }
  if (medium_result)
    for (int c = 0; c < 3; ++c)
      std::printf("  %s: absorbed by surfaces %.6g, by the medium %.6g (%d zones)\n",
                  channel_name(c), medium_result->absorbed_surfaces[c],
                  medium_result->absorbed_medium[c], medium_result->zones.size());
  write_summary(opts.output, json_path, j);
  if (sol.status != SolveStatus::Converged) {
    log_warn("solver " + so.solver + " did not converge (" + to_string(sol.status) +
             "); results were written anyway");
    return kExitNotConverged;
  }
  return kExitOk;
}

CLI::App* add_solve_command(CLI::App& app, SolveCommandOptions& opts) {
  auto* cmd = app.add_subcommand("solve", "Solve the radiosity system and write per-patch B");
  opts.scene.default_patches = 2000;
  opts.scene.require_emitter = true;  // B from E: a scene where nothing emits is refused
  add_scene_options(cmd, opts.scene);
  add_method_options(cmd, opts.method);
  add_ff_options(cmd, opts.ff);
  add_solve_options(cmd, opts.solve, true);
  add_adapt_options(cmd, opts.adapt);
  add_medium_options(cmd, opts.medium);
  add_declared(cmd, "-o,--output", opts.output);
  add_run_options(cmd, opts.run);
  add_distributed_options(cmd, opts.dist, true);
  return cmd;
}

int run_solve(const SolveCommandOptions& opts) {
  const bool matrix = opts.method.name == "matrix";
  Selection selection{"solve", opts.method.name,    matrix ? selected_estimator(opts.ff) : "", {},
                      "",      opts.medium.active()};
  // --distributed solves with PETSc's GMRES over the ranks.
  if (matrix) selection.solvers = {opts.dist.enabled ? "petsc" : opts.solve.solver};
  if (opts.dist.enabled) {
    check_options_read(opts.run, selection);
    return run_solve_distributed(opts);
  }
  static const MethodTable<SolveCommandOptions> kMethods = {
      {"matrix", run_solve_matrix}, {"hierarchical", run_solve_hierarchical}};
  return run_for_method(kMethods, opts, selection);
}

}  // namespace lambert
