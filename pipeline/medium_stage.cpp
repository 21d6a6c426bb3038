#include "pipeline/medium_stage.hpp"

#include <limits>
#include <sstream>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/medium_file.hpp"
#include "pipeline/option_specs.hpp"
#include "pipeline/problem.hpp"
#include "pipeline/solve_stage.hpp"

namespace lambert {
namespace {

bool given(const MediumArgs& args, const std::string& option) {
  return args.given && args.given(option);
}

Eigen::Vector3d rgb_or_zero(const std::vector<double>& v) {
  return v.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(v[0], v[1], v[2]);
}

}  // namespace

const std::vector<std::string>& medium_option_names() {
  static const std::vector<std::string> kNames = option_group("medium");
  return kNames;
}

std::string first_medium_option_given(const MediumArgs& args) {
  for (const std::string& o : medium_option_names())
    if (given(args, o)) return o;
  return "";
}

std::shared_ptr<const Medium> make_medium(const MediumArgs& args) {
  const bool coefficients =
      !args.sigma_a.empty() || !args.sigma_s.empty() || !args.emission.empty();
  if (!args.active()) {
    const std::string o = first_medium_option_given(args);
    if (!o.empty())
      throw UsageError(o +
                       " needs a medium: --medium-box (with --sigma-a/--sigma-s) or "
                       "--medium-grid");
    return nullptr;
  }
  if (!args.grid.empty()) {
    if (!args.box.empty() || coefficients)
      throw UsageError(
          "--medium-grid carries its own bounds and coefficients: drop --medium-box, "
          "--sigma-a, --sigma-s and --medium-emission");
    if (given(args, "--voxels") || given(args, "--voxel-size"))
      throw UsageError("--medium-grid sets its own resolution: drop --voxels and --voxel-size");
    auto m = std::make_shared<Medium>(read_medium_grid(args.grid));
    validate_medium(*m, args.grid);
    return m;
  }
  if (given(args, "--voxels") && given(args, "--voxel-size"))
    throw UsageError("give --voxels or --voxel-size, not both");
  const Eigen::Vector3d lo(args.box[0], args.box[1], args.box[2]);
  const Eigen::Vector3d hi(args.box[3], args.box[4], args.box[5]);
  if (!((hi - lo).minCoeff() > 0.0))
    throw UsageError("--medium-box: empty or inverted box (need X0 < X1, Y0 < Y1, Z0 < Z1)");
  const Eigen::Vector3d sa = rgb_or_zero(args.sigma_a), ss = rgb_or_zero(args.sigma_s);
  auto m = std::make_shared<Medium>(
      homogeneous_medium(lo, hi, medium_resolution(lo, hi, args.voxels, args.voxel_size), sa, ss,
                         rgb_or_zero(args.emission)));
  std::ostringstream src;
  src << "box " << lo.x() << ',' << lo.y() << ',' << lo.z() << ',' << hi.x() << ',' << hi.y() << ','
      << hi.z();
  m->source = src.str();
  validate_medium(*m, "--medium-box with --sigma-a/--sigma-s");
  return m;
}

void check_medium_scene(const PatchMesh& mesh, const ShadeArgs* shade) {
  if (mesh.has_specular())
    throw UsageError(
        "a participating medium needs a diffuse scene: the extended form factors "
        "of specular surfaces are not attenuated by the medium");
  if (shade == nullptr) return;
  if (resolve_shading(*shade) == Shading::Raytrace)
    throw UsageError(
        "--shading raytrace and --final-gather trace light without the medium: use "
        "gouraud or flat shading with a participating medium");
  check_vertex_interp(*shade, false, "a participating medium");
}

namespace {
MediumFactorOptions medium_factor_options(const MediumArgs& args, const RunArgs& run) {
  MediumFactorOptions mo;
  mo.rays = args.rays;
  mo.transmittance_samples = args.transmittance_samples;
  mo.seed = run.seed;
  mo.threads = run.threads;
  return mo;
}
}  // namespace

FormFactors medium_form_factors(const LoadedScene& scene, const FormFactors& surface,
                                const Medium& medium, const Zones& zones, const MediumArgs& args,
                                const RunArgs& run) {
  return extend_with_medium(scene.mesh, medium, zones, surface, medium_factor_options(args, run),
                            scene_bvh(scene, run.threads));
}

SurfaceFactors medium_surface_table(const LoadedScene& scene, const FormFactors& surface,
                                    const FormFactors& extended, const Medium& medium,
                                    const Zones& zones, const MediumArgs& args,
                                    const RunArgs& run) {
  return medium_surface_factors(scene.mesh, surface, extended, medium, zones,
                                medium_factor_options(args, run), scene_bvh(scene, run.threads));
}

MediumResult solve_scene_with_medium(const LoadedScene& scene, const FormFactors& surface,
                                     std::shared_ptr<const Medium> medium, const MediumArgs& args,
                                     const SolveOptions& solver, const RunArgs& run,
                                     RadiosityResult& r) {
  MediumResult out;
  out.medium = std::move(medium);
  const Medium& m = *out.medium;
  const PatchMesh& mesh = scene.mesh;
  const std::int32_t n = mesh.size();
  const Timer timer;
  out.zones = make_zones(m);
  const Zones& zones = out.zones;
  // A loaded F may hold the zones already (obtain_form_factors checked it is this medium's).
  FormFactors extended;
  if (surface.options.contents.medium_zones == 0) {
    warn_about_lighting(mesh, surface.F);
    check_closed_lossless(mesh, surface);
    extended = medium_form_factors(scene, surface, m, zones, args, run);
  }
  const FormFactors& F = surface.options.contents.medium_zones == 0 ? extended : surface;
  LAMBERT_CHECK(F.F.rows() == n + zones.size(), "extended F does not match the zones");
  out.seconds = timer.seconds();
  out.loaded = surface.options.contents.medium_zones > 0;
  out.rays = F.options.contents.medium_rays;
  out.transmittance_samples = F.options.contents.transmittance_samples;
  out.stats = F.stats;
  out.entries = F.F.nonZeros();
  log_info("medium: " + std::to_string(zones.size()) + " zones, " + std::to_string(out.entries) +
           " entries in " + format_duration(out.seconds));

  const RadiosityProblem problem =
      make_extended_problem(mesh, F.F, zones.albedo, zones.emission, zones.area);
  const std::int32_t total = n + zones.size();

  r.ff_stats = out.stats;
  r.ff_options = F.options;
  r.ff_entries = out.entries;
  const Timer solve_timer;
  SolveOptions so = solver;
  so.threads = run.threads;
  set_memory_limit(so, run.max_memory);
  r.solution = solve_radiosity(problem, so);
  r.solve_seconds = solve_timer.seconds();
  r.B = r.solution.B.topRows(n);
  r.indirect.resize(0, 3);
  r.solved = true;

  // Absorbed power split: A_i (1 - rho_i) H_i over patches and over zones, H = F B.
  for (int c = 0; c < 3; ++c) {
    Eigen::VectorXd H(total);
    problem.F->apply(r.solution.B.col(c), H, run.threads);
    const Eigen::ArrayXd absorbed =
        problem.area.array() * (1.0 - problem.rho.col(c).array()) * H.array();
    out.absorbed_surfaces[c] = absorbed.head(n).sum();
    out.absorbed_medium[c] = absorbed.tail(zones.size()).sum();
  }
  out.view.medium = out.medium.get();
  out.view.voxel_B = Eigen::MatrixX3d::Zero(m.voxels(), 3);
  for (std::int32_t z = 0; z < zones.size(); ++z)
    out.view.voxel_B.row(zones.voxel[z]) = r.solution.B.row(n + z);
  int iterations = 0;
  for (const auto& c : r.solution.channels) iterations = std::max(iterations, c.iterations);
  log_info("solve: " + solver.solver + " " + to_string(r.solution.status) + " after " +
           std::to_string(iterations) + " iterations in " + format_duration(r.solve_seconds) +
           " (" + std::to_string(n) + " patches + " + std::to_string(zones.size()) + " zones)");
  return out;
}

Json medium_json(const MediumResult& m) {
  const Medium& md = *m.medium;
  Json j = {{"source", md.source},
            {"bounds", {md.lo.x(), md.lo.y(), md.lo.z(), md.hi.x(), md.hi.y(), md.hi.z()}},
            {"resolution", {md.resolution.x(), md.resolution.y(), md.resolution.z()}},
            {"zones", m.zones.size()},
            {"rays_per_unknown", m.rays},
            {"transmittance_samples", m.transmittance_samples},
            {"loaded", m.loaded},
            {"entries", m.entries},
            {"seconds", m.seconds}};
  j["absorbed_surfaces"] = {m.absorbed_surfaces[0], m.absorbed_surfaces[1], m.absorbed_surfaces[2]};
  j["absorbed_medium"] = {m.absorbed_medium[0], m.absorbed_medium[1], m.absorbed_medium[2]};
  return j;
}

std::string medium_settings_text(const MediumResult& m) {
  const Medium& md = *m.medium;
  std::ostringstream s;
  s << "medium=\"" << md.source << "\" voxels=" << md.resolution.x() << 'x' << md.resolution.y()
    << 'x' << md.resolution.z() << " medium_rays=" << m.rays
    << " transmittance_samples=" << m.transmittance_samples;
  return s.str();
}

}  // namespace lambert
