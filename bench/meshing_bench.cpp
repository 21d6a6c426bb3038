// Meshing benchmark (issue 13): error versus patch count for uniform, adaptive,
// discontinuity and discontinuity + adaptive meshing, with time.
//
// Partial-shadow scene (geometry/analytic.hpp: floor, square light, off-centre blocker; the
// floor's exact radiosity is 0.5 x shadowed_point_factor at every point): per mesh, the
// patches, the time of mesh + F (hybrid, --samples per pair) + solve (gauss-seidel to 1e-10),
// and two errors against the exact field (partial_shadow_errors): L1, the area-mean
// |B_i - B(x)| over the floor of the patch constants, and line, the largest |B_h(x) - B(x)|
// of the Gouraud field at 400 points on the line y = 1.75 across umbra and penumbra, with
// the vertex values `run` uses (exact direct light on discontinuity meshes, the linear fit on
// adapted ones, conservative otherwise) and, in the last column, with conservative ones for every
// method. Adaptive runs start from the uniform mesh of a quarter of the target and refine
// (pipeline/adapt_stage) until the target.
//
// Cornell box (built-in): per-surface average radiosity against a reference (uniform,
// --ref-patches, gather 4096 rays) for uniform and discontinuity meshing (hybrid, 32
// samples per pair) at the same targets (discontinuity makes more patches: its lines force
// them): the worst relative per-surface difference over surfaces and channels, and the time.
//
// Log-log slopes of error against patches are printed per method; --plot FILE.svg writes
// error versus patches (both errors, log-log).
//
// Plan (issue 35, item 2): the time of the meshing plan (plan_mesh: the edge bound for a patch
// target) against input size, on two generated families of about n triangles: the bumpy grid
// (tests/common/bumpy_grid.hpp: one connected surface, like a scanned model) and the Cornell
// box with tessellated objects (bench/scene_generator.hpp: sqrt(n)/2 surfaces). Per size the
// median of 3 runs of the plan for 2,000 patches and for n patches, and of plan + mesh_scene
// for n (what `lambert info --patches n` does after loading); then the cost exponent p of
// each column, fitted as time ~ c n^p in log-log (bench/power_law.hpp).
//
// Usage: meshing_bench [--targets 300,1000,3000] [--samples 64] [--ref-patches 48000]
//   [--sizes 10000,20000,40000,80000] [--sections shadow,cornell,plan,adapt] [--plot meshing.svg]
// (adapt is not run by default).

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "bench/power_law.hpp"
#include "bench/scene_generator.hpp"
#include "common/bumpy_grid.hpp"
#include "core/timer.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/mesh/adapt.hpp"
#include "geometry/render/vertex_field.hpp"
#include "geometry/visibility/shadow.hpp"
#include "io/obj_loader.hpp"
#include "io/plot.hpp"
#include "pipeline/adapt_stage.hpp"
#include "pipeline/problem.hpp"
#include "solvers/radiosity.hpp"

using namespace lambert;

namespace {

std::vector<long> parse_list(const std::string& s) {
  std::vector<long> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stol(item));
  return out;
}

struct Run {
  std::string method;
  std::int64_t patches = 0;
  double seconds = 0;
  PartialShadowErrors err;        // line error with the method's vertex values
  double line_conservative = 0;  // line error with conservative vertex values
};

// B and the indirect irradiance I = F (B - E) on `mesh`.
std::pair<Eigen::MatrixX3d, Eigen::MatrixX3d> solve_mesh(const PatchMesh& mesh, int samples) {
  FormFactorOptions fo;
  fo.estimator = "hybrid";
  fo.pair.samples = samples;
  fo.run.progress = false;
  const FormFactors F = compute_form_factors(mesh, fo);
  SolveOptions so;
  so.tol = 1e-10;
  Eigen::MatrixX3d B = solve_radiosity(make_problem(mesh, F.F), so).B;
  Eigen::MatrixX3d I = indirect_irradiance(mesh, F.F, B);
  return {B, I};
}

