#include "apps/heat_outputs.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "apps/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/colormap.hpp"
#include "io/exr.hpp"
#include "io/ply.hpp"
#include "io/vtu.hpp"
#include "pipeline/solve_stage.hpp"
#include "pipeline/viewer_stage.hpp"

namespace lambert {
namespace {

const char* condition_name(const SurfaceCondition& c) {
  return c.known_temperature ? "temperature" : "heat_flux";
}

// A number, or null when it is not finite (an undefined temperature).
Json number_or_null(double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); }

// The per-vertex field of (T, q, J), interpolated area-weighted (a temperature is no power:
// the conservative rescale does not apply).
VertexField heat_vertex_field(const HeatReport& r) {
  const ThermalSolution& s = *r.solution;
  Eigen::MatrixX3d values(s.T.size(), 3);
  values.col(0) = s.T;
  values.col(1) = s.q;
  values.col(2) = s.J;
  return interpolate_to_vertices(r.loaded->mesh, values, parse_vertex_interpolation("area"));
}

// Range of column `c` of the field's finite values (lo == hi widened so the map is defined).
std::pair<double, double> value_range(const VertexField& f, int c) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::int32_t k = 0; k < f.size(); ++k) {
    const double v = f.values(k, c);
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (!(lo <= hi)) lo = hi = 0.0;
  if (hi == lo) hi = lo + 1.0;
  return {lo, hi};
}

double unit_position(double v, std::pair<double, double> range) {
  return (v - range.first) / (range.second - range.first);
}

// The conductors' section of the summary: the matrix up to kJsonConductorSurfaces surfaces,
// its reciprocity max |GR − GRᵀ| / max |GR| (F's non-reciprocity and the solver's tolerance).
Json conductors_json(const HeatReport& r) {
  const RadiativeConductors& c = *r.conductors;
  const double scale = c.GR.cwiseAbs().maxCoeff();
  Json j = {{"units", "m^2 (multiply by sigma (T_i^4 - T_j^4) for W)"},
            {"file", r.options->conductors},
            {"status", to_string(c.status)},
            {"solves", c.solves},
            {"residual", c.residual},
            {"seconds", c.seconds},
            {"reciprocity_error",
             scale > 0.0 ? (c.GR - c.GR.transpose()).cwiseAbs().maxCoeff() / scale : 0.0}};
  if (c.GR.rows() > kJsonConductorSurfaces) return j;
  Json rows = Json::array();
  for (Eigen::Index s = 0; s < c.GR.rows(); ++s) {
    Json row = Json::array();
    for (Eigen::Index t = 0; t < c.GR.cols(); ++t) row.push_back(c.GR(s, t));
    rows.push_back(row);
  }
  Json env = Json::array(), emittance = Json::array();
  for (Eigen::Index s = 0; s < c.GR.rows(); ++s) {
    env.push_back(c.environment[s]);
    emittance.push_back(c.emittance[s]);
  }
  j["surfaces"] = r.loaded->mesh.surface_names;
  j["GR_m2"] = rows;
  j["environment_m2"] = env;
  j["emittance_m2"] = emittance;
  return j;
}

}  // namespace

void add_heat_output_options(CLI::App* cmd, HeatImageArgs& args) {
  add_declared(cmd, "--vertex-exr", args.vertex_exr);
  add_declared(cmd, "--ply", args.ply);
  add_declared(cmd, "--image", args.image);
  add_declared(cmd, "--image-quantity", args.quantity);
  add_declared(cmd, "--glb", args.glb);
  add_camera_options(cmd, args.camera);
}

namespace {

// --glb FILE: the viewer page beside it, FILE with .html.
std::string heat_page_path(const HeatImageArgs& args) {
  return args.glb.empty() ? ""
                          : std::filesystem::path(args.glb).replace_extension(".html").string();
}

}  // namespace

void check_heat_output_options(const HeatImageArgs& args, const OptionGiven& given) {
  if (!given) return;
  const bool camera_read = !args.image.empty() || !args.glb.empty();
  for (const char* name : {"--eye", "--look-at", "--up", "--fov", "--size", "--view"})
    if (given(name) && !camera_read)
      throw UsageError(std::string(name) +
                       " does not apply to heat without --image or --glb (it sets their camera)");
  if (given("--image-quantity") && args.image.empty() && args.ply.empty())
    throw UsageError(
        "--image-quantity does not apply to heat without --image or --ply (it "
        "chooses what they colour)");
}

void add_heat_outputs_to_plan(JobPlan& plan, const HeatImageArgs& args) {
  plan.outputs.push_back({"--vertex-exr", args.vertex_exr});
  plan.outputs.push_back({"--ply", args.ply});
  plan.outputs.push_back({"--image", args.image});
  plan.outputs.push_back({"--glb", args.glb});
  plan.outputs.push_back({"--glb", heat_page_path(args)});
}

