#include "pipeline/render_stages.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/exr.hpp"
#include "io/ply.hpp"
#include "io/tonemap.hpp"
#include "pipeline/problem.hpp"
#include "pipeline/solve_stage.hpp"

namespace lambert {
namespace {

Eigen::Vector3d vec3(const std::vector<double>& v) { return {v[0], v[1], v[2]}; }

}  // namespace

namespace {

// Distance along unit `d` from o to triangle (a, b, c) (Moller-Trumbore), or infinity.
double ray_triangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a, p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d s = o - a;
  const double u = s.dot(p) / det;
  if (u < 0.0 || u > 1.0) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) / det;
  if (v < 0.0 || u + v > 1.0) return std::numeric_limits<double>::infinity();
  const double t = e2.dot(q) / det;
  return t > 0.0 ? t : std::numeric_limits<double>::infinity();
}

}  // namespace

bool encloses_its_centre(const Scene& scene) {
  if (scene.faces.empty() || scene.faces.size() > kMaxEnclosureFaces) return false;
  const PatchMesh faces = mesh_scene(scene, {});  // one patch per face (or its triangles)
  const auto [lo, hi] = scene.bounds();
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const Eigen::Vector3d d = Eigen::Vector3d(dx, dy, dz).normalized();
        // The nearest face along d, by brute force (no BVH: the run builds its one BVH later).
        double nearest = std::numeric_limits<double>::infinity();
        std::int32_t hit = -1;
        for (std::int32_t i = 0; i < faces.size(); ++i) {
          const Patch& p = faces.patches[i];
          const auto& v = faces.vertices;
          for (int k = 1; k + 1 < p.vertex_count; ++k) {
            const double t =
                ray_triangle(centre, d, v[p.vertices[0]], v[p.vertices[k]], v[p.vertices[k + 1]]);
            if (t < nearest) {
              nearest = t;
              hit = i;
            }
          }
        }
        if (hit < 0 || !(faces.patches[hit].normal.dot(d) < 0.0)) return false;
      }
  return true;
}

Camera make_camera(const Scene& scene, const CameraArgs& args) {
  Camera cam = scene.camera;
  if (!cam.defined) {
    const auto [lo, hi] = scene.bounds();
    cam = framing_camera(lo, hi);
  }
  if (cam.automatic && args.view.empty() && args.eye.empty() && args.look_at.empty() &&
      encloses_its_centre(scene)) {  // a closed room seen from outside shows wall backs
    const auto [lo, hi] = scene.bounds();
    const int up = std::abs(cam.up.z()) > std::abs(cam.up.y()) ? 2 : 1;
    const int width = cam.width, height = cam.height;
    cam = room_camera(lo, hi, up);
    cam.width = width;
    cam.height = height;
  }
  if (!args.view.empty()) {  // about the scene's up axis: z when its camera has z up, else y
    const auto [lo, hi] = scene.bounds();
    const int up = std::abs(cam.up.z()) > std::abs(cam.up.y()) ? 2 : 1;
    const int width = cam.width, height = cam.height;
    cam = view_camera(lo, hi, up, args.view);
    cam.width = width;
    cam.height = height;
  }
  if (!args.eye.empty()) cam.eye = vec3(args.eye);
  if (!args.look_at.empty()) cam.look_at = vec3(args.look_at);
  if (!args.up.empty()) cam.up = vec3(args.up);
  if (args.fov > 0) cam.vfov_degrees = args.fov;
  if (!args.size.empty()) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(args.size.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 ||
        (x != 'x' && x != 'X') || w < 1 || h < 1 || w > 16384 || h > 16384)
      throw UsageError("--size must be WxH with 1 <= W, H <= 16384, got '" + args.size + "'");
    cam.width = w;
    cam.height = h;
  }
  if (!camera_problem(cam).empty())
    throw UsageError(
        "camera: --look-at must differ from --eye and --up must not be parallel "
        "to the view direction");
  return cam;
}

Selection render_selection(const std::string& command, const std::string& method, bool solves,
                           const FormFactorArgs& ff, const std::string& solver,
                           const ShadeArgs& shade, bool medium) {
  const Shading shading = resolve_shading(shade);
  Selection s{command,
              method,
              solves ? selected_estimator(ff) : "",
              {},
              shading_name(shading),
              medium,
              shading == Shading::Raytrace || shade.antialias > 1};
  if (solves) s.solvers = {solver};
  return s;
}

Shading resolve_shading(const ShadeArgs& args) {
  if (args.flat && !args.shading.empty() && args.shading != "flat")
    throw UsageError("--flat contradicts --shading " + args.shading);
  if (args.final_gather > 0 && (args.flat || (!args.shading.empty() && args.shading != "raytrace")))
    throw UsageError("--final-gather needs --shading raytrace (got " +
                     (args.flat ? std::string("--flat") : "--shading " + args.shading) + ")");
  if (args.shading == "raytrace" || args.final_gather > 0) return Shading::Raytrace;
  if (args.shading == "flat" || args.flat) return Shading::Flat;
  return Shading::Gouraud;
}

