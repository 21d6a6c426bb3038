// Estimator accuracy at equal time (issue 11): the error of `gather` and of `hybrid` on the
// built-in Cornell box against a high-sample reference, each timed, and which one is more
// accurate at the time the other takes.
//
// Reference: `gather` with `--ref-rays` K rays per patch and reciprocity none (every entry
// the mean of K Bernoulli hits, so unbiased entry by entry; averaging's balancing is a
// nonlinear correction with a small bias of its own), run as two independent halves of K/2
// rays (seeds 1001, 1002) and averaged: F_ref = (F_1 + F_2) / 2. The reference's own error
// in any quantity Q is estimated as |Q_1 - Q_2| / 2 (the error of the mean of two independent
// unbiased estimates), printed, and subtracted in quadrature from the RMS errors in the
// equal-time comparison.
//
// Metrics of each contender against the reference:
//  - surface table: S_GH = Σ_{i∈G} A_i Σ_{j∈H} F_ij / A_G (surface_factors), max and RMS
//    of |S - S_ref| over all surface pairs;
//  - row sums Σ_j F_ij per patch: max and RMS of the absolute error;
//  - B: each F solved with gauss-seidel to tol 1e-10 (make_problem, solve_radiosity);
//    per patch sqrt(Σ_i A_i |B_i - Bref_i|² / Σ_i A_i |Bref_i|²) (all three channels), and
//    the same over the per-surface area-weighted averages of B.
// Equal time: for each hybrid run, gather's error at hybrid's time from the power law
// error = c t^p fitted (log-log least squares) to the gather runs.
//
// Usage: estimator_accuracy_bench [--patches 10000] [--ref-rays 65536] [--samples 4,8,16]
//                                 [--rays 256,512,...,32768] [-j N] [--plot out.svg]
// Wall times on a shared machine: quote them as measured.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bench/power_law.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/analysis.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "io/obj_loader.hpp"
#include "io/plot.hpp"
#include "pipeline/problem.hpp"
#include "solvers/radiosity.hpp"

using namespace lambert;