// Refines `loaded` by adapt_scene (hybrid, `samples` per pair) until `target` patches: B and
// the indirect irradiance I = F (B - E) on the refined mesh.
std::pair<Eigen::MatrixX3d, Eigen::MatrixX3d> adapt_mesh(LoadedScene& loaded, long target,
                                                         int samples, bool quiet) {
  FormFactorArgs ff;
  ff.estimator = "hybrid";
  ff.set_param("--samples", samples);
  RunArgs run;
  run.quiet = quiet;
  AdaptArgs a;
  a.patches = target;
  SolveOptions so;
  so.tol = 1e-10;
  FormFactors F;
  RadiositySolution sol;
  adapt_scene(loaded, ff, so, run, a, F, sol);
  return {sol.B, indirect_irradiance(loaded.mesh, F.F, sol.B)};
}

// Meshes and solves the partial-shadow scene one way (adaptive ways through adapt_scene).
Run run_method(const Scene& scene, const std::string& method, long target, int samples) {
  Run r;
  r.method = method;
  Timer t;
  const bool disc = method.find("discontinuity") != std::string::npos;
  const bool adapt = method.find("adaptive") != std::string::npos;
  MeshOptions mo;
  mo.discontinuity = disc;
  mo.target_patches = adapt ? target / 4 : target;
  LoadedScene loaded;
  loaded.scene = scene;
  loaded.mesh = mesh_scene(scene, mo);
  loaded.discontinuity = disc;
  Eigen::MatrixX3d B, I;
  if (adapt) {
    std::tie(B, I) = adapt_mesh(loaded, target, samples, false);
  } else {
    std::tie(B, I) = solve_mesh(loaded.mesh, samples);
  }
  // The vertex values `run` uses by default: exact direct light on discontinuity meshes.
  const VertexField field =
      disc ? exact_direct_vertex_field(scene, loaded.mesh, B, I)
           : interpolate_to_vertices(
                 loaded.mesh, B,
                 adapt ? VertexInterpolation::LinearFit : VertexInterpolation::Conservative);
  r.seconds = t.seconds();
  r.patches = loaded.mesh.size();
  r.err = partial_shadow_errors(loaded.mesh, B, field);
  r.line_conservative = partial_shadow_errors(loaded.mesh, B, interpolate_to_vertices(loaded.mesh, B)).line;
  return r;
}

double slope(const std::vector<Run>& runs, const std::string& method, bool line) {
  std::vector<double> x, y;
  for (const auto& r : runs)
    if (r.method == method) {
      x.push_back(std::log(static_cast<double>(r.patches)));
      y.push_back(std::log(line ? r.err.line : r.err.l1));
    }
  if (x.size() < 2) return NAN;
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < x.size(); ++k) sx += x[k], sy += y[k], sxx += x[k] * x[k], sxy += x[k] * y[k];
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// The median of 3 timings of f() (seconds).
template <class F>
double median_of_3(F&& f) {
  std::vector<double> t;
  for (int k = 0; k < 3; ++k) {
    Timer timer;
    f();
    t.push_back(timer.seconds());
  }
  std::sort(t.begin(), t.end());
  return t[1];
}

