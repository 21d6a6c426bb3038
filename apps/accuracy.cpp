// `lambert accuracy`: several form-factor estimators and settings on one meshed scene,
// each compared with a reference F and with the radiosity B that reference leads to.
//
// Reference: for a built-in analytic case (--case) the per-patch factors
//   F_ij = (1/A_i) ∫_{A_i} F(x -> j) dA_x
// with the exact point-to-patch factor F(x -> j) (Lambert's contour formula) integrated by
// composite Gauss-Legendre quadrature (these cases are unoccluded), plus the closed form of
// the surface factor; for the occluded partial_shadow case and any other scene a
// high-sample `hybrid` run whose own standard error is reported (partial_shadow also has
// an exact occluded surface factor, from the partial-shadow kernel).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/analysis.hpp"
#include "geometry/formfactors/reference.hpp"
#include "io/plot.hpp"
#include "pipeline/problem.hpp"
#include "pipeline/solve_stage.hpp"

namespace lambert {
namespace {

// Pairs closer than this many patch diameters (centroid distance / larger diameter) count as
// "near" in the error split: the hemicube's proximity error (F taken from the centre point
// instead of averaged over patch i) is large there, while past ~2 diameters the point-to-area
// factor varies little across patch i (relative error ~ (diameter / 2d)² < 6%).
constexpr double kNearDiameters = 2.0;
// Solver tolerance for comparing B: ||E - K B|| / ||E|| <= 1e-10 gives ||B - B*||∞ <=
// 1e-10 ||E|| / (1 - ρmax) ~ 1e-9 relative for ρ ≤ 0.9, far below the F-induced differences
// (>= 1e-6 for any estimator setting the harness runs).
constexpr double kSolveTol = 1e-10;

// One estimator run (or the reference) and its comparison with the reference.
struct AccuracyRow {
  std::string estimator;
  std::string setting;
  double seconds = 0.0;
  std::int64_t nnz = 0;
  double f_ab = std::nan("");        ///< surface factor of the first exact pair
  double f_exact_err = std::nan("");  ///< max |F_GH - exact| over the exact surface pairs
  double max_err = 0.0, rms_err = 0.0;  ///< per-patch |F_ij - Fref_ij|
  double max_err_near = 0.0, max_err_far = 0.0;
  std::int32_t worst_i = -1, worst_j = -1;
  double worst_ratio = 0.0;     ///< centroid distance / diameter of the worst pair
  double max_row_err = 0.0;     ///< max_i |Σ_j F_ij - Σ_j Fref_ij|
  double reciprocity = 0.0;     ///< max |A_i F_ij - A_j F_ji| / ((A_i + A_j) / 2)
  double b_max_rel = 0.0, b_rms_rel = 0.0;  ///< per surface and channel, vs B of the reference
  std::vector<SurfaceRadiosity> surfaces;    ///< this run's per-surface B
};

// An exactly known surface-to-surface factor.
struct ExactPair {
  std::int32_t g, h;
  double value;
};

// The scene to study: an analytic case or a file (or the built-in Cornell box).
struct Study {
  std::string name;
  Scene scene;
  PatchMesh mesh;
  std::vector<ExactPair> exact;  ///< empty for non-analytic scenes
  bool occluded = false;  ///< blockers between the pairs: the per-patch reference is hybrid
};

std::int32_t surface_index(const PatchMesh& mesh, const std::string& name) {
  const auto it = std::find(mesh.surface_names.begin(), mesh.surface_names.end(), name);
  LAMBERT_CHECK(it != mesh.surface_names.end(), "analytic case without surface " + name);
  return static_cast<std::int32_t>(it - mesh.surface_names.begin());
}

std::vector<double> surface_areas(const PatchMesh& mesh) {
  std::vector<double> a(mesh.surface_names.size(), 0.0);
  for (const auto& p : mesh.patches) a[p.surface] += p.area;
  return a;
}

// Meshes a built-in case after the plan's checks (load_scene does the same for files).
PatchMesh mesh_case(const Scene& scene, const SceneArgs& args, const JobPlan& plan) {
  check_job_files({}, plan.outputs);
  const MeshPlan mp = plan_mesh(scene, mesh_options(args));
  if (mp.patches <= kMaxPatches) check_job_memory(mp.patches, plan);
  return mesh_scene(scene, mesh_options(args));
}

Study make_study(const AccuracyOptions& opts, const JobPlan& plan) {
  Study s;
  if (opts.analytic_case.empty()) {
    LoadedScene loaded = load_scene(opts.scene, plan);
    s.name = loaded.scene.source;
    s.scene = std::move(loaded.scene);
    s.mesh = std::move(loaded.mesh);
    return s;
  }
  if (!opts.scene.scene.empty()) throw UsageError("accuracy: give either SCENE or --case");
  s.name = opts.analytic_case;
  if (opts.analytic_case == "unit_cube") {
    s.scene = unit_cube();
    s.mesh = mesh_case(s.scene, opts.scene, plan);
    // Every face sees the opposite face with kCubeOpposite and each of four neighbours with
    // kCubeAdjacent (equal areas, so both directions have the same value).
    for (std::int32_t g = 0; g < 6; ++g)
      for (std::int32_t h = 0; h < 6; ++h) {
        if (g == h) continue;
        const bool opposite = s.mesh.surface_names[g].substr(1) == s.mesh.surface_names[h].substr(1);
        s.exact.push_back({g, h, opposite ? kCubeOpposite : kCubeAdjacent});
      }
    return s;
  }
  if (opts.analytic_case == "partial_shadow") {
    // The floor-to-light factor past the blocker, exact (the partial-shadow kernel
    // integrated cell by cell between the D1/D2 lines); per patch the hybrid reference.
    s.scene = partial_shadow_scene();
    s.mesh = mesh_case(s.scene, opts.scene, plan);
    s.occluded = true;
    const std::int32_t f = surface_index(s.mesh, "floor"), l = surface_index(s.mesh, "light");
    const std::vector<double> area = surface_areas(s.mesh);
    const double exact = partial_shadow_floor_light_factor();
    s.exact.push_back({f, l, exact});
    s.exact.push_back({l, f, exact * area[f] / area[l]});  // reciprocity
    return s;
  }
  for (auto& c : analytic_cases()) {
    if (c.name != opts.analytic_case) continue;
    s.scene = std::move(c.scene);
    s.mesh = mesh_case(s.scene, opts.scene, plan);
    const std::int32_t a = surface_index(s.mesh, "a"), b = surface_index(s.mesh, "b");
    const std::vector<double> area = surface_areas(s.mesh);
    s.exact.push_back({a, b, c.exact_ab});
    s.exact.push_back({b, a, c.exact_ab * area[a] / area[b]});  // reciprocity
    return s;
  }
  throw UsageError("accuracy: unknown --case '" + opts.analytic_case + "'");
}

// Per-patch comparison of F with the reference (union of both sparsity patterns).
void compare_factors(const PatchMesh& mesh, const SparseF& F, const SparseF& ref, AccuracyRow& row) {
  const SparseF diff = F - ref;
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(mesh.size());
  row.max_row_err = (diff * ones).cwiseAbs().maxCoeff();
  double sum2 = 0.0;
  std::int64_t count = 0;
  for (std::int32_t i = 0; i < diff.outerSize(); ++i) {
    for (SparseF::InnerIterator it(diff, i); it; ++it) {
      const double e = std::abs(it.value());
      sum2 += e * e;
      ++count;
      const double ratio = proximity(mesh, i, static_cast<std::int32_t>(it.col()));
      double& bucket = ratio < kNearDiameters ? row.max_err_near : row.max_err_far;
      bucket = std::max(bucket, e);
      if (e > row.max_err) {
        row.max_err = e;
        row.worst_i = i;
        row.worst_j = static_cast<std::int32_t>(it.col());
        row.worst_ratio = ratio;
      }
    }
  }
  row.rms_err = count > 0 ? std::sqrt(sum2 / count) : 0.0;
  // Reciprocity: G = diag(A) F, residual G - G^T per pair, in units of F.
  Eigen::VectorXd area(mesh.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) area[i] = mesh.patches[i].area;
  const SparseF G = area.asDiagonal() * F;
  const SparseF R = G - SparseF(G.transpose());
  for (std::int32_t i = 0; i < R.outerSize(); ++i)
    for (SparseF::InnerIterator it(R, i); it; ++it)
      row.reciprocity = std::max(row.reciprocity,
                                 std::abs(it.value()) / (0.5 * (area[i] + area[it.col()])));
}

// The participating medium of a study, when there is one: every F gets its zones.
struct StudyMedium {
  std::shared_ptr<const Medium> medium;
  Zones zones;
  LoadedScene scene;  // the study's scene and mesh, for medium_form_factors
};

// F over the patches only: with a medium, its top-left N x N block (the attenuated surface
// factors); the comparisons per patch pair read that.
SparseF patch_block(const SparseF& F, std::int32_t n) {
  if (F.rows() == n) return F;
  return F.topLeftCorner(n, n);
}

std::vector<SurfaceRadiosity> solve_surfaces(const PatchMesh& mesh, const SparseF& F, int threads,
                                             const Zones* zones) {
  const RadiosityProblem problem =
      zones ? make_extended_problem(mesh, F, zones->albedo, zones->emission, zones->area)
            : make_problem(mesh, F);
  SolveOptions so;
  so.tol = kSolveTol;
  so.threads = threads;
  const RadiositySolution sol = solve_radiosity(problem, so);
  if (sol.status != SolveStatus::Converged)
    log_warn(std::string("accuracy: radiosity solve ended with status ") + to_string(sol.status));
  return surface_averages(mesh, sol.B.topRows(mesh.size()));
}

// Relative differences of per-surface B (each channel with B_ref > 0): max and RMS.
void compare_radiosity(const std::vector<SurfaceRadiosity>& ref, AccuracyRow& row) {
  double sum2 = 0.0;
  int count = 0;
  for (size_t s = 0; s < ref.size(); ++s)
    for (int c = 0; c < 3; ++c) {
      if (ref[s].area <= 0.0 || !(ref[s].average[c] > 0.0)) continue;
      const double rel = std::abs(row.surfaces[s].average[c] - ref[s].average[c]) / ref[s].average[c];
      row.b_max_rel = std::max(row.b_max_rel, rel);
      sum2 += rel * rel;
      ++count;
    }
  row.b_rms_rel = count > 0 ? std::sqrt(sum2 / count) : 0.0;
}

void compare_exact(const Study& study, const FormFactors& ff, AccuracyRow& row) {
  if (study.exact.empty()) return;
  const SurfaceFactors sf = surface_factors(study.mesh, ff);
  row.f_ab = sf.F(study.exact[0].g, study.exact[0].h);
  row.f_exact_err = 0.0;
  for (const auto& e : study.exact)
    row.f_exact_err = std::max(row.f_exact_err, std::abs(sf.F(e.g, e.h) - e.value));
}

// The runs to make, in table order: (estimator, samples or resolution, symmetrize).
struct RunSpec {
  std::string estimator;
  int value;
  bool symmetrize;
};

std::vector<RunSpec> run_specs(const AccuracyOptions& opts) {
  const std::vector<std::string> families =
      opts.estimators.empty() ? std::vector<std::string>{"mc", "hybrid", "hemicube"} : opts.estimators;
  std::vector<RunSpec> out;
  for (const auto& f : families) {
    if (f == "mc")
      for (int k : opts.mc_samples) out.push_back({f, k, false});
    if (f == "hybrid")
      for (int k : opts.hybrid_samples) out.push_back({f, k, false});
    if (f == "gather")
      for (int k : opts.gather_rays) out.push_back({f, k, false});
    if (f == "hemicube")
      for (int r : opts.hemicube_res) {
        out.push_back({f, r, false});
        if (opts.symmetrize) out.push_back({f, r, true});
      }
  }
  return out;
}

std::string spec_name(const RunSpec& s) { return s.symmetrize ? s.estimator + "-sym" : s.estimator; }
std::string spec_setting(const RunSpec& s) {
  return (s.estimator == "hemicube" ? "N=" : s.estimator == "gather" ? "K=" : "k=") +
         std::to_string(s.value);
}

void write_table_csv(const std::string& path, const Study& study, const std::vector<AccuracyRow>& rows) {
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "scene,estimator,setting,seconds,nnz,F_ab,F_exact_abs_err,max_abs_err,rms_abs_err,"
           "max_abs_err_near,max_abs_err_far,worst_i,worst_j,worst_distance_ratio,"
           "max_row_sum_err,reciprocity,B_max_rel_diff,B_rms_rel_diff\n";
    for (const auto& r : rows)
      out << csv_field(study.name) << ',' << r.estimator << ',' << r.setting << ','
          << csv_number(r.seconds) << ',' << r.nnz << ',' << csv_number(r.f_ab) << ','
          << csv_number(r.f_exact_err) << ',' << csv_number(r.max_err) << ','
          << csv_number(r.rms_err) << ',' << csv_number(r.max_err_near) << ','
          << csv_number(r.max_err_far) << ',' << r.worst_i << ',' << r.worst_j << ','
          << csv_number(r.worst_ratio) << ',' << csv_number(r.max_row_err) << ','
          << csv_number(r.reciprocity) << ',' << csv_number(r.b_max_rel) << ','
          << csv_number(r.b_rms_rel) << '\n';
  });
}