HeatPaths heat_paths(const HeatOptions& o) {
  namespace fs = std::filesystem;
  HeatPaths p;
  p.conductors_csv = o.conductors;
  const OutputPrefix prefix = plan_output_prefix(o.output, "heat");
  std::error_code ec;
  const bool folder = !prefix.folder.empty() || fs::is_directory(o.output, ec);
  if (!folder && fs::path(o.output).extension() == ".vtu") {
    p.vtu = o.output;
    p.json = fs::path(o.output).replace_extension(".json").string();
    p.patches_csv = o.patches_csv;
    return p;
  }
  if (!folder && (writes_in_place(o.output) || fs::path(o.output).extension() == ".csv")) {
    p.surfaces_csv = o.output;
    p.json = summary_beside(o.output);
    p.patches_csv = o.patches_csv;
    return p;
  }
  p.folder = prefix.folder;
  p.surfaces_csv = prefix.prefix + "_surfaces.csv";
  p.patches_csv = o.patches_csv.empty() ? prefix.prefix + "_patches.csv" : o.patches_csv;
  p.json = prefix.prefix + ".json";
  return p;
}

void add_heat_paths_to_plan(JobPlan& plan, const HeatPaths& paths) {
  plan.outputs.push_back({"-o", paths.surfaces_csv});
  plan.outputs.push_back({"-o", paths.vtu});
  plan.outputs.push_back({"--patches-csv", paths.patches_csv});
  plan.outputs.push_back({"the summary", paths.json});
  plan.outputs.push_back({"--conductors", paths.conductors_csv});
  if (!paths.folder.empty()) plan.folders.push_back(paths.folder);
}

void write_heat_conductors_csv(const std::string& path, const HeatReport& r) {
  const auto& names = r.loaded->mesh.surface_names;
  const RadiativeConductors& c = *r.conductors;
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "GR_m2";
    for (const auto& n : names) out << ',' << csv_field(n);
    out << ",environment\n";
    for (Eigen::Index s = 0; s < c.GR.rows(); ++s) {
      out << csv_field(names[s]);
      for (Eigen::Index t = 0; t < c.GR.cols(); ++t) out << ',' << csv_number(c.GR(s, t));
      out << ',' << csv_number(c.environment[s]) << '\n';
    }
  });
}

void write_heat_surfaces_csv(const std::string& path, const HeatReport& r) {
  const auto& names = r.loaded->mesh.surface_names;
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "surface,emissivity,condition,given,area_m2,patches,T_mean_K,T_min_K,T_max_K,J_W_m2,"
           "q_W_m2,Q_W\n";
    for (size_t s = 0; s < names.size(); ++s) {
      const SurfaceHeat& h = (*r.surfaces)[s];
      const SurfaceCondition& c = (*r.conditions)[s];
      out << csv_field(names[s]) << ',' << csv_number(c.emissivity) << ',' << condition_name(c)
          << ',' << csv_number(c.value) << ',' << csv_number(h.area) << ',' << h.patches << ','
          << csv_number(h.T) << ',' << csv_number(h.T_min) << ',' << csv_number(h.T_max) << ','
          << csv_number(h.J) << ',' << csv_number(h.q) << ',' << csv_number(h.Q) << '\n';
    }
    out << "environment,,,,,,,,,,," << csv_number(r.solution->environment_power) << '\n';
  });
}

void write_heat_patches_csv(const std::string& path, const HeatReport& r) {
  const PatchMesh& mesh = r.loaded->mesh;
  const ThermalSolution& s = *r.solution;
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "patch,surface,area_m2,emissivity,T_K,J_W_m2,H_W_m2,q_W_m2,Q_W\n";
    for (std::int32_t i = 0; i < mesh.size(); ++i)
      out << i << ',' << csv_field(mesh.surface_names[mesh.patches[i].surface]) << ','
          << csv_number(r.problem->area[i]) << ',' << csv_number(r.problem->emissivity[i]) << ','
          << csv_number(s.T[i]) << ',' << csv_number(s.J[i]) << ',' << csv_number(s.H[i]) << ','
          << csv_number(s.q[i]) << ',' << csv_number(s.Q[i]) << '\n';
  });
}