const char* shading_name(Shading shading) {
  switch (shading) {
    case Shading::Flat:
      return "flat";
    case Shading::Raytrace:
      return "raytrace";
    case Shading::Gouraud:
      break;
  }
  return "gouraud";
}

std::string shading_settings(const ShadeArgs& args, int specular_depth) {
  const Shading shading = resolve_shading(args);
  std::string s = std::string("shading=") + shading_name(shading);
  if (shading == Shading::Raytrace)
    s += " specular_depth=" + std::to_string(specular_depth) +
         " final_gather=" + std::to_string(args.final_gather);
  return s;
}

Json shading_json(const ShadeArgs& args, int specular_depth) {
  const Shading shading = resolve_shading(args);
  return {{"shading", shading_name(shading)},
          {"final_gather", args.final_gather},
          {"specular_depth", shading == Shading::Raytrace ? Json(specular_depth) : Json()}};
}

void check_vertex_interp(const ShadeArgs& args, bool has_form_factors, const std::string& why) {
  if (args.vertex_interp == "exact-direct" && !has_form_factors)
    throw UsageError("--vertex-interp exact-direct needs the form factors B is solved with (" +
                     why + " gives B without them)");
}

namespace {

// The bases of r over `problem` (E with the daylight's parts), as solve_bases.
void add_bases(const LoadedScene& scene, const RadiosityProblem& problem, const SolveOptions& so,
               RadiosityResult& r) {
  r.bases = emitter_sources(scene.mesh, r.daylight);
  r.bases_seconds = solve_emitter_bases(problem, r.B, so, r.bases);
  if (r.bases.size() > 1)
    log_info("relighting: " + std::to_string(r.bases.size()) +
             " light sources solved one by one in " + format_duration(r.bases_seconds));
}

}  // namespace

void solve_scene(const LoadedScene& scene, const FormFactors& F, const SolveOptions& solver,
                 const RunArgs& run, RadiosityResult& r, bool bases) {
  r.ff_stats = F.stats;
  r.ff_options = F.options;
  r.ff_entries = F.F.nonZeros();
  const Timer solve_timer;
  const RadiosityProblem problem = make_lit_problem(scene, F, run.seed, run.threads, &r.daylight);
  warn_about_lighting(scene.mesh, F.F);
  check_closed_lossless(scene.mesh, F);
  SolveOptions so = solver;
  so.threads = run.threads;
  set_memory_limit(so, run.max_memory);
  r.solution = solve_radiosity(problem, so);
  r.solve_seconds = solve_timer.seconds();
  r.B = r.solution.B;
  r.indirect = indirect_irradiance(scene.mesh, F.F, r.B);
  r.solved = true;
  int iterations = 0;
  for (const auto& c : r.solution.channels) iterations = std::max(iterations, c.iterations);
  log_info("solve: " + solver.solver + " " + to_string(r.solution.status) + " after " +
           std::to_string(iterations) + " iterations in " + format_duration(r.solve_seconds));
  if (r.solution.status != SolveStatus::Converged)
    log_warn("the solver did not converge (" + std::string(to_string(r.solution.status)) +
             "); results are written anyway");
  warn_about_non_reciprocity(r.solution, F.options);
  if (bases) add_bases(scene, problem, so, r);
}

void warn_about_non_reciprocity(const RadiositySolution& solution, const FormFactorOptions& ff) {
  double worst = 0.0;
  int channel = 0;
  for (int c = 0; c < 3; ++c) {
    const EnergyBalance& e = solution.energy[c];
    const double part = e.emitted > 0.0 ? std::abs(e.non_reciprocity_part) / e.emitted : 0.0;
    if (part > worst) {
      worst = part;
      channel = c;
    }
  }
  if (!(worst > kNonReciprocityWarning)) return;
  char line[400];
  std::snprintf(line, sizeof line,
                "F is not reciprocal (A_i F_ij != A_j F_ji): the energy balance misses %.2g of "
                "the emitted power (%s) through it, estimator %s with reciprocity %s%s",
                worst, channel_name(channel), ff.estimator.c_str(), ff.reciprocity.c_str(),
                ff.reciprocity == "none"
                    ? "; --reciprocity average balances it (or --estimator hybrid)"
                    : "");
  log_warn(line);
}

void solve_bases(const LoadedScene& scene, const FormFactors& F, const SolveOptions& solver,
                 const RunArgs& run, RadiosityResult& r) {
  SolveOptions so = solver;
  so.threads = run.threads;
  set_memory_limit(so, run.max_memory);
  add_bases(scene, make_lit_problem(scene, F, run.seed, run.threads, nullptr), so, r);
}