void write_surfaces_csv(const std::string& path, const std::vector<AccuracyRow>& rows,
                        const std::vector<SurfaceRadiosity>& ref) {
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "estimator,setting,surface,channel,B,B_reference,rel_diff\n";
    for (const auto& r : rows)
      for (size_t s = 0; s < ref.size(); ++s)
        for (int c = 0; c < 3; ++c) {
          const double b = r.surfaces[s].average[c], br = ref[s].average[c];
          out << r.estimator << ',' << r.setting << ',' << csv_field(ref[s].name) << ','
              << channel_name(c) << ',' << csv_number(b) << ',' << csv_number(br) << ','
              << csv_number(br > 0.0 ? std::abs(b - br) / br : std::nan("")) << '\n';
        }
  });
}

// Error-vs-time panels, one series per estimator family (points in table order).
std::vector<Plot> error_plots(const std::vector<AccuracyRow>& rows, bool analytic) {
  Plot f, b;
  f.log_x = f.markers = true;
  f.title = "RMS |F - F_ref| per patch pair vs time";
  f.x_label = "form-factor time (s)";
  f.y_label = "RMS abs error of F";
  b.title = "max relative B difference per surface vs time";
  b.log_x = b.markers = true;
  b.x_label = f.x_label;
  b.y_label = "max |B - B_ref| / B_ref";
  Plot e;
  e.log_x = e.markers = true;
  e.title = "surface factor error vs time (closed form)";
  e.x_label = f.x_label;
  e.y_label = "max |F_GH - exact|";
  std::map<std::string, size_t> index;
  for (const auto& r : rows) {
    if (r.setting == "reference") continue;
    auto [it, added] = index.emplace(r.estimator, f.series.size());
    if (added) {
      f.series.push_back({r.estimator, {}, {}});
      b.series.push_back({r.estimator, {}, {}});
      e.series.push_back({r.estimator, {}, {}});
    }
    const size_t k = it->second;
    f.series[k].x.push_back(r.seconds);
    f.series[k].y.push_back(r.rms_err);
    b.series[k].x.push_back(r.seconds);
    b.series[k].y.push_back(r.b_max_rel);
    e.series[k].x.push_back(r.seconds);
    e.series[k].y.push_back(r.f_exact_err);
  }
  if (analytic) return {f, e, b};
  return {f, b};
}

