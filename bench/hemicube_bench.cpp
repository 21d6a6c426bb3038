// Hemicube benchmark (issue 6). Prints, for the Cornell box meshed at --patches:
//  1. a reference F: hybrid at --reference-samples with its own standard error;
//  2. for each sample count k of a sweep (1, 2, 4, ...), the time and error of "mc" and
//     "hybrid" (error = RMS |F_ij - Fref_ij| over the union of the sparsity patterns, and
//     max row-sum difference);
//  3. for each hemicube resolution (64/128/256 by default), its time and error, and the
//     smallest mc / hybrid sample count of the sweep reaching the same RMS error, with its time.
// Usage: hemicube_bench [--patches 10000] [--res 64,128,256] [--reference-samples 256]
//                       [--max-samples 256] [-j N] [--times-only]
// The machine is shared: times are wall-clock of one run each; compare within a run.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "core/log.hpp"
#include "core/parallel.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/formfactors/hemicube.hpp"
#include "io/obj_loader.hpp"

using namespace lambert;

namespace {

struct Measure {
  std::string estimator;
  int setting = 0;
  double seconds = 0.0;
  double rms = 0.0;      // RMS |F - Fref| over the union pattern
  double row_sum = 0.0;  // max_i |Σ_j F_ij - Σ_j Fref_ij|
};

void compare(const SparseF& F, const SparseF& ref, Measure& m) {
  const SparseF diff = F - ref;
  double sum2 = 0.0;
  for (std::int64_t k = 0; k < diff.nonZeros(); ++k) sum2 += std::pow(diff.valuePtr()[k], 2);
  m.rms = std::sqrt(sum2 / std::max<std::int64_t>(1, diff.nonZeros()));
  m.row_sum = (diff * Eigen::VectorXd::Ones(F.cols())).cwiseAbs().maxCoeff();
}

Measure run(const PatchMesh& mesh, const SparseF& ref, const std::string& estimator, int value,
            int threads) {
  FormFactorOptions o;
  o.estimator = estimator;
  if (estimator == "hemicube")
    o.hemicube.resolution = value;
  else
    o.pair.samples = value;
  o.run.threads = threads;
  o.run.progress = false;
  const FormFactors ff = compute_form_factors(mesh, o);
  Measure m{estimator, value, ff.stats.seconds};
  compare(ff.F, ref, m);
  std::fprintf(stderr, "  %-8s %5d  %8.2f s  rms %.3e\n", estimator.c_str(), value, m.seconds, m.rms);
  return m;
}

std::vector<int> parse_list(const char* s) {
  std::vector<int> out;
  for (const char* p = s; *p;) {
    out.push_back(std::atoi(p));
    while (*p && *p != ',') ++p;
    if (*p == ',') ++p;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::int64_t patches = 10000;
  std::vector<int> res{64, 128, 256};
  int reference_samples = 256, max_samples = 256, threads = 0;
  bool times_only = false;  // --times-only: hemicube times alone (for patch counts where the
                            // reference is too slow on a shared machine)
  for (int a = 1; a < argc; ++a) {
    const bool more = a + 1 < argc;
    if (!std::strcmp(argv[a], "--patches") && more) patches = std::atoll(argv[++a]);
    else if (!std::strcmp(argv[a], "--res") && more) res = parse_list(argv[++a]);
    else if (!std::strcmp(argv[a], "--reference-samples") && more) reference_samples = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--max-samples") && more) max_samples = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "-j") && more) threads = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--times-only")) times_only = true;
    else {
      std::fprintf(stderr, "usage: hemicube_bench [--patches N] [--res 64,128,256] "
                           "[--reference-samples K] [--max-samples K] [-j N] [--times-only]\n");
      return 2;
    }
  }
  set_log_level(LogLevel::Quiet);
  const Scene scene = load_obj(builtin_cornell_box_path());
  const PatchMesh mesh = mesh_scene(scene, {0.0, patches});
  std::printf("Cornell box, %d patches, %d threads\n", mesh.size(), resolve_threads(threads));
  if (times_only) {
    for (int r : res) {
      FormFactorOptions o;
      o.estimator = "hemicube";
      o.hemicube.resolution = r;
      o.run.threads = threads;
      o.run.progress = false;
      ff::HemicubeStats hs;
      const FormFactors ff = ff::compute_hemicube(mesh, o, &hs);
      std::printf("hemicube N=%-4d %8.2f s  nnz %lld  pixels tested %.3g\n", r, ff.stats.seconds,
                  static_cast<long long>(ff.F.nonZeros()), static_cast<double>(hs.pixels));
    }
    return 0;
  }

  FormFactorOptions ro;
  ro.pair.samples = reference_samples;
  ro.run.seed = 0x5EED;  // a stream independent of the sweep's (seed 1), so hybrid at k equal
                         // to the reference's count is not compared with itself
  ro.run.threads = threads;
  ro.run.with_stderr = true;
  ro.run.progress = false;
  const FormFactors ref = compute_form_factors(mesh, ro);
  double se2 = 0.0;
  for (std::int64_t k = 0; k < ref.stderr_F.nonZeros(); ++k) se2 += std::pow(ref.stderr_F.valuePtr()[k], 2);
  const double ref_se = std::sqrt(se2 / std::max<std::int64_t>(1, ref.stderr_F.nonZeros()));
  std::printf("reference: hybrid k=%d in %.1f s, RMS standard error per entry %.3e "
              "(errors below ~2x this are not resolved)\n\n",
              reference_samples, ref.stats.seconds, ref_se);

  std::vector<Measure> sweep;
  for (const char* est : {"mc", "hybrid"})
    for (int k = 1; k <= max_samples; k *= 2) sweep.push_back(run(mesh, ref.F, est, k, threads));
  std::vector<Measure> cubes;
  for (int r : res) cubes.push_back(run(mesh, ref.F, "hemicube", r, threads));

  std::printf("%-10s %10s %12s %12s\n", "estimator", "setting", "time (s)", "RMS |dF|");
  for (const auto& m : sweep)
    std::printf("%-10s %10s %12.2f %12.3e\n", m.estimator.c_str(), ("k=" + std::to_string(m.setting)).c_str(), m.seconds, m.rms);
  for (const auto& m : cubes)
    std::printf("%-10s %10s %12.2f %12.3e\n", m.estimator.c_str(), ("N=" + std::to_string(m.setting)).c_str(), m.seconds, m.rms);

  std::printf("\n%-10s %10s %12s | %-22s | %-22s\n", "hemicube", "time (s)", "RMS |dF|",
              "mc: k reaching it, time", "hybrid: k reaching it, time");
  for (const auto& c : cubes) {
    std::printf("N=%-8d %10.2f %12.3e", c.setting, c.seconds, c.rms);
    for (const char* est : {"mc", "hybrid"}) {
      const auto it = std::find_if(sweep.begin(), sweep.end(), [&](const Measure& m) {
        return m.estimator == est && m.rms <= c.rms;
      });
      if (it == sweep.end()) std::printf(" | %-22s", ("> " + std::to_string(max_samples)).c_str());
      else std::printf(" | k=%-5d %8.2f s     ", it->setting, it->seconds);
    }
    std::printf("\n");
  }
  return 0;
}