void write_heat_vtu(const std::string& path, const HeatReport& r) {
  const PatchMesh& mesh = r.loaded->mesh;
  const ThermalSolution& s = *r.solution;
  const auto column = [](const Eigen::VectorXd& v) {
    return std::vector<double>(v.data(), v.data() + v.size());
  };
  VtuContent c;
  std::vector<std::int32_t> surface(mesh.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) surface[i] = mesh.patches[i].surface;
  c.cell_data = {{"T_K", column(s.T)},
                 {"q_W_m2", column(s.q)},
                 {"Q_W", column(s.Q)},
                 {"J_W_m2", column(s.J)},
                 {"H_W_m2", column(s.H)},
                 {"emissivity", column(r.problem->emissivity)},
                 {"area_m2", column(r.problem->area)},
                 {"surface", surface}};
  const auto& names = mesh.surface_names;
  const auto n = names.size();
  std::vector<double> eps(n), given(n), area(n), t(n), t_min(n), t_max(n), j(n), q(n), big_q(n);
  std::vector<std::int32_t> known_t(n), patches(n);
  for (size_t k = 0; k < n; ++k) {
    const SurfaceHeat& h = (*r.surfaces)[k];
    const SurfaceCondition& cond = (*r.conditions)[k];
    eps[k] = cond.emissivity;
    known_t[k] = cond.known_temperature ? 1 : 0;
    given[k] = cond.value;
    area[k] = h.area;
    patches[k] = h.patches;
    t[k] = h.T;
    t_min[k] = h.T_min;
    t_max[k] = h.T_max;
    j[k] = h.J;
    q[k] = h.q;
    big_q[k] = h.Q;
  }
  c.field_data = {vtu_string_array("surface_names", names),
                  {"surface_emissivity", eps},
                  {"surface_known_temperature", known_t},
                  {"surface_given", given},
                  {"surface_area_m2", area},
                  {"surface_patches", patches},
                  {"surface_T_mean_K", t},
                  {"surface_T_min_K", t_min},
                  {"surface_T_max_K", t_max},
                  {"surface_J_W_m2", j},
                  {"surface_q_W_m2", q},
                  {"surface_Q_W", big_q},
                  {"environment_W", std::vector<double>{s.environment_power}},
                  {"closure_W", std::vector<double>{s.closure}}};
  c.comments = {"lambert heat of " + r.loaded->scene.source + ", conditions " + r.options->surfaces,
                "points in the scene's unit (" + r.options->length_unit +
                    "); T K, q J H W/m^2 (q net, leaving), Q W, area m^2; NaN: undefined T",
                "surface_known_temperature 1: surface_given is T (K), 0: q (W/m^2)"};
  for (size_t k = 0; k < n; ++k)
    c.comments.push_back("surface " + std::to_string(k) + ": " + names[k]);
  write_vtu(path, mesh, c);
}

Json heat_json(const HeatReport& r) {
  const HeatOptions& o = *r.options;
  const ThermalSolution& s = *r.solution;
  const ChannelReport& ch = s.radiosity.channels[0];
  Json surfaces = Json::array();
  const auto& names = r.loaded->mesh.surface_names;
  for (size_t k = 0; k < names.size(); ++k) {
    const SurfaceHeat& h = (*r.surfaces)[k];
    const SurfaceCondition& c = (*r.conditions)[k];
    surfaces.push_back({{"name", names[k]},
                        {"emissivity", c.emissivity},
                        {"condition", condition_name(c)},
                        {"given", c.value},
                        {"area_m2", h.area},
                        {"patches", h.patches},
                        {"temperature_K", number_or_null(h.T)},
                        {"temperature_min_K", number_or_null(h.T_min)},
                        {"temperature_max_K", number_or_null(h.T_max)},
                        {"radiosity_W_m2", h.J},
                        {"heat_flux_W_m2", h.q},
                        {"power_W", h.Q}});
  }
  double surface_sum = 0.0;
  for (const auto& h : *r.surfaces) surface_sum += h.Q;
  Json j{{"scene", r.loaded->scene.source},
         {"surfaces_file", o.surfaces},
         {"patches", r.loaded->mesh.size()},
         {"settings",
          {{"length_unit", o.length_unit},
           {"ambient_temperature_K", r.problem->ambient_temperature},
           {"stefan_boltzmann", kStefanBoltzmann},
           {"solver", o.solve.solver},
           {"tol", o.solve.tol},
           {"max_iterations", o.solve.max_iterations},
           {"form_factors", ff_settings_json(r.ff->options, o.ff.ff_file)}}},
         {"status", to_string(s.radiosity.status)},
         {"iterations", ch.iterations},
         {"residual", ch.residual},
         {"closure",
          {{"surfaces_W", surface_sum},
           {"environment_W", s.environment_power},
           {"sum_W", s.closure},
           {"max_flux_mismatch_W_m2", s.max_flux_mismatch}}},
         {"undefined_temperatures", s.undefined_temperatures},
         {"surfaces", surfaces},
         {"timings",
          {{"load_and_mesh_seconds", r.timings.load_seconds},
           {"form_factors_seconds", r.timings.form_factors_seconds},
           {"solve_seconds", r.timings.solve_seconds},
           {"total_seconds", r.timings.total_seconds}}}};
  if (r.conductors != nullptr) j["conductors"] = conductors_json(r);
  return j;
}