RadiosityResult compute_radiosity(const LoadedScene& scene, const FormFactorArgs& ff,
                                  const SolveOptions& solver, const RunArgs& run, bool bases) {
  RadiosityResult r;
  const Timer ff_timer;
  const FormFactors F = obtain_form_factors(scene, ff, run);
  r.ff_seconds = ff_timer.seconds();
  solve_scene(scene, F, solver, run, r, bases);
  return r;
}

std::string resolve_vertex_interp(const ShadeArgs& args, const LoadedScene& scene,
                                  const Eigen::MatrixX3d* indirect) {
  // Exact direct light sees emitters only directly: light they send through mirrors and
  // glass is in B but would be missing at the vertices.
  if (args.vertex_interp == "exact-direct" && scene.mesh.has_specular())
    throw UsageError(
        "--vertex-interp exact-direct computes direct light without mirrors and "
        "glass, and this scene has specular surfaces: use conservative");
  // Nor does it see the sky and the sun (the renderer draws the sun's shadows per pixel).
  if (args.vertex_interp == "exact-direct" && scene.scene.daylight.any())
    throw UsageError(
        "--vertex-interp exact-direct computes direct light from emitting surfaces only, and "
        "--sky or --sun light this scene: use conservative");
  if (args.vertex_interp != "auto") return args.vertex_interp;
  if (scene.scene.daylight.any()) return "conservative";
  if (scene.discontinuity && indirect && !scene.mesh.has_specular()) return "exact-direct";
  return scene.adapted ? "linear" : "conservative";
}

ShadedField shade_vertices(const LoadedScene& scene, const Eigen::MatrixX3d& B,
                           const Eigen::MatrixX3d* indirect, const ShadeArgs& args, int threads) {
  const Timer timer;
  ShadedField s;
  s.interpolation = resolve_vertex_interp(args, scene, indirect);
  if (s.interpolation == "exact-direct") {
    LAMBERT_CHECK(indirect, "exact-direct vertex values without the indirect irradiance");
    s.field = exact_direct_vertex_field(scene.scene, scene.mesh, B, *indirect, threads, &s.power);
  } else {
    s.field = interpolate_to_vertices(scene.mesh, B, parse_vertex_interpolation(s.interpolation),
                                      &s.power);
  }
  s.seconds = timer.seconds();
  return s;
}

std::string pixel_direct_obstacle(const LoadedScene& scene) {
  if (scene.mesh.has_specular())
    return "this scene has mirrors or glass (F carries light through them, shadow rays to the "
           "emitters do not)";
  if (scene.scene.daylight.any())
    return "--sky or --sun light this scene (its sun is drawn per pixel already)";
  const PixelDirectLight light(scene.scene, 1, 0.0);
  return light.why();
}

void check_pixel_direct(const ShadeArgs& args, const LoadedScene& scene) {
  if (args.direct_rays <= 0) return;
  if (const std::string why = pixel_direct_obstacle(scene); !why.empty())
    throw UsageError("--direct-rays does not apply: " + why + "; leave it out");
}

VertexField emitted_and_indirect_field(const PatchMesh& mesh, const Eigen::MatrixX3d& indirect,
                                       VertexInterpolation interpolation) {
  LAMBERT_CHECK(indirect.rows() == mesh.size(), "indirect irradiance does not match the mesh");
  Eigen::MatrixX3d values(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    values.row(i) = (p.emission + p.rho.cwiseProduct(indirect.row(i).transpose())).transpose();
  }
  return interpolate_to_vertices(mesh, values, interpolation);
}

