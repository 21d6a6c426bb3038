#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "apps/command_outputs.hpp"
#include "apps/commands.hpp"
#include "apps/distributed.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/analysis.hpp"
#include "io/ff_file.hpp"
#include "io/json.hpp"
#include "pipeline/ff_stage.hpp"

namespace lambert {
namespace {

// The settings stored with a saved F (recovered by `--ff`) and written to its report.
std::string settings_string(const FormFactorOptions& o, const LoadedScene& s) {
  std::ostringstream ss;
  ss << format_ff_settings(o) << " patches=" << s.mesh.size() << " max_edge=" << s.max_edge;
  return ss.str();
}

double row_sum(const SparseF& F, std::int32_t i) {
  double sum = 0.0;
  for (SparseF::InnerIterator it(F, i); it; ++it) sum += it.value();
  return sum;
}

Json diagnostics_json(const LoadedScene& s, const FormFactors& ff, const FormFactorDiagnostics& d,
                      const std::string& settings) {
  Json worst = Json::array();
  for (auto i : d.worst_rows)
    worst.push_back({{"patch", i},
                     {"surface", s.mesh.surface_names[s.mesh.patches[i].surface]},
                     {"row_sum", row_sum(ff.F, i)}});
  return {{"scene", s.scene.source},
          {"settings", settings},
          {"form_factors", ff_settings_json(ff.options, "")},
          {"reciprocity_averaging", reciprocity_json(ff)},
          {"patches", d.n},
          {"nnz", d.nnz},
          {"pairs_tested", ff.stats.pairs_tested},
          {"pairs_culled", ff.stats.pairs_culled},
          {"pairs_unverified", ff.stats.pairs_unverified},
          {"unverified_exchange_share", unverified_exchange_share(ff, s.mesh)},
          {"pairs_short_of_target", ff.stats.pairs_short_of_target},
          {"rays", ff.stats.rays},
          {"seconds", ff.stats.seconds},
          {"rays_per_second", ff.stats.seconds > 0 ? ff.stats.rays / ff.stats.seconds : 0.0},
          {"row_sums",
           {{"min", d.row_sum_min},
            {"max", d.row_sum_max},
            {"mean", d.row_sum_mean},
            {"histogram_max", FormFactorDiagnostics::kHistogramMax},
            {"histogram", d.row_sum_histogram},
            {"worst_rows", worst}}},
          {"reciprocity_max", d.reciprocity_max},
          {"reciprocity_max_relative", d.reciprocity_max_relative},
          {"entries_negative", d.negative},
          {"entries_above_one", d.above_one}};
}

void print_diagnostics(const LoadedScene& s, const FormFactors& ff,
                       const FormFactorDiagnostics& d) {
  std::printf("patches %d, nnz %lld (%.1f%% dense), pairs tested %lld, culled %lld\n", d.n,
              static_cast<long long>(d.nnz), 100.0 * d.nnz / std::max(1.0, double(d.n) * d.n),
              static_cast<long long>(ff.stats.pairs_tested),
              static_cast<long long>(ff.stats.pairs_culled));
  std::printf("rays %s in %s (%s rays/s)\n", format_si(double(ff.stats.rays)).c_str(),
              format_duration(ff.stats.seconds).c_str(),
              format_si(ff.stats.seconds > 0 ? ff.stats.rays / ff.stats.seconds : 0).c_str());
  std::printf("row sums: min %.6f  mean %.6f  max %.6f\n", d.row_sum_min, d.row_sum_mean,
              d.row_sum_max);
  if (ff.specular_continued.size() == d.n && d.n > 0) {
    // Extended rows count light again after each specular bounce; what ends somewhere (row
    // sum minus what was carried on) is the quantity bounded by 1.
    double lo = 1e300, hi = -1e300, mean = 0.0;
    for (std::int32_t i = 0; i < d.n; ++i) {
      const double t = row_sum(ff.F, i) - ff.specular_continued[i];
      lo = std::min(lo, t), hi = std::max(hi, t), mean += t / d.n;
    }
    std::printf(
        "extended: row sums minus the part carried on by mirrors and glass: min %.6f  "
        "mean %.6f  max %.6f\n",
        lo, mean, hi);
  }
  std::printf("row-sum histogram (bins of %.2f from 0):",
              FormFactorDiagnostics::kHistogramMax / FormFactorDiagnostics::kHistogramBins);
  for (auto c : d.row_sum_histogram) std::printf(" %lld", static_cast<long long>(c));
  std::printf("\nlargest row sums:");
  for (auto i : d.worst_rows)
    std::printf(" %d (%s) %.6f;", i, s.mesh.surface_names[s.mesh.patches[i].surface].c_str(),
                row_sum(ff.F, i));
  std::printf("\nreciprocity residual max |A_i F_ij - A_j F_ji| = %.3g (relative %.3g)\n",
              d.reciprocity_max, d.reciprocity_max_relative);
  std::printf("entries < 0: %lld, entries > 1: %lld\n", static_cast<long long>(d.negative),
              static_cast<long long>(d.above_one));
}

// Rows of a dense matrix as nested JSON arrays.
Json rows_json(const Eigen::MatrixXd& m) {
  Json rows = Json::array();
  for (Eigen::Index g = 0; g < m.rows(); ++g) {
    Json& row = rows.emplace_back(Json::array());
    for (Eigen::Index h = 0; h < m.cols(); ++h) row.push_back(m(g, h));
  }
  return rows;
}

Json surface_json(const SurfaceFactors& sf) {
  return {{"surfaces", sf.surfaces},
          {"areas", sf.areas},
          {"F", rows_json(sf.F)},
          {"stderr", sf.has_stderr ? rows_json(sf.stderr_F) : Json()}};
}

Json point_json(const PointFactors& pf) {
  return {{"surfaces", pf.surfaces}, {"F", pf.F}, {"stderr", pf.stderr_F}};
}

Eigen::Vector3d parse_vec(const std::vector<double>& v) { return {v[0], v[1], v[2]}; }

// The medium's zones appended to F (media.hpp). Returns the report section and prints how
// the patches' power divides between the surfaces and the medium.
Json extend_with_zones(const LoadedScene& s, const Medium& medium, const MediumArgs& args,
                       const RunArgs& run, FormFactors& ff, Eigen::VectorXd& zone_area) {
  const Timer timer;
  const Zones zones = make_zones(medium);
  zone_area = zones.area;
  FormFactors extended = medium_form_factors(s, ff, medium, zones, args, run);
  const double seconds = timer.seconds();
  ff = std::move(extended);
  const std::int32_t n = s.mesh.size(), m = zones.size();
  // Per patch row: the part its power sends into the medium (the zone columns).
  double into_min = n > 0 ? 1e300 : 0.0, into_max = 0.0, into_mean = 0.0;
  for (std::int32_t i = 0; i < n; ++i) {
    double into = 0.0;
    for (SparseF::InnerIterator it(ff.F, i); it; ++it)
      if (it.col() >= n) into += it.value();
    into_min = std::min(into_min, into), into_max = std::max(into_max, into);
    into_mean += into / n;
  }
  double zone_min = m > 0 ? 1e300 : 0.0, zone_max = 0.0;
  for (std::int32_t z = 0; z < m; ++z) {
    const double sum = row_sum(ff.F, n + z);
    zone_min = std::min(zone_min, sum), zone_max = std::max(zone_max, sum);
  }
  const Eigen::Vector3i& res = medium.resolution;
  std::printf("medium %s, %dx%dx%d voxels, %d zones: %lld entries in %s\n", medium.source.c_str(),
              res.x(), res.y(), res.z(), m, static_cast<long long>(ff.F.nonZeros()),
              format_duration(seconds).c_str());
  std::printf(
      "patch rows into the medium: min %.6f  mean %.6f  max %.6f; zone row sums: min "
      "%.6f  max %.6f\n",
      into_min, into_mean, into_max, zone_min, zone_max);
  return {
      {"source", medium.source},
      {"bounds",
       {medium.lo.x(), medium.lo.y(), medium.lo.z(), medium.hi.x(), medium.hi.y(), medium.hi.z()}},
      {"resolution", {res.x(), res.y(), res.z()}},
      {"zones", m},
      {"rays_per_unknown", args.rays},
      {"transmittance_samples", args.transmittance_samples},
      {"entries", ff.F.nonZeros()},
      {"seconds", seconds},
      {"patch_rows_into_medium", {{"min", into_min}, {"mean", into_mean}, {"max", into_max}}},
      {"zone_row_sums", {{"min", zone_min}, {"max", zone_max}}}};
}

}  // namespace

CLI::App* add_formfactors_command(CLI::App& app, FormFactorsOptions& opts) {
  auto* cmd = app.add_subcommand("formfactors",
                                 "Compute form factors F and save them (Matrix Market or binary), "
                                 "or surface/point view factors");
  opts.scene.default_patches = 2000;
  add_scene_options(cmd, opts.scene);
  add_run_options(cmd, opts.run);
  add_ff_options(cmd, opts.ff, false, /*tol_alias=*/true);
  add_declared(cmd, "-o,--output", opts.output);
  add_declared(cmd, "--report", opts.report);
  add_declared(cmd, "--stderr", opts.with_stderr);
  add_declared(cmd, "--ff-precision", opts.precision);
  auto* by = add_declared(cmd, "--by-surface", opts.by_surface);
  auto* pt = add_declared(cmd, "--point", opts.point);
  auto* nm = add_declared(cmd, "--normal", opts.normal);
  pt->needs(nm);
  nm->needs(pt);
  pt->excludes(by);
  add_medium_options(cmd, opts.medium);
  add_distributed_options(cmd, opts.dist, false);
  return cmd;
}

void write_formfactors_outputs(const FormFactorsOptions& opts, const LoadedScene& scene,
                               FormFactors& ff, const std::string& report, const Json& distributed,
                               const Medium* medium) {
  namespace fs = std::filesystem;
  warn_about_lighting(scene.mesh, ff.F);
  check_closed_lossless(scene.mesh, ff, false);
  // Diagnostics of the patches' F; with a medium they describe the surfaces' exchange before
  // the medium attenuates it, and the zones are appended to F after them.
  const FormFactorDiagnostics d = diagnose(scene.mesh, ff.F, 5, opts.run.threads);
  print_diagnostics(scene, ff, d);
  Json j = diagnostics_json(scene, ff, d, "");
  Eigen::VectorXd zone_area;
  // With a medium the table's errors need the surfaces' F before the zones are appended.
  const FormFactors surface = medium && opts.by_surface ? ff : FormFactors();
  if (medium) j["medium"] = extend_with_zones(scene, *medium, opts.medium, opts.run, ff, zone_area);
  SurfaceFactors table;
  if (medium && opts.by_surface)
    table = medium_surface_table(scene, surface, ff, *medium, make_zones(*medium), opts.medium,
                                 opts.run);
  else if (opts.by_surface)
    table = surface_factors(scene.mesh, ff);
  const std::string settings = settings_string(ff.options, scene);
  j["settings"] = settings;
  const std::string ext = fs::path(opts.output).extension().string();
  const ValuePrecision precision =
      opts.precision == "float" ? ValuePrecision::Float : ValuePrecision::Double;
  if (opts.by_surface) {
    write_json_file(opts.output, surface_json(table));
  } else if (ext == ".mtx") {
    write_matrix_market(opts.output, ff.F, {mesh_hash(scene.mesh), settings}, precision);
  } else {
    write_ff_binary(opts.output, ff, {mesh_hash(scene.mesh), settings}, precision);
  }
  log_info("wrote " + opts.output);
  if (!distributed.is_null()) j["distributed"] = distributed;
  write_json_file(report, j);
  log_info("wrote " + report);
}

std::string formfactors_report_path(const FormFactorsOptions& opts) {
  namespace fs = std::filesystem;
  return !opts.report.empty() || opts.output.empty()
             ? opts.report
             : fs::path(opts.output).replace_extension(".report.json").string();
}

int run_formfactors(const FormFactorsOptions& opts) {
  if (opts.dist.enabled && opts.medium.active())
    throw UsageError("--distributed does not take a participating medium yet");
  check_options_read(opts.run,
                     {"formfactors", "matrix", opts.ff.estimator, {}, "", opts.medium.active()});
  if (opts.dist.enabled) return run_formfactors_distributed(opts);
  apply_run_options(opts.run);
  namespace fs = std::filesystem;
  if (opts.output.empty() && opts.point.empty())
    throw UsageError("formfactors: -o/--output is required");
  const std::string report = formfactors_report_path(opts);
  const std::shared_ptr<const Medium> medium = make_medium(opts.medium);
  if (medium && (!opts.point.empty() || opts.with_stderr))
    throw UsageError(
        "--point and --stderr do not combine with a participating medium yet: save F (-o F.bin "
        "or F.mtx) and read the zone columns, or --by-surface for the exchange areas");
  // The surface table carries standard errors (with a medium: the surfaces' F's and the
  // spread of the medium's replicates, medium_surface_factors).
  const bool with_stderr = opts.with_stderr || opts.by_surface;
  JobPlan plan = job_plan(opts.run);
  plan.outputs = {{"-o", opts.output}};
  plan.medium = medium.get();
  plan.medium_rays = opts.medium.rays;
  if (opts.point.empty()) {
    plan.outputs.push_back({"--report", report});
    plan_form_factors(plan, opts.ff, opts.run, with_stderr);
  }
  // The analytic estimator (named, or auto's pick for --ff-tol) integrates over whole
  // polygons: one patch per face unless --max-edge or --patches asks for more.
  SceneArgs scene_args = opts.scene;
  if ((opts.ff.estimator == "auto" ? auto_estimator(0, opts.ff.given("--ff-tol"))
                                   : opts.ff.estimator) == "analytic")
    scene_args.default_patches = 0;
  const LoadedScene scene = load_scene(scene_args, plan);
  if (!opts.point.empty()) {
    const FormFactorOptions o = make_ff_options(opts.ff, opts.run);
    if (scene.mesh.has_specular())
      log_warn(
          "--point: sensor-point factors are direct only (specular surfaces receive and "
          "block; paths through mirrors and glass are not followed)");
    const PointFactors pf =
        point_form_factors(scene.mesh, parse_vec(opts.point), parse_vec(opts.normal), o);
    if (opts.output.empty()) {
      std::cout << json_text(point_json(pf));
    } else {
      write_json_file(opts.output, point_json(pf));
      log_info("wrote " + opts.output);
    }
    return 0;
  }
  if (medium) check_medium_scene(scene.mesh, nullptr);
  FormFactors ff = obtain_form_factors(scene, opts.ff, opts.run, with_stderr);
  write_formfactors_outputs(opts, scene, ff, report, Json(), medium.get());
  return 0;
}

}  // namespace lambert
