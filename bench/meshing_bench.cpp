// Meshing benchmark (issue 13): error versus patch count for uniform, adaptive,
// discontinuity and discontinuity + adaptive meshing, with time.
//
// Partial-shadow scene (geometry/analytic.hpp: floor, square light, off-centre blocker; the
// floor's exact radiosity is 0.5 x shadowed_point_factor at every point): per mesh, the
// patches, the time of mesh + F (hybrid, --samples per pair) + solve (gauss-seidel to 1e-10),
// and two errors against the exact field: L1, the area-mean |B_i - B(x)| over the floor of
// the patch constants (midpoint rule on 16 sub-triangles per patch), and line, the largest
// |B_h(x) - B(x)| of the Gouraud field (conservative vertex values) at 400 points on the line
// y = 1.75 across umbra and penumbra. Adaptive runs start from the uniform mesh of a quarter
// of the target and refine (apps/adapt_stage) until the target.
//
// Cornell box (built-in): per-surface average radiosity against a reference (uniform,
// --ref-patches, hybrid) for uniform and discontinuity meshing at about equal patch counts:
// the worst relative per-surface difference over surfaces and channels, and the time.
//
// Log-log slopes of error against patches are printed per method; --plot FILE.png writes
// error versus patches (both errors, log-log).
//
// Usage: meshing_bench [--targets 300,1000,3000] [--samples 64] [--ref-patches 6000]
//   [--sections shadow,cornell] [--plot meshing.png]

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "apps/adapt_stage.hpp"
#include "apps/problem.hpp"
#include "core/timer.hpp"
#include "geometry/adapt.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/shadow.hpp"
#include "geometry/vertex_field.hpp"
#include "io/obj_loader.hpp"
#include "io/plot.hpp"
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

double exact_floor(const Eigen::Vector3d& x) {
  static const PartialShadowGeometry g = partial_shadow_geometry();
  return 0.5 * shadowed_point_factor(x, Eigen::Vector3d::UnitZ(), g.light, {g.blocker});
}

bool inside(const PatchMesh& m, const Patch& p, const Eigen::Vector3d& x) {
  for (int c = 0; c < p.vertex_count; ++c) {
    const Eigen::Vector3d a = m.vertices[p.vertices[c]], b = m.vertices[p.vertices[(c + 1) % p.vertex_count]];
    if ((b - a).cross(x - a).z() < -1e-12) return false;
  }
  return true;
}

struct Errors {
  double l1 = 0, line = 0;
};

Errors floor_errors(const PatchMesh& m, const Eigen::MatrixX3d& B) {
  Errors e;
  double area = 0;
  for (std::int32_t i = 0; i < m.size(); ++i) {
    const Patch& p = m.patches[i];
    if (p.surface != 0) continue;
    for (int t = 1; t + 1 < p.vertex_count; ++t) {
      const Eigen::Vector3d a = m.vertices[p.vertices[0]], b = m.vertices[p.vertices[t]],
                            c = m.vertices[p.vertices[t + 1]];
      const double A = 0.5 * (b - a).cross(c - a).norm();
      const int n = 4;
      double err = 0;
      for (int u = 0; u < n; ++u)
        for (int v = 0; u + v < n; ++v) {
          const Eigen::Vector3d o = a + (b - a) * u / n + (c - a) * v / n;
          err += std::abs(B.row(i).mean() - exact_floor(o + ((b - a) + (c - a)) / (3.0 * n)));
          if (u + v < n - 1)
            err += std::abs(B.row(i).mean() - exact_floor(o + (2.0 * (b - a) + 2.0 * (c - a)) / (3.0 * n)));
        }
      e.l1 += A * err / (n * n);
      area += A;
    }
  }
  e.l1 /= area;
  const VertexField field = interpolate_to_vertices(m, B);
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector3d x(0.2 + 3.6 * (k + 0.5) / 400, 1.75, 0);
    for (std::int32_t i = 0; i < m.size(); ++i) {
      const Patch& p = m.patches[i];
      if (p.surface != 0 || !inside(m, p, x)) continue;
      const auto w = patch_weights(m, i, x);
      double value = 0;
      for (int c = 0; c < p.vertex_count; ++c) value += w[c] * field.values.row(field.patch_corners[i][c]).mean();
      e.line = std::max(e.line, std::abs(value - exact_floor(x)));
      break;
    }
  }
  return e;
}