void print_heat_table(const HeatReport& r) {
  const ThermalSolution& s = *r.solution;
  const ChannelReport& ch = s.radiosity.channels[0];
  std::printf("heat: %d patches, solver %s: %s, %d iterations, residual %.3e\n",
              r.loaded->mesh.size(), r.options->solve.solver.c_str(), to_string(s.radiosity.status),
              ch.iterations, ch.residual);
  std::printf("%-24s %6s %-11s %12s %10s %10s %12s %14s\n", "surface", "eps", "condition",
              "area [m2]", "T [K]", "J [W/m2]", "q [W/m2]", "Q [W]");
  const auto& names = r.loaded->mesh.surface_names;
  for (size_t k = 0; k < names.size(); ++k) {
    const SurfaceHeat& h = (*r.surfaces)[k];
    const SurfaceCondition& c = (*r.conditions)[k];
    std::printf("%-24s %6.3f %-11s %12.6g %10.6g %10.6g %12.6g %14.8g\n", names[k].c_str(),
                c.emissivity, condition_name(c), h.area, h.T, h.J, h.q, h.Q);
  }
  std::printf("%-24s %6s %-11s %12s %10s %10s %12s %14.8g\n", "environment", "", "", "", "", "", "",
              s.environment_power);
  std::printf("closure: sum of Q + environment = %.3e W\n", s.closure);
}

std::vector<std::string> write_heat_images(const HeatReport& r) {
  const HeatImageArgs& a = r.options->images;
  std::vector<std::string> written;
  if (!a.glb.empty()) {
    const Camera camera = make_camera(r.loaded->scene, a.camera);
    const GlbContent glb =
        heat_viewer_glb({r.loaded->mesh, r.solution->T, r.solution->q, r.solution->J, camera,
                         r.loaded->scene.source, "lambert heat --surfaces " + r.options->surfaces});
    const std::string stem = std::filesystem::path(a.glb).stem().string();
    for (const std::string& f : write_viewer(glb, a.glb, heat_page_path(a), stem))
      written.push_back(f);
  }
  if (a.vertex_exr.empty() && a.ply.empty() && a.image.empty()) return written;
  const VertexField field = heat_vertex_field(r);
  const int column = a.quantity == "temperature" ? 0 : 1;
  const auto range = value_range(field, column);
  const std::string title = column == 0 ? "T [K]" : "q [W/m2]";
  if (!a.vertex_exr.empty()) {
    ExrInfo info;
    info.units = "temperature K, heat_flux W/m^2 (net, leaving), radiosity W/m^2";
    info.settings = "lambert heat --surfaces " + r.options->surfaces;
    info.surface_names = r.loaded->mesh.surface_names;
    info.value_channels = {"temperature", "heat_flux", "radiosity"};
    write_vertex_exr(a.vertex_exr, field, info);
    written.push_back(a.vertex_exr);
  }
  if (!a.ply.empty()) {
    PlyValues values;
    values.names = {"temperature", "heat_flux", "radiosity"};
    values.comments = {"colours: viridis of " + title + " from " + std::to_string(range.first) +
                           " to " + std::to_string(range.second),
                       "temperature K, heat_flux W/m^2 (net, leaving), radiosity W/m^2"};
    for (std::int32_t k = 0; k < field.size(); ++k)
      values.colours.push_back(colormap_srgb8(unit_position(field.values(k, column), range)));
    write_ply_values(a.ply, r.loaded->mesh, field, values);
    written.push_back(a.ply);
  }
  if (!a.image.empty()) {
    // Colours rendered as radiance: the renderer shows B/π, so B = π × the linear colour
    // comes back as the map's byte colour at EV 0.
    VertexField colours = field;
    for (std::int32_t k = 0; k < field.size(); ++k)
      colours.values.row(k) =
          M_PI * srgb8_to_linear(colormap_srgb8(unit_position(field.values(k, column), range)))
                     .transpose();
    const PatchMesh& mesh = r.loaded->mesh;
    Eigen::MatrixX3d patch_colour(mesh.size(), 3);
    const Eigen::VectorXd& v = column == 0 ? r.solution->T : r.solution->q;
    for (std::int32_t i = 0; i < mesh.size(); ++i)
      patch_colour.row(i) =
          M_PI * srgb8_to_linear(colormap_srgb8(unit_position(v[i], range))).transpose();
    ShadeArgs shade;
    shade.exposure = "0";
    const Camera camera = make_camera(r.loaded->scene, a.camera);
    const Image image =
        render_scene(*r.loaded, patch_colour, colours, camera, shade, 0, r.options->run, nullptr);
    write_png_with_legend(a.image, image, range.first, range.second, title);
    written.push_back(a.image);
  }
  return written;
}

}  // namespace lambert
