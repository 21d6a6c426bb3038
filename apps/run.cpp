// `lambert run`: the whole job in one command: load, compute B with the chosen method
// (matrix: mesh, form factors, solve; hierarchical: adaptive links and their solve),
// per-vertex radiosity, render, and every output file, with one progress line per stage on
// stderr and a closing summary on stdout.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <utility>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "io/json.hpp"
#include "pipeline/hierarchical_stage.hpp"
#include "pipeline/problem.hpp"
#include "pipeline/solve_stage.hpp"
#include "pipeline/viewer_stage.hpp"

namespace lambert {
namespace {

// "[k/n] what" on stderr, counting the stages of one run, and each stage's wall and CPU
// time under its report key (report.json "timings"; CPU / wall near the thread count where a
// stage is parallel: issue 37).
class Stages {
 public:
  explicit Stages(int total) : total_(total) {}
  /// Ends the stage before (if any) and starts `key` ("": the stage before goes on).
  void next(const std::string& key, const std::string& what) {
    log_info("[" + std::to_string(++k_) + "/" + std::to_string(total_) + "] " + what);
    if (key.empty()) return;
    close();
    key_ = key, wall_ = Timer(), cpu_ = process_cpu_seconds();
  }
  /// {key: {"wall": s, "cpu": s}} of every stage so far, the current one up to now, and their
  /// "total".
  Json timings() {
    close();
    Json j = Json::object();
    double wall = 0.0, cpu = 0.0;
    for (const auto& [key, t] : done_) {
      j[key] = {{"wall", t.first}, {"cpu", t.second}};
      wall += t.first, cpu += t.second;
    }
    j["total"] = {{"wall", wall}, {"cpu", cpu}};
    return j;
  }