struct Run {
  std::string method;
  std::int64_t patches = 0;
  double seconds = 0;
  Errors err;
};

Eigen::MatrixX3d solve_mesh(const PatchMesh& mesh, int samples) {
  FormFactorOptions fo;
  fo.estimator = "hybrid";
  fo.samples = samples;
  fo.progress = false;
  const FormFactors F = compute_form_factors(mesh, fo);
  SolveOptions so;
  so.tol = 1e-10;
  return solve_radiosity(make_problem(mesh, F.F), so).B;
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
  Eigen::MatrixX3d B;
  if (adapt) {
    FormFactorArgs ff;
    ff.estimator = "hybrid";
    ff.samples = samples;
    RunArgs run;
    AdaptArgs a;
    a.patches = target;
    SolveOptions so;
    so.tol = 1e-10;
    FormFactors F;
    RadiositySolution sol;
    adapt_scene(loaded, ff, so, run, a, F, sol);
    B = sol.B;
  } else {
    B = solve_mesh(loaded.mesh, samples);
  }
  r.seconds = t.seconds();
  r.patches = loaded.mesh.size();
  r.err = floor_errors(loaded.mesh, B);
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

}  // namespace

int main(int argc, char** argv) {
  std::vector<long> targets = {300, 1000, 3000};
  int samples = 64;
  long ref_patches = 6000;
  std::string sections = "shadow,cornell", plot;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--targets") targets = parse_list(v);
    else if (a == "--samples") samples = std::stoi(v);
    else if (a == "--ref-patches") ref_patches = std::stol(v);
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
    std::printf("%-24s %8s %9s %12s %12s\n", "method", "patches", "seconds", "L1 error", "line max");
    const Scene scene = partial_shadow_scene();
    for (long target : targets)
      for (const auto& m : methods) {
        runs.push_back(run_method(scene, m, target, samples));
        const Run& r = runs.back();
        std::printf("%-24s %8lld %9.2f %12.4g %12.4g\n", r.method.c_str(), static_cast<long long>(r.patches),
                    r.seconds, r.err.l1, r.err.line);
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
    const auto ref = surface_averages(ref_mesh, solve_mesh(ref_mesh, 4));
    std::printf("\nCornell box: reference uniform %d patches (hybrid 4 samples) in %.1f s\n", ref_mesh.size(), t.seconds());
    std::printf("%-24s %8s %9s %14s\n", "method", "patches", "seconds", "worst surface");
    for (long target : targets)
      for (const std::string m : {"uniform", "discontinuity"}) {
        Timer tm;
        MeshOptions o;
        o.target_patches = target;
        o.discontinuity = m == "discontinuity";
        const PatchMesh mesh = mesh_scene(scene, o);
        const auto avg = surface_averages(mesh, solve_mesh(mesh, samples / 4));
        double worst = 0;
        for (size_t s = 0; s < avg.size(); ++s)
          for (int c = 0; c < 3; ++c)
            if (ref[s].average[c] > 0) worst = std::max(worst, std::abs(avg[s].average[c] / ref[s].average[c] - 1));
        std::printf("%-24s %8d %9.2f %13.3f%%\n", m.c_str(), mesh.size(), tm.seconds(), 100 * worst);
        std::fflush(stdout);
      }
  }
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
    write_plots_png(plot, {l1, line});
    std::printf("wrote %s\n", plot.c_str());
  }
  return 0;
}
