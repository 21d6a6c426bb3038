// `lambert run`: the whole job in one command: load, mesh, form factors, solve, per-vertex
// radiosity, render, and every output file, with one progress line per stage on stderr and
// a closing summary on stdout.

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "apps/solve_args.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "io/json.hpp"

namespace lambert {
namespace {

constexpr int kStages = 6;

void stage(int k, const std::string& what) {
  log_info("[" + std::to_string(k) + "/" + std::to_string(kStages) + "] " + what);
}

// Seconds per stage, in order.
struct StageTimes {
  double load = 0, form_factors = 0, solve = 0, vertices = 0, render = 0, write = 0;
  double total() const { return load + form_factors + solve + vertices + render + write; }
};

std::string run_settings(const RunOptions& o, const LoadedScene& s, const RadiosityResult& r,
                         const Camera& cam) {
  std::ostringstream ss;
  ss << "patches=" << s.mesh.size() << " max_edge=" << s.max_edge << ' '
     << ff_settings_text(r.ff_options, o.ff.ff_file) << " solver=" << o.solver.solver
     << " tol=" << o.solver.tol << " interp=" << o.shade.vertex_interp
     << " shading=" << (o.shade.flat ? "flat" : "gouraud") << " antialias=" << o.shade.antialias
     << " render_seed=" << o.run.seed << " size=" << cam.width << "x" << cam.height;
  return ss.str();
}

std::vector<double> as_vector(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

struct Report {
  const RunOptions& opts;
  const LoadedScene& loaded;
  const RadiosityResult& r;
  const ShadedField& shaded;
  const RenderStats& render;
  const Camera& camera;
  double ev;
  const StageTimes& t;
  const std::vector<std::string>& files;
  std::string settings;
};

Json report_json(const Report& rp) {
  const auto& r = rp.r;
  Json j = {{"scene", rp.loaded.scene.source},
            {"settings", rp.settings},
            {"patches", rp.loaded.mesh.size()},
            {"shading_vertices", rp.shaded.field.size()},
            {"surfaces", rp.loaded.mesh.surface_names.size()}};
  Json& ff = j["form_factors"] = ff_settings_json(r.ff_options, rp.opts.ff.ff_file);
  ff["entries"] = r.ff_entries;
  ff["pairs_tested"] = r.ff_stats.pairs_tested;
  ff["rays"] = r.ff_stats.rays;
  ff["reciprocity_max_relative_change"] = r.ff_stats.reciprocity_max_relative_change;
  ff["reciprocity_mean_relative_change"] = r.ff_stats.reciprocity_mean_relative_change;
  ff["reciprocity_scale_min"] = r.ff_stats.reciprocity_scale_min;
  ff["reciprocity_scale_max"] = r.ff_stats.reciprocity_scale_max;
  ff["reciprocity_rows_scaled"] = r.ff_stats.reciprocity_rows_scaled;

  Json channels = Json::array();
  for (const auto& c : r.solution.channels)
    channels.push_back({{"status", to_string(c.status)},
                        {"iterations", c.iterations},
                        {"matvecs", c.matvecs},
                        {"residual", c.residual},
                        {"seconds", c.seconds}});
  j["solver"] = {{"name", rp.opts.solver.solver},
                 {"tol", rp.opts.solver.tol},
                 {"status", to_string(r.solution.status)},
                 {"channels", channels}};

  Json& energy = j["energy_balance"] = Json::array();
  for (const auto& e : r.solution.energy) energy.push_back(energy_json(e));

  const auto [after, before] = worst_power_error(rp.shaded.power);
  Json surfaces = Json::array();
  for (const auto& s : rp.shaded.power)
    surfaces.push_back({{"name", s.name},
                        {"area", s.area},
                        {"patch_power", as_vector(s.patch_power)},
                        {"field_power", as_vector(s.field_power)},
                        {"area_weighted_power", as_vector(s.area_weighted_power)},
                        {"relative_error", s.relative_error()},
                        {"area_weighted_relative_error", s.area_weighted_relative_error()}});
  j["vertex_power"] = {
      {"interpolation", rp.opts.shade.vertex_interp},
      {"max_relative_error", after},
      {"area_weighted_max_relative_error", before},
      {"tolerance", rp.opts.shade.vertex_interp == "conservative" ? kPowerTolerance : before},
      {"surfaces", surfaces}};

  j["render"] = {{"width", rp.camera.width},
                 {"height", rp.camera.height},
                 {"samples_per_pixel", rp.opts.shade.antialias * rp.opts.shade.antialias},
                 {"shading", rp.opts.shade.flat ? "flat" : "gouraud"},
                 {"rays", rp.render.rays},
                 {"exposure_ev", rp.ev}};
  j["seconds"] = {{"load_and_mesh", rp.t.load}, {"form_factors", rp.t.form_factors},
                  {"solve", rp.t.solve},        {"vertices", rp.t.vertices},
                  {"render", rp.t.render},      {"write", rp.t.write},
                  {"total", rp.t.total()}};
  j["rays_total"] = r.ff_stats.rays + rp.render.rays;
  j["files"] = rp.files;
  return j;
}

void print_summary(const Report& rp) {
  const auto& r = rp.r;
  const char* channel[] = {"R", "G", "B"};
  std::printf("scene      %s\n", rp.loaded.scene.source.c_str());
  std::printf("patches    %d (%d shading vertices, %zu surfaces)\n", rp.loaded.mesh.size(),
              rp.shaded.field.size(), rp.loaded.mesh.surface_names.size());
  std::printf("rays       %s form factors + %s camera = %s\n",
              format_si(static_cast<double>(r.ff_stats.rays)).c_str(),
              format_si(static_cast<double>(rp.render.rays)).c_str(),
              format_si(static_cast<double>(r.ff_stats.rays + rp.render.rays)).c_str());
  std::printf("solver     %s: %s;", rp.opts.solver.solver.c_str(), to_string(r.solution.status));
  for (int c = 0; c < 3; ++c)
    std::printf(" %s %d it (res %.2g)", channel[c], r.solution.channels[c].iterations,
                r.solution.channels[c].residual);
  std::printf("\n");
  std::printf("energy     emitted / absorbed / escaped (W), relative imbalance (its parts):\n");
  for (int c = 0; c < 3; ++c) {
    const auto& e = r.solution.energy[c];
    std::printf("           %s %.6g / %.6g / %.6g, %.2e (%s)\n", channel[c], e.emitted, e.absorbed,
                e.escaped, e.relative_imbalance, energy_split_text(e).c_str());
  }
  const auto [after, before] = worst_power_error(rp.shaded.power);
  std::printf(
      "vertices   power error per surface (max) %.2e with %s interpolation "
      "(area-weighted alone: %.2e)\n",
      after, rp.opts.shade.vertex_interp.c_str(), before);
  std::printf("image      %dx%d, %d samples/pixel, exposure %+.2f EV\n", rp.camera.width,
              rp.camera.height, rp.opts.shade.antialias * rp.opts.shade.antialias, rp.ev);
  std::printf(
      "time       load+mesh %s, form factors %s, solve %s, vertices %s, render %s, "
      "write %s; total %s\n",
      format_duration(rp.t.load).c_str(), format_duration(rp.t.form_factors).c_str(),
      format_duration(rp.t.solve).c_str(), format_duration(rp.t.vertices).c_str(),
      format_duration(rp.t.render).c_str(), format_duration(rp.t.write).c_str(),
      format_duration(rp.t.total()).c_str());
  std::printf("files\n");
  for (const auto& f : rp.files) std::printf("           %s\n", f.c_str());
}

std::string default_name(const SceneArgs& scene) {
  if (scene.scene.empty()) return "cornell";
  return std::filesystem::path(scene.scene).stem().string();
}

}  // namespace

CLI::App* add_run_command(CLI::App& app, RunOptions& opts) {
  auto* cmd = app.add_subcommand(
      "run", "The main job: load, mesh, form factors, solve, render; writes every output");
  opts.scene.default_patches = 1600;
  opts.ff.samples = 16;
  add_scene_options(cmd, opts.scene);
  add_run_options(cmd, opts.run);
  add_ff_options(cmd, opts.ff);
  add_solve_options(cmd, opts.solver, true);
  add_camera_options(cmd, opts.camera);
  add_shade_options(cmd, opts.shade);
  cmd->add_option("-o,--output", opts.output_dir, "Output directory (created if needed)")
      ->capture_default_str();
  cmd->add_option(
      "--name", opts.name,
      "File name prefix (default: the scene file's stem; cornell for the built-in box)");
  return cmd;
}

int run_run(const RunOptions& opts) {
  apply_run_options(opts.run);
  StageTimes t;
  Timer timer;
  stage(1,
        "loading and meshing " + (opts.scene.scene.empty() ? std::string("the built-in Cornell box")
                                                           : opts.scene.scene));
  const std::string name = opts.name.empty() ? default_name(opts.scene) : opts.name;
  if (name.empty() || name.find('/') != std::string::npos)
    throw UsageError("--name must be a non-empty file name prefix without '/'");
  std::error_code ec;
  std::filesystem::create_directories(opts.output_dir, ec);
  if (!std::filesystem::is_directory(opts.output_dir))
    throw IoError(opts.output_dir + ": cannot create the output directory" +
                  (ec ? ": " + ec.message() : std::string()));
  const std::filesystem::path dir(opts.output_dir);
  OutputPaths paths;
  paths.image_exr = (dir / (name + ".exr")).string();
  paths.png = (dir / (name + ".png")).string();
  paths.vertex_exr = (dir / (name + "_vertices.exr")).string();
  paths.ply = (dir / (name + ".ply")).string();
  const std::string report_path = (dir / "report.json").string();
  JobPlan plan = job_plan(opts.run);
  plan.outputs = {{"-o", paths.image_exr}, {"-o", paths.png}, {"-o", paths.vertex_exr},
                  {"-o", paths.ply},       {"-o", report_path}};
  plan_form_factors(plan, opts.ff, opts.run);
  plan.direct = opts.solver.solver == "direct";
  const LoadedScene loaded = load_scene(opts.scene, plan);
  const Camera camera = make_camera(loaded.scene, opts.camera);
  t.load = timer.seconds();
  log_info("      " + std::to_string(loaded.mesh.size()) + " patches on " +
           std::to_string(loaded.mesh.surface_names.size()) + " surfaces");

  const std::string estimator =
      opts.ff.estimator == "auto" ? auto_estimator(loaded.mesh.size()) : opts.ff.estimator;
  const std::string count = estimator_count_option(estimator);
  const std::string per =
      count == "rays"      ? ", " + std::to_string(opts.ff.rays) + " rays per patch"
      : count == "samples" ? ", " + std::to_string(opts.ff.samples) + " samples per pair"
                           : "";
  stage(2, "form factors (" +
               (opts.ff.ff_file.empty() ? estimator + per : "from " + opts.ff.ff_file) +
               ")");
  RadiosityResult r;
  timer.reset();
  const FormFactors F = obtain_form_factors(loaded, opts.ff, opts.run);
  r.ff_seconds = timer.seconds();
  t.form_factors = r.ff_seconds;

  stage(3, "solving (I - rho F) B = E with " + opts.solver.solver);
  solve_scene(loaded, F, opts.solver, opts.run, r);
  t.solve = r.solve_seconds;

  stage(4, "per-vertex radiosity (" + opts.shade.vertex_interp + ")");
  const ShadedField shaded = shade_vertices(loaded.mesh, r.B, opts.shade);
  t.vertices = shaded.seconds;

  stage(5, "rendering " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  RenderStats rs;
  const Image image =
      render_scene(loaded, r.B, shaded.field, camera, opts.shade, opts.run, &rs);
  t.render = rs.seconds;
  const double ev = choose_exposure(opts.shade, image);

  stage(6, "writing " + opts.output_dir + "/" + name + ".*");
  timer.reset();
  const std::string settings = run_settings(opts, loaded, r, camera);
  std::vector<std::string> files = write_outputs(paths, loaded.mesh, shaded, image, ev, settings);
  files.push_back(report_path);
  t.write = timer.seconds();
  const Report report{opts, loaded, r, shaded, rs, camera, ev, t, files, settings};
  write_json_file(report_path, report_json(report));
  print_summary(report);
  if (r.solution.status != SolveStatus::Converged) {
    log_warn("solver status " + std::string(to_string(r.solution.status)) +
             ": results were written but are not converged");
    return kExitNotConverged;
  }
  return kExitOk;
}

}  // namespace lambert