 private:
  void close() {
    if (key_.empty()) return;
    done_.emplace_back(key_, std::make_pair(wall_.seconds(), process_cpu_seconds() - cpu_));
    key_.clear();
  }
  int total_, k_ = 0;
  std::string key_;
  Timer wall_;
  double cpu_ = 0.0;
  std::vector<std::pair<std::string, std::pair<double, double>>> done_;
};

// Where a run writes.
struct RunPaths {
  std::string name, dir;
  OutputPaths files;
  std::string glb, page;  ///< NAME.glb and the viewer page index.html
  std::string report;
};

// What a method produced, for the stages every method shares (vertices, render, write), the
// report and the summary.
struct MethodOutcome {
  MethodOutcome(std::string name, const LoadedScene& scene, const Eigen::MatrixX3d& radiosity)
      : method(std::move(name)), loaded(scene), B(radiosity) {}
  std::string method;
  const LoadedScene& loaded;  ///< the mesh B lives on (and its BVH, for rendering)
  const Eigen::MatrixX3d& B;
  const Eigen::MatrixX3d* indirect = nullptr;  ///< I = F (B - E) when B came with F
  const MediumView* medium = nullptr;          ///< the participating medium, when there is one
  std::string settings;                        ///< the method's part of the settings line
  Json sections = Json::object();              ///< the method's report sections, in report order
  Json energy = Json::array();                 ///< energy_balance: one object per channel
  std::vector<std::pair<std::string, double>> seconds;  ///< the method's stages, report keys
  std::vector<std::string> time_labels;                 ///< the same for the summary's time line
  std::int64_t rays = 0;
  std::string rays_label;            ///< what traced them ("form factors", "links")
  std::string patches_noun;          ///< after the patch count ("" or " leaves")
  std::vector<std::string> summary;  ///< stdout lines between rays and vertices
  SolveStatus status = SolveStatus::Converged;
  std::string not_converged;                         ///< the warning when status is not Converged
  const std::vector<EmitterBasis>* bases = nullptr;  ///< the solution per light source
  double bases_seconds = 0.0;
  std::string no_relighting;  ///< why there are no bases (when none)
};

std::vector<double> as_vector(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

std::string shade_settings(const RunOptions& o, const std::string& interp, const Camera& cam,
                           int direct_rays) {
  std::ostringstream ss;
  ss << " interp=" << interp << ' ' << shading_settings(o.shade, o.ff.specular_depth)
     << " direct_rays=" << direct_rays << (o.shade.wireframe ? " wireframe=1" : "")
     << " antialias=" << o.shade.antialias << " render_seed=" << o.run.seed << " size=" << cam.width
     << "x" << cam.height;
  return ss.str();
}

// The stages after the method's: what the run hands on to the report.
struct Tail {
  const ShadedField& shaded;
  const RenderStats& render;
  const Camera& camera;
  double ev;
  double write_seconds;
  const std::vector<std::string>& files;
  std::string settings;
  Json viewer;  ///< the report's "viewer" section
};

double method_seconds(const MethodOutcome& m) {
  double s = 0.0;
  for (const auto& [key, t] : m.seconds) s += t;
  return s;
}

double total_seconds(const MethodOutcome& m, const Tail& t) {
  return method_seconds(m) + m.bases_seconds + t.shaded.seconds + t.render.seconds +
         t.write_seconds;
}

Json report_json(const RunOptions& opts, const MethodOutcome& m, const Tail& t) {
  Json j = {{"scene", m.loaded.scene.source},
            {"method", m.method},
            {"settings", t.settings},
            {"patches", m.loaded.mesh.size()},
            {"shading_vertices", t.shaded.field.size()},
            {"surfaces", m.loaded.mesh.surface_names.size()}};
  for (const auto& [key, value] : m.sections.items()) j[key] = value;
  j["energy_balance"] = m.energy;
  j["surface_averages"] = surface_averages_json(surface_averages(m.loaded.mesh, m.B));

  const auto [after, before] = worst_power_error(t.shaded.power);
  Json surfaces = Json::array();
  for (const auto& s : t.shaded.power)
    surfaces.push_back({{"name", s.name},
                        {"area", s.area},
                        {"patch_power", as_vector(s.patch_power)},
                        {"field_power", as_vector(s.field_power)},
                        {"area_weighted_power", as_vector(s.area_weighted_power)},
                        {"relative_error", s.relative_error()},
                        {"area_weighted_relative_error", s.area_weighted_relative_error()}});
  j["vertex_power"] = {
      {"interpolation", t.shaded.interpolation},
      {"max_relative_error", after},
      {"area_weighted_max_relative_error", before},
      {"tolerance", t.shaded.interpolation == "conservative" ? kPowerTolerance : before},
      {"surfaces", surfaces}};

  j["render"] = {{"width", t.camera.width},
                 {"height", t.camera.height},
                 {"samples_per_pixel", opts.shade.antialias * opts.shade.antialias},
                 {"rays", t.render.rays},
                 {"direct_light", t.render.direct_rays > 0 ? "per pixel" : "from the vertices"},
                 {"direct_rays", t.render.direct_rays},
                 {"exposure_ev", t.ev}};
  const Json shading = shading_json(opts.shade, opts.ff.specular_depth);
  for (const auto& [key, value] : shading.items()) j["render"][key] = value;
  Json& seconds = j["seconds"] = Json::object();
  for (const auto& [key, s] : m.seconds) seconds[key] = s;
  seconds["vertices"] = t.shaded.seconds;
  seconds["render"] = t.render.seconds;
  seconds["bases"] = m.bases_seconds;
  seconds["write"] = t.write_seconds;
  seconds["total"] = total_seconds(m, t);
  j["rays_total"] = m.rays + t.render.rays;
  j["viewer"] = t.viewer;
  j["files"] = t.files;
  return j;
}

void print_summary(const RunOptions& opts, const MethodOutcome& m, const Tail& t) {
  std::printf("scene      %s\n", m.loaded.scene.source.c_str());
  std::printf("patches    %d%s (%d shading vertices, %zu surfaces)\n", m.loaded.mesh.size(),
              m.patches_noun.c_str(), t.shaded.field.size(), m.loaded.mesh.surface_names.size());
  std::printf("rays       %s %s + %s camera = %s\n", format_si(static_cast<double>(m.rays)).c_str(),
              m.rays_label.c_str(), format_si(static_cast<double>(t.render.rays)).c_str(),
              format_si(static_cast<double>(m.rays + t.render.rays)).c_str());
  for (const std::string& line : m.summary) std::printf("%s\n", line.c_str());
  const auto [after, before] = worst_power_error(t.shaded.power);
  if (t.shaded.interpolation == "exact-direct")
    std::printf(
        "vertices   exact direct light at the vertices; field vs patch power per surface "
        "(max) %.2e (not rescaled)\n",
        after);
  else
    std::printf(
        "vertices   power error per surface (max) %.2e with %s interpolation "
        "(area-weighted alone: %.2e)\n",
        after, t.shaded.interpolation.c_str(), before);
  const std::string direct =
      t.render.direct_rays > 0
          ? ", direct light per pixel (" + std::to_string(t.render.direct_rays) + " shadow rays)"
          : "";
  std::printf("image      %dx%d, %d samples/pixel, %s%s, exposure %+.2f EV\n", t.camera.width,
              t.camera.height, opts.shade.antialias * opts.shade.antialias,
              shading_settings(opts.shade, opts.ff.specular_depth).c_str(), direct.c_str(), t.ev);
  std::string times;
  for (size_t k = 0; k < m.seconds.size(); ++k)
    times += m.time_labels[k] + " " + format_duration(m.seconds[k].second) + ", ";
  if (m.bases_seconds > 0.0) times += "light sources " + format_duration(m.bases_seconds) + ", ";
  std::printf("time       %svertices %s, render %s, write %s; total %s\n", times.c_str(),
              format_duration(t.shaded.seconds).c_str(), format_duration(t.render.seconds).c_str(),
              format_duration(t.write_seconds).c_str(),
              format_duration(total_seconds(m, t)).c_str());
  const Json& v = t.viewer;
  if (v.contains("page")) {
    const std::size_t sources = v["light_sources"].size();
    std::printf("viewer     %s: %zu light source%s%s\n", v["page"].get<std::string>().c_str(),
                sources, sources == 1 ? "" : "s",
                v["relighting"].get<bool>() ? ", relit live" : ", no relighting (see report.json)");
  }
  std::printf("files\n");
  for (const auto& f : t.files) std::printf("           %s\n", f.c_str());
}

// The .glb and the viewer page (added to `files`); returns the report's "viewer" section.
// Warns when the bases do not sum to the solution within kLinearityTolerance.
Json write_run_viewer(const RunPaths& paths, const MethodOutcome& m, const ShadedField& shaded,
                      const Camera& camera, double ev, const std::string& settings,
                      std::vector<std::string>& files) {
  static const std::vector<EmitterBasis> kNone;
  const std::vector<EmitterBasis>& bases = m.bases ? *m.bases : kNone;
  double linearity = 0.0;
  const GlbContent glb = viewer_glb({m.loaded.mesh, m.loaded.scene.daylight, m.loaded.scene.source,
                                     m.B, shaded, bases, m.no_relighting, camera, ev, settings},
                                    &linearity);
  for (const std::string& f : write_viewer(glb, paths.glb, paths.page, paths.name))
    files.push_back(f);
  Json sources = Json::array();
  for (const EmitterBasis& b : bases) sources.push_back(b.name);
  Json j = {{"glb", paths.glb},
            {"page", paths.page},
            {"relighting", !bases.empty()},
            {"light_sources", sources}};
  if (bases.empty()) {
    j["no_relighting"] = m.no_relighting;
  } else {
    j["linearity_error"] = linearity;
    if (linearity > kLinearityTolerance) {
      char line[240];
      std::snprintf(line, sizeof line,
                    "the %zu light sources' solutions sum to the solution within %.2g (above "
                    "%.0e): the viewer at full intensities differs from the image by that much; "
                    "a smaller --tol closes it",
                    bases.size(), linearity, kLinearityTolerance);
      log_warn(line);
    }
  }
  return j;
}

// The stages every method shares: per-vertex radiosity, render, write, report, summary.
int finish_run(const RunOptions& opts, const RunPaths& paths, const MethodOutcome& m,
               const Camera& camera, Stages& stages) {
  stages.next("vertices", "per-vertex radiosity (" +
                              resolve_vertex_interp(opts.shade, m.loaded, m.indirect) + ")");
  const ShadedField shaded =
      shade_vertices(m.loaded, m.B, m.indirect, opts.shade, opts.run.threads);

  stages.next("render",
              "rendering " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  RenderStats rs;
  const Image image =
      render_scene(m.loaded, m.B, shaded.field, camera, opts.shade, opts.ff.specular_depth,
                   opts.run, &rs, m.medium, m.indirect, shaded.interpolation);
  const double ev = choose_exposure(opts.shade, image, m.loaded.scene.daylight.has_sky());

  stages.next("write", "writing " + opts.output_dir + "/" + paths.name + ".*");
  const Timer timer;
  const std::string settings =
      m.settings + shade_settings(opts, shaded.interpolation, camera, rs.direct_rays);
  // The files and the viewer side by side (independent, each written atomically).
  std::vector<std::string> files, viewer_files;
  Json viewer;
  parallel_for(2, 1, opts.run.threads, [&](std::int64_t begin, std::int64_t end) {
    for (auto k = begin; k < end; ++k) {
      if (k == 0)
        files = write_outputs(paths.files, m.loaded.mesh, shaded, image, ev, settings,
                              opts.run.threads);
      else
        viewer = write_run_viewer(paths, m, shaded, camera, ev, settings, viewer_files);
    }
  });
  files.insert(files.end(), viewer_files.begin(), viewer_files.end());
  files.push_back(paths.report);
  const Tail tail{shaded, rs, camera, ev, timer.seconds(), files, settings, viewer};
  Json report = report_json(opts, m, tail);
  report["timings"] = stages.timings();  // the report's own writing is not in "write"
  write_json_file(paths.report, report);
  print_summary(opts, m, tail);
  if (m.status != SolveStatus::Converged) {
    log_warn(m.not_converged);
    return kExitNotConverged;
  }
  return kExitOk;
}

std::string default_name(const SceneArgs& scene) {
  if (scene.scene.empty()) return "cornell";
  return std::filesystem::path(scene.scene).stem().string();
}

// The output names, the directory created; the plan with every output and --max-memory.
RunPaths prepare_outputs(const RunOptions& opts, JobPlan& plan) {
  RunPaths p;
  p.name = opts.name.empty() ? default_name(opts.scene) : opts.name;
  if (p.name.empty() || p.name.find('/') != std::string::npos)
    throw UsageError("--name must be a non-empty file name prefix without '/'");
  std::error_code ec;
  std::filesystem::create_directories(opts.output_dir, ec);
  if (!std::filesystem::is_directory(opts.output_dir))
    throw IoError(opts.output_dir + ": cannot create the output directory" +
                  (ec ? ": " + ec.message() : std::string()));
  const std::filesystem::path dir(opts.output_dir);
  p.files.image_exr = (dir / (p.name + ".exr")).string();
  p.files.png = (dir / (p.name + ".png")).string();
  p.files.vertex_exr = (dir / (p.name + "_vertices.exr")).string();
  p.files.ply = (dir / (p.name + ".ply")).string();
  p.glb = (dir / (p.name + ".glb")).string();
  p.page = (dir / "index.html").string();
  p.report = (dir / "report.json").string();
  plan = job_plan(opts.run);
  plan.outputs = {{"-o", p.files.image_exr}, {"-o", p.files.png}, {"-o", p.files.vertex_exr},
                  {"-o", p.files.ply},       {"-o", p.glb},       {"-o", p.page},
                  {"-o", p.report}};
  return p;
}

std::string loading_what(const RunOptions& opts, const char* verb) {
  return std::string(verb) +
         (opts.scene.scene.empty() ? std::string("the built-in Cornell box") : opts.scene.scene);
}

// The medium's part of the report and summary.
void describe_medium(const MediumResult& medium, MethodOutcome& m) {
  m.medium = &medium.view;
  m.settings += ' ' + medium_settings_text(medium);
  m.sections["medium"] = medium_json(medium);
  const Eigen::Vector3i& res = medium.medium->resolution;
  char line[256];
  std::snprintf(line, sizeof line,
                "medium     %s, %dx%dx%d voxels, %d zones; exchange factors %s (%lld entries)",
                medium.medium->source.c_str(), res.x(), res.y(), res.z(), medium.zones.size(),
                format_duration(medium.seconds).c_str(), static_cast<long long>(medium.entries));
  m.summary.push_back(line);
  m.summary.push_back("           absorbed by surfaces / by the medium (W):");
  for (int c = 0; c < 3; ++c) {
    std::snprintf(line, sizeof line, "           %s %.6g / %.6g", channel_name(c),
                  medium.absorbed_surfaces[c], medium.absorbed_medium[c]);
    m.summary.push_back(line);
  }
}

// What the matrix method's stages hand to its report besides B and F's statistics.
struct MatrixExtras {
  std::string solver;  ///< the solver's name ("petsc" with --distributed)
  double load_seconds = 0.0;
  std::vector<AdaptRound> rounds;
  std::optional<MediumResult> medium;
  Json distributed;  ///< the "distributed" report section (null: none)
};

// The matrix method's report pieces and summary lines, then the shared stages.
int finish_matrix(const RunOptions& opts, const RunPaths& paths, const LoadedScene& loaded,
                  const Camera& camera, Stages& stages, const RadiosityResult& r,
                  const MatrixExtras& x) {
  MethodOutcome m{"matrix", loaded, r.B};
  if (!x.medium) m.indirect = &r.indirect;
  m.bases = &r.bases;
  m.bases_seconds = r.bases_seconds;
  m.no_relighting = x.medium ? "a participating medium's solution is not split by light source yet"
                    : !x.distributed.is_null() ? "--distributed solves once, over the ranks"
                                               : "";
  std::ostringstream settings;
  settings << "patches=" << loaded.mesh.size() << " max_edge=" << loaded.max_edge << ' '
           << ff_settings_text(r.ff_options, opts.ff.ff_file) << " solver=" << x.solver
           << " tol=" << opts.solver.tol << daylight_settings_text(loaded.scene.daylight);
  m.settings = settings.str();
  if (x.medium) describe_medium(*x.medium, m);
  if (!x.distributed.is_null()) m.sections["distributed"] = x.distributed;
  Json& ff = m.sections["form_factors"] = ff_settings_json(r.ff_options, opts.ff.ff_file);
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
  m.sections["solver"] = {{"name", x.solver},
                          {"tol", opts.solver.tol},
                          {"status", to_string(r.solution.status)},
                          {"channels", channels}};
  for (const auto& e : r.solution.energy) m.energy.push_back(energy_json(e));
  if (loaded.scene.daylight.any())
    m.sections["daylight"] = daylight_json(loaded.scene.daylight, r.daylight);
  if (!x.rounds.empty()) {
    m.sections["adapt"] = adapt_json(x.rounds);
    const AdaptRound& last = x.rounds.back();
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "adapt      %zu rounds: %lld -> %lld patches, estimated error %.3g -> %.3g W/m^2",
                  x.rounds.size() - 1, static_cast<long long>(x.rounds.front().patches),
                  static_cast<long long>(last.patches), x.rounds.front().estimated_error,
                  last.estimated_error);
    m.summary.push_back(buf);
  }
  m.seconds = {{"load_and_mesh", x.load_seconds},
               {"form_factors", r.ff_seconds},
               {"solve", r.solve_seconds}};
  m.time_labels = {"load+mesh", "form factors", "solve"};
  m.rays = r.ff_stats.rays;
  m.rays_label = "form factors";

  char line[256];
  std::string solver_line = "solver     " + x.solver + ": " + to_string(r.solution.status) + ";";
  for (int c = 0; c < 3; ++c) {
    std::snprintf(line, sizeof line, " %s %d it (res %.2g)", channel_name(c),
                  r.solution.channels[c].iterations, r.solution.channels[c].residual);
    solver_line += line;
  }
  m.summary.push_back(solver_line);
  if (const Daylight& light = loaded.scene.daylight; light.any()) {
    std::string parts;
    if (light.has_sky()) {
      std::snprintf(line, sizeof line, "sky %.6g W", r.daylight.sky_power[1]);
      parts = line;
    }
    if (light.has_sun()) {
      std::snprintf(line, sizeof line, "sun %.6g W", r.daylight.sun_power[1]);
      parts += (parts.empty() ? "" : ", ") + std::string(line);
    }
    m.summary.push_back("daylight   " + parts +
                        " onto the patches (G); what they reflect of it is \"emitted\" below");
  }
  m.summary.push_back(
      "energy     emitted / absorbed / escaped (W), relative imbalance (its parts):");
  for (int c = 0; c < 3; ++c) {
    const auto& e = r.solution.energy[c];
    std::snprintf(line, sizeof line, "           %s %.6g / %.6g / %.6g, %.2e (%s)", channel_name(c),
                  e.emitted, e.absorbed, e.escaped, e.relative_imbalance,
                  energy_split_text(e).c_str());
    m.summary.push_back(line);
  }
  m.status = r.solution.status;
  m.not_converged = "solver status " + std::string(to_string(r.solution.status)) +
                    ": results were written but are not converged";
  return finish_run(opts, paths, m, camera, stages);
}

// --method matrix --distributed: every rank loads and meshes, F and the solve over the ranks
// (distributed.hpp), then rank 0 alone renders and writes (stages 4-6).
int run_matrix_over_ranks(const RunOptions& opts) {
  Stages stages(6);
  RunPaths paths;
  std::optional<Camera> camera;
  double load_seconds = 0.0;
  auto load = [&](const RunArgs& run, bool root) {
    if (opts.medium.active() || opts.adapt.active())
      throw UsageError("--distributed does not take a participating medium or --adapt yet");
    const Timer timer;
    stages.next("load_and_mesh", loading_what(opts, "loading and meshing "));
    JobPlan plan = job_plan(run);
    if (root) paths = prepare_outputs(opts, plan);  // rank 0 alone creates and writes
    LoadedScene loaded = load_scene(opts.scene, plan);
    camera = make_camera(loaded.scene, opts.camera);
    load_seconds = timer.seconds();
    stages.next("form_factors_and_solve", "form factors over the ranks");
    stages.next("", "solving (I - rho F) B = E with PETSc over the ranks");
    return loaded;
  };
  auto finish = [&](const LoadedScene& loaded, const RadiosityResult& r, const Json& section) {
    return finish_matrix(opts, paths, loaded, *camera, stages, r,
                         {"petsc", load_seconds, {}, std::nullopt, section});
  };
  return run_matrix_distributed(opts.dist, opts.run, opts.ff, opts.solver, load, finish);
}

// --method matrix: mesh, F, solve (stages 1-3 of 6).
int run_matrix(const RunOptions& opts) {
  if (opts.dist.enabled) return run_matrix_over_ranks(opts);
  const std::shared_ptr<const Medium> medium = make_medium(opts.medium);
  if (medium && opts.adapt.active())
    throw UsageError("--adapt does not combine with a participating medium yet");
  Stages stages(6);
  Timer timer;
  stages.next("load_and_mesh", loading_what(opts, "loading and meshing "));
  JobPlan plan;
  const RunPaths paths = prepare_outputs(opts, plan);
  plan_form_factors(plan, opts.ff, opts.run);
  plan.medium = medium.get();
  plan.medium_rays = opts.medium.rays;
  plan.direct = opts.solver.solver == "direct";
  LoadedScene loaded = load_scene(opts.scene, plan);
  check_pixel_direct(opts.shade, loaded);
  const Camera camera = make_camera(loaded.scene, opts.camera);
  const double load_seconds = timer.seconds();
  log_info("      " + std::to_string(loaded.mesh.size()) + " patches on " +
           std::to_string(loaded.mesh.surface_names.size()) + " surfaces");
  if (medium) check_medium_scene(loaded.mesh, &opts.shade);

  const std::string estimator = opts.ff.estimator == "auto"
                                    ? auto_estimator(loaded.mesh.size(), opts.ff.given("--ff-tol"))
                                    : opts.ff.estimator;
  const std::string count = estimator_count_option(estimator);
  const std::string per =
      count == "rays"
          ? ", " + std::to_string(std::lround(opts.ff.param("--rays"))) + " rays per patch"
      : count == "samples"
          ? ", " + std::to_string(std::lround(opts.ff.param("--samples"))) + " samples per pair"
          : "";
  stages.next("form_factors",
              "form factors (" +
                  (opts.ff.ff_file.empty() ? estimator + per : "from " + opts.ff.ff_file) + ")");
  RadiosityResult r;
  std::optional<MediumResult> medium_result;
  timer.reset();
  std::vector<AdaptRound> rounds;
  if (opts.adapt.active()) {
    stages.next("adapt_and_solve", "adaptive meshing and solving with " + opts.solver.solver);
    SolveOptions so = opts.solver;
    set_memory_limit(so, opts.run.max_memory);
    FormFactors F;
    rounds = adapt_scene(loaded, opts.ff, so, opts.run, opts.adapt, F, r.solution);
    // Every round's solves count as solve time, the rest (F, error estimates, refinement)
    // as form-factor time.
    r.solve_seconds = 0.0;
    for (const auto& round : rounds) r.solve_seconds += round.solve_seconds;
    r.ff_seconds = timer.seconds() - r.solve_seconds;
    r.ff_stats = F.stats;
    r.ff_options = F.options;
    r.ff_entries = F.F.nonZeros();
    r.B = r.solution.B;
    r.indirect = indirect_irradiance(loaded.mesh, F.F, r.B);
    r.daylight = daylight_sources(loaded, F, opts.run.seed, opts.run.threads);
    r.solved = true;
    warn_about_lighting(loaded.mesh, F.F);
    solve_bases(loaded, F, so, opts.run, r);
  } else {
    const FormFactors F = obtain_form_factors(loaded, opts.ff, opts.run, false, medium.get());
    r.ff_seconds = timer.seconds();
    if (medium) {
      stages.next("medium_and_solve",
                  "medium zones and solving (I - rho F) B = E with " + opts.solver.solver);
      medium_result =
          solve_scene_with_medium(loaded, F, medium, opts.medium, opts.solver, opts.run, r);
      r.ff_seconds += medium_result->seconds;  // the zones' exchange factors are form factors
    } else {
      stages.next("solve", "solving (I - rho F) B = E with " + opts.solver.solver);
      solve_scene(loaded, F, opts.solver, opts.run, r, true);
    }
  }

  return finish_matrix(opts, paths, loaded, camera, stages, r,
                       {opts.solver.solver, load_seconds, rounds, medium_result, Json()});
}

// --method hierarchical: load (no meshing), hierarchical solve (stages 1-2 of 5).
int run_hierarchical(const RunOptions& opts) {
  check_vertex_interp(opts.shade, false, "--method hierarchical");
  Stages stages(5);
  const Timer timer;
  stages.next("load", loading_what(opts, "loading "));
  JobPlan plan;
  const RunPaths paths = prepare_outputs(opts, plan);
  Scene scene = load_checked_scene(opts.scene, plan);
  const Camera camera = make_camera(scene, opts.camera);
  const double load_seconds = timer.seconds();
  log_info("      " + std::to_string(scene.faces.size()) + " faces on " +
           std::to_string(scene.surfaces.size()) + " surfaces");

  const HierarchicalOptions ho = make_hierarchical_options(
      opts.method, opts.method.hierarchical.epsilon, opts.solver, opts.run);
  std::ostringstream what;
  what << "hierarchical radiosity (epsilon " << ho.epsilon << ", " << ho.link_rays
       << " rays per link, tol " << ho.tol << ")";
  stages.next("hierarchical", what.str());
  const HierarchicalRun h = solve_scene_hierarchical(std::move(scene), ho);
  const HierarchicalStats& st = h.stats;

  MethodOutcome m{"hierarchical", h.loaded, h.B};
  m.no_relighting =
      "hierarchical radiosity refines its links for the whole E: its solution is not split by "
      "light source";
  m.settings = hierarchical_settings_text(h);
  m.sections["hierarchical"] = hierarchical_json(h);
  for (const auto& e : st.energy) m.energy.push_back(hierarchical_energy_json(e));
  m.seconds = {{"load", load_seconds},
               {"build", st.build_seconds},
               {"refine", st.refine_seconds},
               {"solve", st.solve_seconds}};
  m.time_labels = {"load", "hierarchy build", "refine", "solve"};
  m.rays = st.rays;
  m.rays_label = "links";
  m.patches_noun = " leaves";
  char line[256];
  std::snprintf(line, sizeof line,
                "hierarchy  %lld faces, %lld elements, %lld clusters; %lld links (%lld with a "
                "cluster); min area %.3g; %s",
                static_cast<long long>(st.faces), static_cast<long long>(st.elements),
                static_cast<long long>(st.clusters), static_cast<long long>(st.links),
                static_cast<long long>(st.cluster_links), st.min_area,
                format_bytes(st.memory_bytes).c_str());
  m.summary.push_back(line);
  std::snprintf(line, sizeof line,
                "solve      hierarchical: %s; %d passes, %d sweeps (change %.2g)",
                to_string(hierarchical_status(st)), st.passes, st.iterations, st.change);
  m.summary.push_back(line);
  m.summary.push_back("energy     emitted / absorbed / escaped (W), relative imbalance:");
  for (int c = 0; c < 3; ++c) {
    const HierarchicalEnergy& e = st.energy[c];
    std::snprintf(line, sizeof line, "           %s %.6g / %.6g / %.6g, %.2e", channel_name(c),
                  e.emitted, e.absorbed, e.escaped, e.relative_imbalance);
    m.summary.push_back(line);
  }
  m.status = hierarchical_status(st);
  m.not_converged = "hierarchical status " + std::string(to_string(m.status)) +
                    ": results were written but are not converged";
  return finish_run(opts, paths, m, camera, stages);
}

}  // namespace

CLI::App* add_run_command(CLI::App& app, RunOptions& opts) {
  auto* cmd = app.add_subcommand(
      "run", "The main job: load, mesh, form factors, solve, render; writes every output");
  opts.scene.default_patches = 1600;
  opts.scene.require_emitter = true;  // B from E: a scene where nothing emits is refused
  opts.ff.params["--samples"] = kRunDefaultSamples;
  add_scene_options(cmd, opts.scene);
  add_run_options(cmd, opts.run);
  add_method_options(cmd, opts.method);
  add_ff_options(cmd, opts.ff);
  add_solve_options(cmd, opts.solver, true);
  add_adapt_options(cmd, opts.adapt);
  add_camera_options(cmd, opts.camera);
  add_shade_options(cmd, opts.shade);
  add_medium_options(cmd, opts.medium);
  add_declared(cmd, "-o,--output", opts.output_dir);
  add_declared(cmd, "--name", opts.name);
  add_distributed_options(cmd, opts.dist, true);
  return cmd;
}

int run_run(const RunOptions& opts) {
  if (opts.dist.enabled && opts.method.name != "matrix")
    throw UsageError("--distributed runs the matrix method (F over the ranks)");
  static const MethodTable<RunOptions> kMethods = {{"matrix", run_matrix},
                                                   {"hierarchical", run_hierarchical}};
  // Contradicting shading options: usage error before any work. --distributed solves with
  // PETSc's GMRES over the ranks.
  return run_for_method(kMethods, opts,
                        render_selection("run", opts.method.name, opts.method.name == "matrix",
                                         opts.ff, opts.dist.enabled ? "petsc" : opts.solver.solver,
                                         opts.shade, opts.medium.active()));
}

}  // namespace lambert