void print_table(const Study& study, const std::vector<AccuracyRow>& rows) {
  std::printf("%-12s %-10s %9s %10s %10s %10s %10s %10s %10s %10s %10s %10s %10s\n", "estimator",
              "setting", "time (s)", "F_ab", "|F_GH-ex|", "max|dF|", "rms|dF|", "near max",
              "far max", "max|dRow|", "recip", "B max rel", "B rms rel");
  for (const auto& r : rows) {
    std::printf("%-12s %-10s %9.3f %10.6f %10.3e %10.3e %10.3e %10.3e %10.3e %10.3e %10.3e "
                "%10.3e %10.3e\n",
                r.estimator.c_str(), r.setting.c_str(), r.seconds, r.f_ab, r.f_exact_err,
                r.max_err, r.rms_err, r.max_err_near, r.max_err_far, r.max_row_err,
                r.reciprocity, r.b_max_rel, r.b_rms_rel);
  }
  (void)study;
}

// Spells out the two hemicube failure modes from the table: the far-pair error (aliasing)
// falls with the resolution, the near-pair error (proximity) does not.
void print_failure_modes(const std::vector<AccuracyRow>& rows) {
  const AccuracyRow* lo = nullptr;
  const AccuracyRow* hi = nullptr;
  for (const auto& r : rows) {
    if (r.estimator != "hemicube") continue;
    if (!lo) lo = &r;
    hi = &r;
  }
  if (!lo || lo == hi) return;
  std::printf("hemicube aliasing (pairs >= %.0f diameters apart): max |dF| %.3e at %s -> %.3e at %s\n",
              kNearDiameters, lo->max_err_far, lo->setting.c_str(), hi->max_err_far, hi->setting.c_str());
  if (lo->max_err_near <= 0.0 && hi->max_err_near <= 0.0) return;  // no neighbours in the scene
  std::printf("hemicube proximity (pairs < %.0f diameters apart): max |dF| %.3e at %s -> %.3e at %s"
              " (F is taken at the patch centre: resolution cannot remove this)\n",
              kNearDiameters, lo->max_err_near, lo->setting.c_str(), hi->max_err_near,
              hi->setting.c_str());
}

}  // namespace

