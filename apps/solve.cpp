#include <cstdio>
#include <filesystem>
#include <fstream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "apps/problem.hpp"
#include "apps/solve_args.hpp"
#include "core/atomic_file.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/json.hpp"

namespace lambert {
namespace {

// B.csv -> B.json; a name without .csv gets .json appended.
std::string summary_path(const std::string& csv) {
  std::filesystem::path p(csv);
  if (p.extension() == ".csv") return p.replace_extension(".json").string();
  return csv + ".json";
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

void write_channel(JsonWriter& j, const ChannelReport& r, const EnergyBalance& e, int c) {
  j.begin_object();
  j.field("channel", channel_name(c));
  j.field("status", to_string(r.status));
  j.field("iterations", r.iterations);
  j.field("matvecs", r.matvecs);
  j.field("residual", r.residual);
  j.field("seconds", r.seconds);
  if (!r.note.empty()) j.field("note", r.note);
  j.key("energy");
  write_energy_json(j, e);
  j.key("history");
  j.begin_object();
  std::vector<double> its(r.history_iteration.begin(), r.history_iteration.end());
  j.field("iteration", its);
  j.field("seconds", r.time_history);
  j.field("residual", r.residual_history);
  j.end_object();
  j.end_object();
}

}  // namespace

CLI::App* add_solve_command(CLI::App& app, SolveCommandOptions& opts) {
  auto* cmd = app.add_subcommand("solve", "Solve the radiosity system and write per-patch B");
  opts.scene.default_patches = 2000;
  add_scene_options(cmd, opts.scene);
  add_ff_options(cmd, opts.ff);
  add_solve_options(cmd, opts.solve, true);
  cmd->add_option("-o,--output", opts.output,
                  "Per-patch radiosity CSV (patch,surface,area,R,G,B); the summary goes to the "
                  "same name with .json")
      ->check(output_file_check())
      ->capture_default_str();
  add_run_options(cmd, opts.run);
  return cmd;
}

int run_solve(const SolveCommandOptions& opts) {
  apply_run_options(opts.run);
  const Timer total;
  const LoadedScene loaded = load_scene(opts.scene);
  const double load_seconds = total.seconds();
  const Timer ff_timer;
  const FormFactors ff = obtain_form_factors(loaded, opts.ff, opts.run);
  const double ff_seconds = ff_timer.seconds();
  const RadiosityProblem problem = make_problem(loaded.mesh, ff.F);
  warn_about_lighting(loaded.mesh, ff.F, true);
  SolveOptions so = opts.solve;
  so.threads = opts.run.threads;
  const RadiositySolution sol = solve_radiosity(problem, so);

  const std::string json_path = summary_path(opts.output);
  write_radiosity_csv(opts.output, loaded.mesh, sol.B);
  const auto surfaces = surface_averages(loaded.mesh, sol.B);
  write_stream_atomically(json_path, [&](std::ostream& out) {
    JsonWriter j(out);
    j.begin_object();
    j.field("scene", loaded.scene.source);
    j.field("patches", static_cast<std::int64_t>(loaded.mesh.size()));
    j.field("solver", so.solver);
    j.field("status", to_string(sol.status));
    j.key("options");
    j.begin_object();
    j.field("tol", so.tol);
    j.field("max_iterations", so.max_iterations);
    j.field("omega", so.omega);
    j.field("preconditioner", so.preconditioner);
    j.field("restart", so.restart);
    j.field("ambient", so.ambient);
    j.end_object();
    int iterations = 0;
    double residual = 0.0;
    for (const auto& r : sol.channels) {
      iterations = std::max(iterations, r.iterations);
      residual = std::max(residual, r.residual);
    }
    j.field("iterations", iterations);
    j.field("residual", residual);
    j.key("timings");
    j.begin_object();
    j.field("load_and_mesh_seconds", load_seconds);
    j.field("form_factors_seconds", ff_seconds);
    j.field("form_factors_source", opts.ff.ff_file.empty() ? "computed" : opts.ff.ff_file);
    j.field("solve_seconds", sol.seconds);
    j.end_object();
    j.field("form_factor_nonzeros", static_cast<std::int64_t>(ff.F.nonZeros()));
    j.key("channels");
    j.begin_array();
    for (int c = 0; c < 3; ++c) write_channel(j, sol.channels[c], sol.energy[c], c);
    j.end_array();
    j.key("surfaces");
    j.begin_array();
    for (const auto& s : surfaces) {
      j.begin_object();
      j.field("name", s.name);
      j.field("area", s.area);
      j.field("patches", s.patches);
      j.field("average_radiosity", std::vector<double>{s.average[0], s.average[1], s.average[2]});
      j.end_object();
    }
    j.end_array();
    j.end_object();
    out << '\n';
  });

  std::printf("solver %s: %s\n", so.solver.c_str(), to_string(sol.status));
  for (int c = 0; c < 3; ++c) {
    const ChannelReport& r = sol.channels[c];
    std::printf(
        "  %s: %-15s %6d iterations %8lld matvecs  residual %.3e  %.4fs  energy "
        "emitted %.6g absorbed %.6g escaped %.6g (imbalance %.2e)\n",
        channel_name(c), to_string(r.status), r.iterations, static_cast<long long>(r.matvecs),
        r.residual, r.seconds, sol.energy[c].emitted, sol.energy[c].absorbed, sol.energy[c].escaped,
        sol.energy[c].relative_imbalance);
  }
  std::printf("wrote %s and %s\n", opts.output.c_str(), json_path.c_str());
  if (sol.status != SolveStatus::Converged) {
    log_warn("solver " + so.solver + " did not converge (" + to_string(sol.status) +
             "); results were written anyway");
    return kExitNotConverged;
  }
  return kExitOk;
}

}  // namespace lambert