// The plan section: plan and plan + mesh times against input size, and their exponents.
void plan_section(const std::vector<long>& sizes) {
  std::printf("\nmeshing plan against input size (medians of 3)\n");
  std::printf("%-8s %9s %8s %12s %12s %14s %11s %9s\n", "family", "triangles", "surfaces",
              "plan 2000 s", "plan n s", "plan+mesh n s", "evaluations", "terms");
  for (const std::string family : {"grid", "objects"}) {
    std::vector<std::pair<double, double>> coarse, fine, meshed;
    for (const long n : sizes) {
      const Scene scene = family == "grid"
                              ? test::bumpy_grid(static_cast<int>(std::lround(std::sqrt(n / 2.0))))
                              : bench::cornell_with_objects(n);
      const auto tris = static_cast<double>(bench::triangle_count(scene));
      const MeshOptions to_2000{0, 2000}, to_n{0, n};
      MeshPlan plan;
      coarse.emplace_back(tris, median_of_3([&] { plan_mesh(scene, to_2000); }));
      fine.emplace_back(tris, median_of_3([&] { plan = plan_mesh(scene, to_n); }));
      meshed.emplace_back(tris, median_of_3([&] {
                            MeshOptions o = to_n;
                            o.max_edge = plan_mesh(scene, to_n).max_edge;
                            mesh_scene(scene, o);
                          }));
      std::printf("%-8s %9.0f %8zu %12.4f %12.4f %14.4f %11lld %9lld\n", family.c_str(), tris,
                  scene.surfaces.size(), coarse.back().second, fine.back().second,
                  meshed.back().second, static_cast<long long>(plan.stats.evaluations),
                  static_cast<long long>(plan.stats.terms));
      std::fflush(stdout);
    }
    std::printf(
        "cost exponent (time ~ n^p) %-8s plan 2000 p %5.2f  plan n p %5.2f  plan+mesh n p %5.2f\n",
        family.c_str(), fit_power_law(coarse).p, fit_power_law(fine).p, fit_power_law(meshed).p);
  }
}

