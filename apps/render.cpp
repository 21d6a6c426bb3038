#include <cstdio>
#include <filesystem>
#include <sstream>
#include <utility>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/radiosity_csv.hpp"
#include "pipeline/hierarchical_stage.hpp"
#include "pipeline/solve_stage.hpp"
#include "pipeline/viewer_stage.hpp"

namespace lambert {
namespace {

// The method's part of the settings line: how B was obtained.
std::string matrix_settings(const RenderOptions& o, const LoadedScene& s,
                            const RadiosityResult& r) {
  std::ostringstream ss;
  ss << "patches=" << s.mesh.size() << " max_edge=" << s.max_edge;
  if (!o.radiosity.empty()) {
    ss << " radiosity=" << o.radiosity;
  } else {
    ss << ' ' << ff_settings_text(r.ff_options, o.ff.ff_file) << " solver=" << o.solver.solver
       << " tol=" << o.solver.tol;
  }
  return ss.str();
}

// The settings line: the method's part, then shading and camera.
std::string render_settings(const RenderOptions& o, const std::string& method_part,
                            const std::string& interp, const Camera& cam, int direct_rays) {
  std::ostringstream ss;
  ss << method_part;
  ss << " interp=" << interp << ' ' << shading_settings(o.shade, o.ff.specular_depth)
     << " direct_rays=" << direct_rays << (o.shade.wireframe ? " wireframe=1" : "")
     << " antialias=" << o.shade.antialias << " render_seed=" << o.run.seed << " size=" << cam.width
     << "x" << cam.height << " eye=" << cam.eye.x() << "," << cam.eye.y() << "," << cam.eye.z()
     << " look_at=" << cam.look_at.x() << "," << cam.look_at.y() << "," << cam.look_at.z()
     << " vfov=" << cam.vfov_degrees;
  return ss.str();
}

// --glb FILE: the viewer page beside it, FILE with .html.
std::string page_path(const RenderOptions& opts) {
  return opts.glb.empty() ? ""
                          : std::filesystem::path(opts.glb).replace_extension(".html").string();
}

std::string png_path(const RenderOptions& opts) {
  return opts.png.empty() ? std::filesystem::path(opts.output).replace_extension(".png").string()
                          : opts.png;
}

// What --glb carries besides B: the solution per light source, or why there is none.
struct Relighting {
  const std::vector<EmitterBasis>* bases = nullptr;
  std::string why_not;
};

// Shades, renders and writes B on the loaded mesh; prints what was written.
void render_and_write(const RenderOptions& opts, const LoadedScene& loaded,
                      const Eigen::MatrixX3d& B, const Eigen::MatrixX3d* indirect,
                      const Camera& camera, const std::string& method_settings,
                      const Relighting& relight, const MediumView* medium = nullptr) {
  const ShadedField shaded = shade_vertices(loaded, B, indirect, opts.shade, opts.run.threads);
  RenderStats stats;
  const Image image =
      render_scene(loaded, B, shaded.field, camera, opts.shade, opts.ff.specular_depth, opts.run,
                   &stats, medium, indirect, shaded.interpolation);
  const double ev = choose_exposure(opts.shade, image, loaded.scene.daylight.has_sky());
  OutputPaths paths;
  paths.image_exr = opts.output;
  paths.png = png_path(opts);
  paths.vertex_exr = opts.vertex_exr;
  paths.ply = opts.ply;
  const std::string settings =
      render_settings(opts, method_settings, shaded.interpolation, camera, stats.direct_rays);
  auto written = write_outputs(paths, loaded.mesh, shaded, image, ev, settings, opts.run.threads);
  if (!opts.glb.empty()) {
    static const std::vector<EmitterBasis> kNone;
    const std::vector<EmitterBasis>& bases = relight.bases ? *relight.bases : kNone;
    double linearity = 0.0;
    const GlbContent glb = viewer_glb({loaded.mesh, loaded.scene.daylight, loaded.scene.source, B,
                                       shaded, bases, relight.why_not, camera, ev, settings},
                                      &linearity);
    const std::string stem = std::filesystem::path(opts.glb).stem().string();
    for (const std::string& f : write_viewer(glb, opts.glb, page_path(opts), stem))
      written.push_back(f);
    if (!bases.empty() && linearity > kLinearityTolerance)
      log_warn("the " + std::to_string(bases.size()) +
               " light sources' solutions sum to the solution within " + std::to_string(linearity) +
               ": the viewer at full intensities differs from the image by that much; a smaller "
               "--tol closes it");
  }
  const auto [power_after, power_before] = worst_power_error(shaded.power);
  std::printf("rendered %dx%d, %lld rays in %.2fs, exposure %+.3f EV\n", image.width, image.height,
              static_cast<long long>(stats.rays), stats.seconds, ev);
  std::printf("vertex power error (max over surfaces): %.3g (%s), %.3g before rescale\n",
              power_after, shaded.interpolation.c_str(), power_before);
  for (const auto& f : written) std::printf("wrote %s\n", f.c_str());
}

JobPlan render_plan(const RenderOptions& opts) {
  JobPlan plan = job_plan(opts.run);
  plan.outputs = {{"-o", opts.output}, {"--png", png_path(opts)}, {"--vertex-exr", opts.vertex_exr},
                  {"--ply", opts.ply}, {"--glb", opts.glb},       {"--glb", page_path(opts)}};
  return plan;
}

// --method matrix: B from --radiosity, or F and a solve.
int render_matrix(const RenderOptions& opts) {
  const std::shared_ptr<const Medium> medium = make_medium(opts.medium);
  if (medium && !opts.radiosity.empty())
    throw UsageError(
        "--radiosity holds the patches' radiosity only: a participating medium "
        "needs F and a solve here (drop --radiosity)");
  JobPlan plan = render_plan(opts);
  if (opts.radiosity.empty()) {
    plan_form_factors(plan, opts.ff, opts.run);
    plan.medium = medium.get();
    plan.medium_rays = opts.medium.rays;
    plan.direct = opts.solver.solver == "direct";
  } else {
    plan.inputs.push_back({"--radiosity", opts.radiosity});
    check_vertex_interp(opts.shade, false, "--radiosity");
  }
  SceneArgs scene_args = opts.scene;
  scene_args.require_emitter = opts.radiosity.empty();  // --radiosity: B is given
  const LoadedScene loaded = load_scene(scene_args, plan);
  check_pixel_direct(opts.shade, loaded);
  const Camera camera = make_camera(loaded.scene, opts.camera);
  RadiosityResult r;
  if (medium) {
    check_medium_scene(loaded.mesh, &opts.shade);
    const Timer timer;
    const FormFactors F = obtain_form_factors(loaded, opts.ff, opts.run, false, medium.get());
    r.ff_seconds = timer.seconds();
    const MediumResult m =
        solve_scene_with_medium(loaded, F, medium, opts.medium, opts.solver, opts.run, r);
    render_and_write(
        opts, loaded, r.B, nullptr, camera,
        matrix_settings(opts, loaded, r) + ' ' + medium_settings_text(m),
        {nullptr, "a participating medium's solution is not split by light source yet"}, &m.view);
    return r.solution.status != SolveStatus::Converged ? kExitNotConverged : kExitOk;
  }
  if (!opts.radiosity.empty()) {
    r.B = read_radiosity_csv(opts.radiosity, loaded.mesh);
    log_info("radiosity: read " + std::to_string(loaded.mesh.size()) + " patches from " +
             opts.radiosity);
  } else {
    r = compute_radiosity(loaded, opts.ff, opts.solver, opts.run, !opts.glb.empty());
  }
  render_and_write(opts, loaded, r.B, r.solved ? &r.indirect : nullptr, camera,
                   matrix_settings(opts, loaded, r),
                   {r.solved ? &r.bases : nullptr,
                    "--radiosity gives B without its form factors: nothing to split it by light "
                    "source"});
  return r.solved && r.solution.status != SolveStatus::Converged ? kExitNotConverged : kExitOk;
}

// --method hierarchical: load (no meshing), solve hierarchically, render the leaves.
int render_hierarchical(const RenderOptions& opts) {
  check_vertex_interp(opts.shade, false, "--method hierarchical");
  Scene scene = load_checked_scene(opts.scene, render_plan(opts));
  const Camera camera = make_camera(scene, opts.camera);
  const HierarchicalRun h = solve_scene_hierarchical(
      std::move(scene), make_hierarchical_options(opts.method, opts.method.hierarchical.epsilon,
                                                  opts.solver, opts.run));
  render_and_write(opts, h.loaded, h.B, nullptr, camera, hierarchical_settings_text(h),
                   {nullptr,
                    "hierarchical radiosity refines its links for the whole E: its solution is "
                    "not split by light source"});
  return hierarchical_status(h.stats) != SolveStatus::Converged ? kExitNotConverged : kExitOk;
}

}  // namespace

CLI::App* add_render_command(CLI::App& app, RenderOptions& opts) {
  auto* cmd = app.add_subcommand(
      "render",
      "Render the radiosity solution (HDR EXR + sRGB PNG), optionally per-vertex EXR/PLY");
  opts.scene.default_patches = 2000;
  opts.scene.require_emitter = true;  // B from E: a scene where nothing emits is refused
  add_scene_options(cmd, opts.scene);
  add_run_options(cmd, opts.run);
  add_method_options(cmd, opts.method);
  add_ff_options(cmd, opts.ff);
  add_solve_options(cmd, opts.solver, true);
  add_camera_options(cmd, opts.camera);
  add_shade_options(cmd, opts.shade);
  add_medium_options(cmd, opts.medium);
  add_declared(cmd, "--radiosity", opts.radiosity);
  add_declared(cmd, "-o,--output", opts.output);
  add_declared(cmd, "--png", opts.png);
  add_declared(cmd, "--vertex-exr", opts.vertex_exr);
  add_declared(cmd, "--ply", opts.ply);
  add_declared(cmd, "--glb", opts.glb);
  return cmd;
}

int run_render(const RenderOptions& opts) {
  static const MethodTable<RenderOptions> kMethods = {{"matrix", render_matrix},
                                                      {"hierarchical", render_hierarchical}};
  // Contradicting shading options: usage error before any work. A given B (--radiosity)
  // needs neither F nor a solver.
  const bool solves = opts.method.name == "matrix" && opts.radiosity.empty();
  return run_for_method(kMethods, opts,
                        render_selection("render", opts.method.name, solves, opts.ff,
                                         opts.solver.solver, opts.shade, opts.medium.active()));
}

}  // namespace lambert