CLI::App* add_accuracy_command(CLI::App& app, AccuracyOptions& opts) {
  auto* cmd = app.add_subcommand(
      "accuracy", "Compare form-factor estimators and settings with a reference: table, CSV, plot");
  opts.scene.default_patches = 200;
  add_scene_options(cmd, opts.scene);
  add_declared(cmd, "--case", opts.analytic_case);
  add_declared(cmd, "--estimators", opts.estimators);
  add_declared(cmd, "--mc-samples", opts.mc_samples);
  add_declared(cmd, "--hybrid-samples", opts.hybrid_samples);
  add_declared(cmd, "--gather-rays", opts.gather_rays);
  add_declared(cmd, "--hemicube-res", opts.hemicube_res);
  add_declared(cmd, "--symmetrize", opts.symmetrize);
  add_declared(cmd, "--reference-samples", opts.reference_samples);
  add_declared(cmd, "-o,--output", opts.output);
  add_run_options(cmd, opts.run);
  add_medium_options(cmd, opts.medium);
  return cmd;
}

int run_accuracy(const AccuracyOptions& opts) {
  apply_run_options(opts.run);
  const std::string base_path = output_prefix(opts.output, "accuracy");
  const std::string csv = base_path + "_table.csv", surf = base_path + "_surfaces.csv";
  const std::string svg = base_path + "_error_vs_time.svg";
  JobPlan plan = job_plan(opts.run);
  plan.outputs = {{"-o", csv}, {"-o", surf}, {"-o", svg}};
  // The largest F held at a time: an all-pairs estimate with standard errors (the hybrid
  // reference) beside the run's own.
  plan.ff = FormFactorOptions{};
  plan.ff->run.with_stderr = true;
  std::optional<StudyMedium> sm;
  if (const std::shared_ptr<const Medium> medium = make_medium(opts.medium)) {
    sm.emplace();
    sm->medium = medium;
    plan.medium = medium.get();
    plan.medium_rays = opts.medium.rays;
  }
  const Study study = make_study(opts, plan);
  const PatchMesh& mesh = study.mesh;
  const bool analytic = !study.exact.empty() && !study.occluded;
  // With a medium every F, the reference's too, gets the zones with the same medium settings
  // and streams: the differences are the surface estimators' as the medium carries them.
  // The closed forms hold without a medium only.
  const Zones* zones = nullptr;
  if (sm) {
    check_medium_scene(mesh, nullptr);
    sm->zones = make_zones(*sm->medium);
    sm->scene.scene = study.scene;
    sm->scene.mesh = mesh;
    zones = &sm->zones;
  }
  const auto add_medium = [&](FormFactors ff) {
    if (!sm) return ff;
    return medium_form_factors(sm->scene, ff, *sm->medium, sm->zones, opts.medium, opts.run);
  };
  const bool exact = !study.exact.empty() && !sm;
  std::printf("%s: %zu surfaces, %d patches\n", study.name.c_str(), mesh.surface_names.size(),
              mesh.size());

  // The reference.
  FormFactorOptions base;
  base.run.seed = opts.run.seed;
  base.run.threads = opts.run.threads;
  base.run.progress = !opts.run.quiet;
  FormFactors ref;
  if (analytic) {
    log_info("accuracy: reference by quadrature of the exact point-to-patch factor");
    ref = unoccluded_quadrature(mesh, opts.run.threads);
  } else {
    FormFactorOptions o = base;
    o.estimator = "hybrid";
    o.pair.samples = opts.reference_samples;
    // Its own random streams: sharing the runs' lattice shifts would correlate their errors
    // with the reference's and make them look smaller than they are.
    o.run.seed = hash_keys(opts.run.seed, 0x7265666572656E63ull);
    o.run.with_stderr = true;
    log_info("accuracy: reference hybrid k=" + std::to_string(o.pair.samples));
    ref = compute_form_factors(mesh, o);
  }
  SparseF ref_stderr;  // the surface reference's own error (the medium's factors have none)
  ref_stderr.swap(ref.stderr_F);
  ref = add_medium(std::move(ref));
  const SparseF ref_block = patch_block(ref.F, mesh.size());
  AccuracyRow ref_row;
  ref_row.estimator = analytic ? "quadrature" : "hybrid";
  ref_row.setting = "reference";
  ref_row.seconds = ref.stats.seconds;
  ref_row.nnz = ref.F.nonZeros();
  if (exact) compare_exact(study, ref, ref_row);
  ref_row.surfaces = solve_surfaces(mesh, ref.F, opts.run.threads, zones);
  compare_factors(mesh, ref_block, ref_block, ref_row);
  if (sm) {
    std::printf(
        "medium %s: %d zones, the same medium factors (--medium-rays %d, "
        "--transmittance-samples %d) added to every F; the closed forms hold without "
        "a medium and are not compared\n",
        sm->medium->source.c_str(), sm->zones.size(), opts.medium.rays,
        opts.medium.transmittance_samples);
  }
  if (analytic && !sm) {
    std::printf("reference: per-patch quadrature of the exact point-to-patch factor; exact "
                "surface factors (closed form): F(%s->%s) = %.9f\n",
                mesh.surface_names[study.exact[0].g].c_str(),
                mesh.surface_names[study.exact[0].h].c_str(), study.exact[0].value);
  } else if (!analytic) {
    if (study.occluded && !sm)
      std::printf("exact surface factor (partial-shadow kernel): F(%s->%s) = %.12f\n",
                  mesh.surface_names[study.exact[0].g].c_str(),
                  mesh.surface_names[study.exact[0].h].c_str(), study.exact[0].value);
    double max_se = 0.0, sum2 = 0.0;
    for (std::int64_t k = 0; k < ref_stderr.nonZeros(); ++k) {
      max_se = std::max(max_se, ref_stderr.valuePtr()[k]);
      sum2 += std::pow(ref_stderr.valuePtr()[k], 2);
    }
    std::printf("reference: hybrid k=%d, its own standard error per entry: max %.3e, RMS %.3e\n",
                opts.reference_samples, max_se,
                std::sqrt(sum2 / std::max<std::int64_t>(1, ref_stderr.nonZeros())));
  }

  std::vector<AccuracyRow> rows{ref_row};
  for (const RunSpec& spec : run_specs(opts)) {
    FormFactorOptions o = base;
    o.estimator = spec.estimator;
    if (spec.estimator == "hemicube")
      o.hemicube.resolution = spec.value;
    else if (spec.estimator == "gather")
      o.gather.rays = spec.value;
    else
      o.pair.samples = spec.value;
    // gather keeps its default (averaged); the hemicube rows say which they are.
    o.reciprocity = spec.symmetrize ? "average" : spec.estimator == "gather" ? "auto" : "none";
    AccuracyRow row;
    row.estimator = spec_name(spec);
    row.setting = spec_setting(spec);
    log_info("accuracy: " + row.estimator + " " + row.setting);
    const FormFactors ff = add_medium(compute_form_factors(mesh, o));
    row.seconds = ff.stats.seconds;
    row.nnz = ff.F.nonZeros();
    if (exact) compare_exact(study, ff, row);
    compare_factors(mesh, patch_block(ff.F, mesh.size()), ref_block, row);
    row.surfaces = solve_surfaces(mesh, ff.F, opts.run.threads, zones);
    compare_radiosity(ref_row.surfaces, row);
    rows.push_back(std::move(row));
  }

  print_table(study, rows);
  print_failure_modes(rows);
  write_table_csv(csv, study, rows);
  write_surfaces_csv(surf, rows, ref_row.surfaces);
  const std::vector<Plot> plots = error_plots(rows, exact);
  write_plots_svg(svg, plots);
  std::printf("wrote %s, %s, %s (PNG: python3 -m lambert.plot accuracy %s)\n", csv.c_str(),
              surf.c_str(), svg.c_str(), opts.output.c_str());
  return kExitOk;
}

}  // namespace lambert