Image render_scene(const LoadedScene& scene, const Eigen::MatrixX3d& B, const VertexField& field,
                   const Camera& camera, const ShadeArgs& args, int specular_depth,
                   const RunArgs& run, RenderStats* stats, const MediumView* medium,
                   const Eigen::MatrixX3d* indirect, const std::string& interpolation) {
  const Timer timer;
  const PatchMesh& mesh = scene.mesh;
  const Bvh& bvh = scene_bvh(scene, run.threads);
  RenderSettings settings;
  settings.shading = resolve_shading(args);
  settings.view.specular_depth = specular_depth;
  settings.view.final_gather = args.final_gather;
  settings.wireframe = args.wireframe;
  settings.antialias = args.antialias;
  settings.seed = run.seed;
  settings.threads = run.threads;
  settings.progress = !run.quiet;
  settings.medium = medium;
  std::unique_ptr<DirectLight> direct;
  if (args.final_gather > 0) direct = std::make_unique<DirectLight>(scene.scene);
  const Daylight& light = scene.scene.daylight;
  if (light.any()) settings.daylight = &light;
  if (light.has_sun()) {
    // The sun's light is drawn per pixel with its exact shadow: B and the vertex field
    // without each patch's mean sun part (the same shadow rays as the solve's).
    DaylightSources sources;
    sources.sun = sun_patch_part(scene, run.seed, run.threads);
    const Eigen::MatrixX3d without_sun = B - sources.reflected_sun(mesh);
    const VertexField field_without_sun = interpolate_to_vertices(
        mesh, without_sun, parse_vertex_interpolation(resolve_vertex_interp(args, scene, nullptr)));
    Image img = render(mesh, bvh, camera, without_sun, field_without_sun, settings, stats);
    if (stats) stats->seconds = timer.seconds();
    log_info("render: " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
             ", " + std::to_string(args.antialias * args.antialias) + " samples/pixel, " +
             shading_settings(args, specular_depth) + ", sun shadows per pixel in " +
             format_duration(timer.seconds()));
    return img;
  }
  // The emitters' direct light per pixel (pixel_direct.hpp): the field becomes E + rho I,
  // and each front hit adds rho H_d(x) from its shadow rays. By default not over an
  // exact-direct field (a discontinuity mesh's shadows follow its edges already).
  const int rays = args.direct_rays >= 0             ? args.direct_rays
                   : interpolation == "exact-direct" ? 0
                                                     : kDefaultDirectRays;
  std::unique_ptr<PixelDirectLight> pixel;
  VertexField without_direct;
  if (rays > 0 && indirect && !medium && settings.shading == Shading::Gouraud &&
      pixel_direct_obstacle(scene).empty()) {
    pixel = std::make_unique<PixelDirectLight>(scene.scene, rays, ff::kRayOffset * mesh.scale);
    without_direct = emitted_and_indirect_field(
        mesh, *indirect,
        parse_vertex_interpolation(interpolation == "exact-direct" ? "conservative"
                                                                   : interpolation));
    settings.pixel_direct = pixel.get();
  }
  Image img =
      render(mesh, bvh, camera, B, pixel ? without_direct : field, settings, stats, direct.get());
  if (stats) {
    stats->seconds = timer.seconds();  // including the BVH build when not yet built
    stats->direct_rays = pixel ? rays : 0;
  }
  log_info("render: " + std::to_string(camera.width) + "x" + std::to_string(camera.height) + ", " +
           std::to_string(args.antialias * args.antialias) + " samples/pixel, " +
           shading_settings(args, specular_depth) +
           (pixel ? ", direct light per pixel (" + std::to_string(rays) + " shadow rays a sample)"
                  : std::string()) +
           " in " + format_duration(timer.seconds()));
  return img;
}

double choose_exposure(const ShadeArgs& args, const Image& image, bool sky) {
  return args.exposure == "auto" ? auto_exposure(image, sky)
                                 : std::strtod(args.exposure.c_str(), nullptr);
}

std::vector<std::string> write_outputs(const OutputPaths& paths, const PatchMesh& mesh,
                                       const ShadedField& shaded, const Image& image, double ev,
                                       const std::string& settings, int threads) {
  std::vector<std::string> written;
  std::vector<std::function<void()>> jobs;
  if (!paths.image_exr.empty()) {
    jobs.push_back([&] {
      write_image_exr(paths.image_exr, image,
                      {"R,G,B: radiance L = B/pi (W m^-2 sr^-1, scene emission units per sr); "
                       "A: fraction of pixel samples that hit a surface",
                       settings,
                       {}});
    });
    written.push_back(paths.image_exr);
  }
  if (!paths.png.empty()) {
    jobs.push_back([&] { write_png_preview(paths.png, image, ev); });
    written.push_back(paths.png);
  }
  if (!paths.vertex_exr.empty()) {
    jobs.push_back([&] {
      write_vertex_exr(paths.vertex_exr, shaded.field,
                       {"R,G,B: radiosity B (W/m^2, the units of the scene's emission Ke); "
                        "P: position (scene length units); N: unit normal; surface: index into "
                        "surfaceNames",
                        settings, mesh.surface_names});
    });
    written.push_back(paths.vertex_exr);
  }
  if (!paths.ply.empty()) {
    jobs.push_back([&] { write_ply(paths.ply, mesh, shaded.field, ev, settings); });
    written.push_back(paths.ply);
  }
  parallel_for(static_cast<std::int64_t>(jobs.size()), 1, threads,
               [&](std::int64_t begin, std::int64_t end) {
                 for (auto k = begin; k < end; ++k) jobs[static_cast<size_t>(k)]();
               });
  return written;
}

std::pair<double, double> worst_power_error(const std::vector<SurfacePower>& power) {
  double after = 0.0, before = 0.0;
  for (const auto& s : power) {
    after = std::max(after, s.relative_error());
    before = std::max(before, s.area_weighted_relative_error());
  }
  return {after, before};
}

}  // namespace lambert
