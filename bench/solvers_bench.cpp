// Radiosity solver benchmark, all figures measured in one run:
//  1. the machine's memory bandwidth, a STREAM-like triad a = b + s c (24 bytes per element,
//     STREAM's counting), single thread, median of repetitions;
//  2. per-iteration time of the SpMV-bound solvers (jacobi, gauss-seidel) on the Cornell box,
//     the bytes one iteration must move (F values 8 nnz + column indices 4 nnz + row offsets
//     4 (N+1) + the N-vectors read and written), and the ratio of that rate to the triad's;
//  3. time to a relative residual of 1e-8 for every solver on the same system.
// Usage: solvers_bench [--patches N (10000)] [--samples S (4)] [--threads T (1)]
//                      [--direct-max N (5000): skip `direct` above N patches (dense LU, O(N^3))]

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/timer.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "pipeline/job.hpp"
#include "pipeline/problem.hpp"
#include "solvers/radiosity.hpp"

namespace {

using lambert::Timer;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// STREAM triad on arrays far larger than the caches; returns bytes/s (median of 9).
double triad_bandwidth() {
  const std::size_t n = std::size_t{1} << 25;  // 32 Mi doubles = 256 MiB per array
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  std::vector<double> rates;
  for (int rep = 0; rep < 9; ++rep) {
    const double s = 0.5 + rep;
    Timer t;
    double* ap = a.data();
    const double* bp = b.data();
    const double* cp = c.data();
    for (std::size_t i = 0; i < n; ++i) ap[i] = bp[i] + s * cp[i];
    const double sec = t.seconds();
    rates.push_back(24.0 * static_cast<double>(n) / sec);
  }
  volatile double sink = a[n / 3];  // keep the loop
  (void)sink;
  return median(rates);
}

}  // namespace

int main(int argc, char** argv) {
  std::int64_t patches = 10000, direct_max = 5000;
  int samples = 4, threads = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--patches")
      patches = std::atoll(argv[i + 1]);
    else if (k == "--samples")
      samples = std::atoi(argv[i + 1]);
    else if (k == "--threads")
      threads = std::atoi(argv[i + 1]);
    else if (k == "--direct-max")
      direct_max = std::atoll(argv[i + 1]);
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }

  const double bandwidth = triad_bandwidth();
  std::printf("memory bandwidth (triad, 1 thread, median of 9): %.2f GB/s\n", bandwidth / 1e9);

  lambert::SceneArgs sa;
  sa.patches = patches;
  const lambert::LoadedScene scene = lambert::load_scene(sa);
  lambert::FormFactorOptions fo;
  fo.estimator = "hybrid";
  fo.pair.samples = samples;
  fo.run.progress = false;
  Timer ff_timer;
  const lambert::FormFactors ff = lambert::compute_form_factors(scene.mesh, fo);
  const double ff_seconds = ff_timer.seconds();
  const double n = scene.mesh.size();
  const double nnz = static_cast<double>(ff.F.nonZeros());
  std::printf(
      "Cornell box: %d patches, F: %.0f non-zeros (%.1f%% full, %.0f MB), computed in "
      "%.1f s (hybrid, %d samples, all cores)\n",
      scene.mesh.size(), nnz, 100.0 * nnz / (n * n), 12e-6 * nnz, ff_seconds, samples);
  const lambert::RadiosityProblem problem = lambert::make_problem(scene.mesh, ff.F);

  // 2. Per-iteration cost of the SpMV-bound solvers: a fixed number of iterations (the
  // tolerance is unreachable), channel R only would do, but solve_radiosity runs all three.
  constexpr int kIterations = 30;
  std::printf("\nper-iteration time (%d iterations x 3 channels, %d thread(s)):\n", kIterations,
              threads);
  std::printf("%-13s %12s %12s %12s %10s\n", "solver", "ms/iter", "MB/iter", "GB/s", "of triad");
  // Bytes per iteration: F (8 nnz + 4 nnz + 4 (N+1)); x read once per entry in the best case
  // (x fits in cache: 8 N); jacobi also reads rho, E, diag, B, K B and writes B, K B (~8 N
  // vectors); gauss-seidel reads rho, E, diag and updates B in place (~5 N vectors).
  for (const char* name : {"jacobi", "gauss-seidel"}) {
    lambert::SolveOptions o;
    o.solver = name;
    o.tol = 1e-15;
    o.max_iterations = kIterations;
    o.threads = threads;
    std::vector<double> per;
    for (int rep = 0; rep < 3; ++rep) {
      const lambert::RadiositySolution s = lambert::solve_radiosity(problem, o);
      int its = 0;
      for (const auto& c : s.channels) its += c.iterations;
      per.push_back(s.seconds / its);
    }
    const double sec = median(per);
    const double vectors = std::strcmp(name, "jacobi") == 0 ? 8.0 : 5.0;
    const double bytes = 12.0 * nnz + 4.0 * (n + 1) + 8.0 * vectors * n;
    std::printf("%-13s %12.3f %12.1f %12.2f %9.0f%%\n", name, 1e3 * sec, bytes / 1e6,
                bytes / sec / 1e9, 100.0 * bytes / sec / bandwidth);
  }

  // 3. Time to 1e-8 for every solver.
  std::printf("\ntime to relative residual 1e-8 (3 channels, %d thread(s)):\n", threads);
  std::printf("%-13s %-15s %10s %10s %10s %12s\n", "solver", "status", "iterations", "mat-vecs",
              "seconds", "residual");
  for (const auto& name : lambert::solver_names()) {
    if (name == "direct" && scene.mesh.size() > direct_max) {
      std::printf("%-13s skipped (dense LU of a %d x %d matrix; raise --direct-max)\n",
                  name.c_str(), scene.mesh.size(), scene.mesh.size());
      continue;
    }
    lambert::SolveOptions o;
    o.solver = name;
    o.tol = 1e-8;
    o.threads = threads;
    const lambert::RadiositySolution s = lambert::solve_radiosity(problem, o);
    int its = 0;
    long long mv = 0;
    double res = 0.0;
    for (const auto& c : s.channels) {
      its += c.iterations;
      mv += c.matvecs;
      res = std::max(res, c.residual);
    }
    std::printf("%-13s %-15s %10d %10lld %10.3f %12.3e\n", name.c_str(),
                lambert::to_string(s.status), its, mv, s.seconds, res);
  }
  return 0;
}