namespace {

// Solver tolerance: ||B - B*|| <= tol ||E|| / (1 - ρmax) ~ 1e-9 relative for ρ <= 0.9, far
// below the F-induced differences measured here (>= 1e-5).
constexpr double kSolveTol = 1e-10;

// What a user reads from one F.
struct Quantities {
  Eigen::MatrixXd surface_F;   // surface table
  Eigen::VectorXd row_sums;    // per patch
  Eigen::MatrixX3d B;          // per patch radiosity
  Eigen::MatrixX3d B_surface;  // per surface average radiosity
};

// Errors of one set of quantities against another (the metrics above).
struct Errors {
  double sf_max = 0, sf_rms = 0, row_max = 0, row_rms = 0, b_rms = 0, bs_rms = 0;
};
constexpr int kMetrics = 6;
const char* const kMetricNames[kMetrics] = {"surfF max", "surfF rms", "rowsum max",
                                            "rowsum rms", "B rel", "Bsurf rel"};
double metric(const Errors& e, int k) {
  const double v[kMetrics] = {e.sf_max, e.sf_rms, e.row_max, e.row_rms, e.b_rms, e.bs_rms};
  return v[k];
}

struct Run {
  std::string estimator, setting;
  double seconds = 0;
  std::int64_t rays = 0;
  Errors err;
};

Quantities quantities(const PatchMesh& mesh, const FormFactors& ff, int threads) {
  Quantities q;
  q.surface_F = surface_factors(mesh, ff).F;
  q.row_sums = ff.F * Eigen::VectorXd::Ones(ff.F.cols());
  SolveOptions so;
  so.solver = "gauss-seidel";
  so.tol = kSolveTol;
  so.threads = threads;
  const RadiositySolution sol = solve_radiosity(make_problem(mesh, ff.F), so);
  if (sol.status != SolveStatus::Converged)
    std::fprintf(stderr, "warning: gauss-seidel did not converge (%s)\n", to_string(sol.status));
  q.B = sol.B;
  const auto surf = surface_averages(mesh, sol.B);
  q.B_surface.resize(static_cast<Eigen::Index>(surf.size()), 3);
  for (size_t s = 0; s < surf.size(); ++s) q.B_surface.row(s) = surf[s].average.transpose();
  return q;
}

// sqrt(Σ_k w_k |a_k - b_k|² / Σ_k w_k |b_k|²) over the rows k of a and b.
double relative_rms(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b,
                    const Eigen::VectorXd& w) {
  return std::sqrt(w.dot((a - b).rowwise().squaredNorm()) / w.dot(b.rowwise().squaredNorm()));
}

Errors compare(const Quantities& a, const Quantities& ref, const Eigen::VectorXd& patch_area,
               const Eigen::VectorXd& surface_area) {
  Errors e;
  const Eigen::ArrayXXd ds = (a.surface_F - ref.surface_F).array().abs();
  e.sf_max = ds.maxCoeff();
  e.sf_rms = std::sqrt(ds.square().mean());
  const Eigen::ArrayXd dr = (a.row_sums - ref.row_sums).array().abs();
  e.row_max = dr.maxCoeff();
  e.row_rms = std::sqrt(dr.square().mean());
  e.b_rms = relative_rms(a.B, ref.B, patch_area);
  e.bs_rms = relative_rms(a.B_surface, ref.B_surface, surface_area);
  return e;
}

// The errors with the reference's own RMS noise taken out in quadrature (max metrics kept).
Errors corrected(Errors e, const Errors& noise) {
  auto q = [](double x, double n) { return std::sqrt(std::max(0.0, x * x - n * n)); };
  e.sf_rms = q(e.sf_rms, noise.sf_rms);
  e.row_rms = q(e.row_rms, noise.row_rms);
  e.b_rms = q(e.b_rms, noise.b_rms);
  e.bs_rms = q(e.bs_rms, noise.bs_rms);
  return e;
}

std::vector<int> parse_list(const char* s) {
  std::vector<int> v;
  std::string str(s);
  for (size_t a = 0; a <= str.size();) {
    const size_t b = std::min(str.find(',', a), str.size());
    v.push_back(std::atoi(str.substr(a, b - a).c_str()));
    a = b + 1;
  }
  return v;
}

void print_row(const Run& r) {
  std::printf("%-8s %-14s %9.2f %12.3e", r.estimator.c_str(), r.setting.c_str(), r.seconds,
              static_cast<double>(r.rays));
  for (int k = 0; k < kMetrics; ++k) std::printf(" %11.3e", metric(r.err, k));
  std::printf("\n");
}

void write_plot(const std::string& path, const std::vector<Run>& runs, const Errors& noise,
                int patches) {
  const int shown[4] = {1, 3, 4, 5};
  const char* titles[4] = {"surface view factors: RMS abs error", "row sums: RMS abs error",
                           "B per patch: area-weighted rel RMS", "B per surface: rel RMS"};
  std::vector<Plot> panels;
  double t_min = 1e300, t_max = 0;
  for (const auto& r : runs) t_min = std::min(t_min, r.seconds), t_max = std::max(t_max, r.seconds);
  for (int p = 0; p < 4; ++p) {
    Plot plot;
    plot.title = std::string(titles[p]) + " (" + std::to_string(patches) + " patches)";
    plot.x_label = "seconds (compute_form_factors, wall)";
    plot.y_label = "error vs reference";
    plot.log_x = plot.log_y = plot.markers = true;
    for (const char* est : {"hybrid", "gather"}) {
      PlotSeries s{std::string(est) + (std::string(est) == "hybrid" ? " (samples 4..)" : " (rays 256..)"),
                   {}, {}};
      for (const auto& r : runs)
        if (r.estimator == est) s.x.push_back(r.seconds), s.y.push_back(metric(r.err, shown[p]));
      plot.series.push_back(s);
    }
    const double n = metric(noise, shown[p]);
    plot.series.push_back({"reference's own error", {t_min, t_max}, {n, n}});
    panels.push_back(plot);
  }
  write_plots_svg(path, panels);
}

}  // namespace