// The adapt section (issue 35, item 7): floor L1 error of the patch constants against patch
// count, uniform meshing (quads, what a plain run meshes) against --adapt (from the uniform
// mesh of a quarter of the target, refined until the target), on the partial-shadow scene
// and the sharper square_shadow_geometry, hybrid `samples` per pair.
void adapt_section(const std::vector<long>& targets, int samples) {
  std::printf("\nadaptive vs uniform (floor L1 error of the patch constants, hybrid %d samples)\n",
              samples);
  std::printf("%-14s %-9s %8s %12s %12s %12s %9s\n", "scene", "method", "patches", "L1 error",
              "field L1", "line max", "seconds");
  for (const std::string name : {"partial", "square"}) {
    const PartialShadowGeometry g =
        name == "partial" ? partial_shadow_geometry() : square_shadow_geometry();
    const double line_y = name == "partial" ? 1.75 : 2.0;
    const Scene scene = shadow_scene(g);
    for (const long target : targets)
      for (const std::string method : {"uniform", "adaptive"}) {
        Timer t;
        MeshOptions mo;
        mo.target_patches = method == "adaptive" ? target / 4 : target;
        LoadedScene loaded;
        loaded.scene = scene;
        loaded.mesh = mesh_scene(scene, mo);
        Eigen::MatrixX3d B;
        if (method == "adaptive") {
          B = adapt_mesh(loaded, target, samples, true).first;
        } else {
          B = solve_mesh(loaded.mesh, samples).first;
        }
        const double seconds = t.seconds();
        // Shaded as `run` shades each (--vertex-interp auto).
        const VertexField field =
            interpolate_to_vertices(loaded.mesh, B,
                                    method == "adaptive" ? VertexInterpolation::LinearFit
                                                         : VertexInterpolation::Conservative);
        const PartialShadowErrors e = shadow_errors(g, loaded.mesh, B, field, line_y);
        std::printf("%-14s %-9s %8d %12.4g %12.4g %12.4g %9.2f\n", name.c_str(), method.c_str(),
                    loaded.mesh.size(), e.l1, e.field_l1, e.line, seconds);
        std::fflush(stdout);
      }
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<long> targets = {300, 1000, 3000};
  std::vector<long> sizes = {10000, 20000, 40000, 80000};
  int samples = 64;
  long ref_patches = 48000;
  std::string sections = "shadow,cornell,plan", plot;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--targets") targets = parse_list(v);
    else if (a == "--samples") samples = std::stoi(v);
    else if (a == "--ref-patches") ref_patches = std::stol(v);
    else if (a == "--sizes")
      sizes = parse_list(v);
    else if (a == "--sections") sections = v;
    else if (a == "--plot") plot = v;
    else {
      std::fprintf(stderr, "meshing_bench: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  const std::vector<std::string> methods = {"uniform", "adaptive", "discontinuity", "discontinuity+adaptive"};
  std::vector<Run> runs;
  if (sections.find("shadow") != std::string::npos) {
    std::printf("partial-shadow scene, hybrid %d samples/pair, errors of the floor radiosity (max ~0.012)\n", samples);
    std::printf("%-24s %8s %9s %12s %12s %14s\n", "method", "patches", "seconds", "L1 error",
                "line max", "(conservative)");
    const Scene scene = partial_shadow_scene();
    for (long target : targets)
      for (const auto& m : methods) {
        runs.push_back(run_method(scene, m, target, samples));
        const Run& r = runs.back();
        std::printf("%-24s %8lld %9.2f %12.4g %12.4g %14.4g\n", r.method.c_str(),
                    static_cast<long long>(r.patches), r.seconds, r.err.l1, r.err.line,
                    r.line_conservative);
        std::fflush(stdout);
      }
    for (const auto& m : methods)
      std::printf("slope of error vs patches (log-log) %-24s L1 %6.3f  line %6.3f\n", m.c_str(),
                  slope(runs, m, false), slope(runs, m, true));
  }
  if (sections.find("cornell") != std::string::npos) {
    const Scene scene = load_obj(builtin_cornell_box_path());
    Timer t;
    MeshOptions mo;
    mo.target_patches = ref_patches;
    const PatchMesh ref_mesh = mesh_scene(scene, mo);
    // The reference: uniform, gather with 4096 rays per patch (hybrid is O(N²) pairs; gather
    // O(N K)). Uniform meshes err low by O(h) (patches half under a block lose the light
    // their lit part reflects), so the reference errs the same way, by about 0.2 % at 48k.
    FormFactorOptions fo;
    fo.estimator = "gather";
    fo.gather.rays = 4096;
    fo.run.progress = false;
    SolveOptions so;
    so.tol = 1e-10;
    const FormFactors ref_F = compute_form_factors(ref_mesh, fo);
    const auto ref = surface_averages(ref_mesh, solve_radiosity(make_problem(ref_mesh, ref_F.F), so).B);
    std::printf("\nCornell box: reference uniform %d patches (gather 4096 rays) in %.1f s\n", ref_mesh.size(), t.seconds());
    std::printf("%-24s %8s %9s %14s\n", "method", "patches", "seconds", "worst surface");
    for (long target : targets)
      for (const std::string m : {"uniform", "discontinuity"}) {
        Timer tm;
        MeshOptions o;
        o.target_patches = target;
        o.discontinuity = m == "discontinuity";
        const PatchMesh mesh = mesh_scene(scene, o);
        const auto avg = surface_averages(mesh, solve_mesh(mesh, 32).first);
        double worst = 0;
        for (size_t s = 0; s < avg.size(); ++s)
          for (int c = 0; c < 3; ++c)
            if (ref[s].average[c] > 0) worst = std::max(worst, std::abs(avg[s].average[c] / ref[s].average[c] - 1));
        std::printf("%-24s %8d %9.2f %13.3f%%\n", m.c_str(), mesh.size(), tm.seconds(), 100 * worst);
        std::fflush(stdout);
      }
  }
  if (sections.find("plan") != std::string::npos) plan_section(sizes);
  if (sections.find("adapt") != std::string::npos) adapt_section(targets, samples);
  if (!plot.empty() && !runs.empty()) {
    Plot l1{"partial shadow: floor L1 error", "patches", "error (W/m^2)", true, true, true, {}};
    Plot line{"partial shadow: max error on y = 1.75", "patches", "error (W/m^2)", true, true, true, {}};
    for (const auto& m : methods) {
      PlotSeries a{m, {}, {}}, b{m, {}, {}};
      for (const auto& r : runs)
        if (r.method == m) {
          a.x.push_back(static_cast<double>(r.patches));
          a.y.push_back(r.err.l1);
          b.x.push_back(static_cast<double>(r.patches));
          b.y.push_back(r.err.line);
        }
      l1.series.push_back(a);
      line.series.push_back(b);
    }
    write_plots_svg(plot, {l1, line});
    std::printf("wrote %s\n", plot.c_str());
  }
  return 0;
}