int main(int argc, char** argv) {
  set_log_level(LogLevel::Quiet);
  int patches = 10000, ref_rays = 65536, threads = resolve_threads(0);
  std::vector<int> samples = {4, 8, 16}, rays = {256, 512, 1024, 2048, 4096, 8192, 16384, 32768};
  std::string plot_path;
  for (int a = 1; a < argc; ++a) {
    const bool has = a + 1 < argc;
    if (!std::strcmp(argv[a], "--patches") && has) patches = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--ref-rays") && has) ref_rays = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--samples") && has) samples = parse_list(argv[++a]);
    else if (!std::strcmp(argv[a], "--rays") && has) rays = parse_list(argv[++a]);
    else if (!std::strcmp(argv[a], "-j") && has) threads = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--plot") && has) plot_path = argv[++a];
    else {
      std::fprintf(stderr, "unknown or incomplete option %s\n", argv[a]);
      return 2;
    }
  }
  Timer total;
  const PatchMesh mesh = mesh_scene(load_obj(builtin_cornell_box_path()), {0.0, patches});
  Eigen::VectorXd patch_area(mesh.size());
  Eigen::VectorXd surface_area = Eigen::VectorXd::Zero(mesh.surface_names.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    patch_area[i] = mesh.patches[i].area;
    surface_area[mesh.patches[i].surface] += mesh.patches[i].area;
  }
  auto options = [&](const char* est, int count, std::uint64_t seed, const char* recip) {
    FormFactorOptions o;
    o.estimator = est;
    (std::string(est) == "gather" ? o.gather.rays : o.pair.samples) = count;
    o.run.seed = seed;
    o.reciprocity = recip;
    o.run.threads = threads;
    o.run.progress = false;
    return o;
  };

  // Reference: two independent halves, averaged.
  std::fprintf(stderr, "reference: gather, 2 x %d rays per patch, %d patches\n", ref_rays / 2,
               mesh.size());
  Timer ref_timer;
  FormFactors half1 = compute_form_factors(mesh, options("gather", ref_rays / 2, 1001, "none"));
  const Quantities q1 = quantities(mesh, half1, threads);
  FormFactors half2 = compute_form_factors(mesh, options("gather", ref_rays / 2, 1002, "none"));
  const Quantities q2 = quantities(mesh, half2, threads);
  FormFactors ref;
  ref.F = (0.5 * (half1.F + half2.F)).pruned();
  half1 = FormFactors();
  half2 = FormFactors();
  const Quantities qref = quantities(mesh, ref, threads);
  Errors noise = compare(q1, q2, patch_area, surface_area);
  for (double* x : {&noise.sf_max, &noise.sf_rms, &noise.row_max, &noise.row_rms, &noise.b_rms,
                    &noise.bs_rms})
    *x /= 2.0;
  const double ref_seconds = ref_timer.seconds();
  const std::int64_t ref_nnz = ref.F.nonZeros();
  ref = FormFactors();

  std::vector<Run> runs;
  auto contender = [&](const char* est, int count) {
    std::fprintf(stderr, "%s %d ...\n", est, count);
    Timer t;
    const FormFactors ff = compute_form_factors(mesh, options(est, count, 1, "auto"));
    Run r{est, std::string(std::string(est) == "gather" ? "rays " : "samples ") +
                   std::to_string(count), t.seconds(), ff.stats.rays, {}};
    r.err = compare(quantities(mesh, ff, threads), qref, patch_area, surface_area);
    runs.push_back(r);
  };
  for (int k : rays) contender("gather", k);
  for (int s : samples) contender("hybrid", s);

  std::printf("Cornell box, %d patches, %d threads; reference: gather, reciprocity none, "
              "2 x %d rays per patch (%.0f s incl. 3 solves, nnz %lld)\n",
              mesh.size(), threads, ref_rays / 2, ref_seconds, static_cast<long long>(ref_nnz));
  std::printf("gather contenders: reciprocity average (its default); hybrid: reciprocal by "
              "construction. B solved with gauss-seidel, tol %.0e.\n\n", kSolveTol);
  std::printf("%-8s %-14s %9s %12s", "estim.", "setting", "seconds", "rays");
  for (int k = 0; k < kMetrics; ++k) std::printf(" %11s", kMetricNames[k]);
  std::printf("\n");
  for (const auto& r : runs) print_row(r);
  print_row({"ref-err", "|half1-half2|/2", 0, 0, noise});

  std::printf("\nequal time (RMS metrics with the reference's error removed in quadrature; "
              "gather from a power law fitted to its runs, at hybrid's time; * = extrapolated):\n");
  std::printf("%-14s %9s", "hybrid", "seconds");
  for (int k = 0; k < kMetrics; ++k) std::printf(" %11s %11s", kMetricNames[k], "gather");
  std::printf("\n");
  // Per metric over the hybrid runs: how often hybrid was smaller, gather smaller, or both
  // below what the reference resolves (raw error < 2 x the reference's own error).
  int wins[kMetrics][3] = {};
  for (const auto& h : runs) {
    if (h.estimator != "hybrid") continue;
    std::printf("%-14s %9.2f", h.setting.c_str(), h.seconds);
    for (int k = 0; k < kMetrics; ++k) {
      std::vector<std::pair<double, double>> pts;
      for (const auto& g : runs)
        if (g.estimator == "gather") pts.push_back({g.seconds, metric(g.err, k)});
      const PowerLaw law = fit_power_law(pts);
      const bool extra = law.extrapolates(h.seconds);
      Errors g_err;
      double* g_slot[kMetrics] = {&g_err.sf_max, &g_err.sf_rms, &g_err.row_max,
                                  &g_err.row_rms, &g_err.b_rms,  &g_err.bs_rms};
      *g_slot[k] = law.at(h.seconds);
      const double n = metric(noise, k);
      const bool h_res = metric(h.err, k) > 2 * n, g_res = *g_slot[k] > 2 * n;
      const double he = metric(corrected(h.err, noise), k), ge = metric(corrected(g_err, noise), k);
      const int w = h_res && g_res ? (he < ge ? 0 : 1) : h_res ? 1 : g_res ? 0 : 2;
      ++wins[k][w];
      std::printf(" %11.3e %9.3e%s%s", he, ge, w == 0 ? "h" : w == 1 ? "g" : "=", extra ? "*" : " ");
    }
    std::printf("\n");
  }
  std::printf("(h: hybrid smaller, g: gather smaller, =: both below 2 x the reference's own "
              "error)\n\nwinner at equal time:");
  for (int k = 0; k < kMetrics; ++k)
    std::printf("  %s: hybrid %d, gather %d, unresolved %d;", kMetricNames[k], wins[k][0],
                wins[k][1], wins[k][2]);
  std::printf("\ntotal run time %.0f s\n", total.seconds());
  if (!plot_path.empty()) write_plot(plot_path, runs, noise, mesh.size());
  return 0;
}
