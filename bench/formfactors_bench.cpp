// Form-factor engine benchmark (issue 3). Prints, in one run:
//  1. raw Embree occlusion-ray throughput of the scene's BVH on the same rays the "mc"
//     estimator traces (pre-generated for a random subset of pairs, so only the traversal
//     is timed), with the same thread count, one ray at a time (rtcOccluded1) and as one
//     packet per pair (rtcOccluded4/8/16, what mc and hybrid trace);
//  2. end-to-end throughput of the full "mc" and "hybrid" fills (sampling, kernels, culling,
//     matrix assembly included) and the ratio end-to-end / raw; the same for "gather"
//     against raw Embree closest-hit rays from the patches in cosine-distributed directions
//     (the rays gather traces);
//  2b. the same end-to-end fills on CAD slivers: the generated heat sink of data/heat_sink
//     (3,852 facets up to 100 mm x 0.05 mm, issue 36), rays/s and the ratio to the Cornell
//     box's per-ray rate of the same estimator in the same run, and raw Embree on its rays;
//  2c. the same for "hemicube" (directions, i.e. pixels, per second against closest-hit
//     rays) and for the specular pass of the extended form factors (segments per second on
//     the specular Cornell box against raw closest-hit rays on its BVH);
//  3. time and peak memory of the Cornell box fill at ~2,000, ~10,000 and ~30,000 patches,
//     each in a forked child so that its peak RSS is its own.
// Usage: formfactors_bench [--quick] [--repeats N] [--sizes 2000,10000,30000] [--samples K]
//                          [--rays K] [-j N]
// Medians over repeats (default 3, 1 with --quick) are quoted; the machine is shared, so
// compare ratios.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/child.hpp"
#include "bench/raw_rays.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/specular.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/obj_loader.hpp"
#include "io/stl_loader.hpp"

using namespace lambert;

namespace {

struct Ray {
  Eigen::Vector3f org, dir;
};

// The rays "mc" would trace for `pairs` random exchanging pairs (same sampling and offsets).
std::vector<Ray> mc_rays(const PatchMesh& mesh, int samples, std::int64_t pairs,
                         std::vector<std::int64_t>* starts = nullptr) {
  const auto geom = ff::patch_geometry(mesh);
  std::vector<Ray> rays;
  Rng rng(12345);
  const double offset = 1e-6 * mesh.scale;
  while (static_cast<std::int64_t>(rays.size()) < pairs * samples) {
    const auto i = static_cast<std::int32_t>(rng.uniform() * mesh.size());
    const auto j = static_cast<std::int32_t>(rng.uniform() * mesh.size());
    if (i == j || !ff::can_exchange(geom[i], geom[j], 1e-12 * mesh.scale)) continue;
    const Kronecker4 seq(hash_keys(1, i, j));
    if (starts) starts->push_back(static_cast<std::int64_t>(rays.size()));
    for (int s = 0; s < samples; ++s) {
      double ja, jb;
      const Eigen::Vector3d x = ff::sample_patch(geom[i], seq.get(s, 0), seq.get(s, 1), ja);
      const Eigen::Vector3d y = ff::sample_patch(geom[j], seq.get(s, 2), seq.get(s, 3), jb);
      const Eigen::Vector3d d = y - x;
      if (geom[i].normal.dot(d) <= 0 || geom[j].normal.dot(d) >= 0) continue;
      const Eigen::Vector3d a = x + offset * geom[i].normal, b = y + offset * geom[j].normal;
      rays.push_back({a.cast<float>(), (b - a).cast<float>()});
    }
  }
  return rays;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Rays per second of bvh.occluded over `rays` on `threads` threads.
double raw_throughput(const Bvh& bvh, const std::vector<Ray>& rays, int threads) {
  std::vector<char> hit(rays.size());
  Timer t;
  parallel_for(static_cast<std::int64_t>(rays.size()), 4096, threads,
               [&](std::int64_t b, std::int64_t e) {
                 for (auto k = b; k < e; ++k) hit[k] = bvh.occluded(rays[k].org, rays[k].dir, 0.0f, 1.0f);
               });
  return static_cast<double>(rays.size()) / t.seconds();
}

// Rays per second of bvh.occluded_packet over `rays`, one packet per pair (`starts`).
double raw_packet_throughput(const Bvh& bvh, const std::vector<Ray>& rays,
                             const std::vector<std::int64_t>& starts, int threads) {
  std::vector<char> hit(rays.size());
  Timer t;
  const auto groups = static_cast<std::int64_t>(starts.size());
  parallel_for(groups, 256, threads, [&](std::int64_t b, std::int64_t e) {
    Eigen::Vector3f o[Bvh::kPacket], d[Bvh::kPacket];
    bool h[Bvh::kPacket];
    for (auto g = b; g < e; ++g) {
      const std::int64_t lo = starts[g], hi = g + 1 < groups
                                                  ? starts[g + 1]
                                                  : static_cast<std::int64_t>(rays.size());
      for (std::int64_t k0 = lo; k0 < hi; k0 += Bvh::kPacket) {
        const int n = static_cast<int>(std::min<std::int64_t>(Bvh::kPacket, hi - k0));
        for (int k = 0; k < n; ++k) o[k] = rays[k0 + k].org, d[k] = rays[k0 + k].dir;
        bvh.occluded_packet(o, d, n, h);
        for (int k = 0; k < n; ++k) hit[k0 + k] = h[k];
      }
    }
  });
  return static_cast<double>(rays.size()) / t.seconds();
}

// Options for one fill by `estimator` on `threads` threads, without progress output.
FormFactorOptions bench_options(const char* estimator, int threads) {
  FormFactorOptions o;
  o.estimator = estimator;
  o.run.threads = threads;
  o.run.progress = false;
  return o;
}

// Rays per second of a whole fill of F by a pair estimator (stats.rays / stats.seconds).
double fill_rate(const PatchMesh& mesh, const char* estimator, int samples, int threads) {
  FormFactorOptions o = bench_options(estimator, threads);
  o.pair.samples = samples;
  const FormFactors ff = compute_form_factors(mesh, o);
  return ff.stats.rays / ff.stats.seconds;
}

PatchMesh cornell(std::int64_t patches) {
  return mesh_scene(load_obj(builtin_cornell_box_path()), {0.0, patches});
}

struct ChildResult {
  double seconds = 0, rays = 0, nnz = 0;
  int patches = 0;
  long max_rss_kb = 0;
};

// Runs one fill in a forked child and returns its time and peak RSS.
ChildResult fill_in_child(std::int64_t patches, const FormFactorOptions& o) {
  long rss = 0;
  ChildResult r = run_in_child<ChildResult>(
      [&] {
        const PatchMesh mesh = cornell(patches);
        const FormFactors ff = compute_form_factors(mesh, o);
        return ChildResult{ff.stats.seconds, static_cast<double>(ff.stats.rays),
                           static_cast<double>(ff.F.nonZeros()), mesh.size(), 0};
      },
      rss);
  r.max_rss_kb = rss;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  set_log_level(LogLevel::Quiet);
  bool quick = false;
  int threads = resolve_threads(0);
  int samples = 16;
  int gather_k = 1024;
  int repeats = 0;  // 0: 1 with --quick, else 3
  std::vector<std::int64_t> sizes = {2000, 10000, 30000};
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--quick")) quick = true;
    else if (!std::strcmp(argv[a], "-j") && a + 1 < argc) threads = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--samples") && a + 1 < argc) samples = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--repeats") && a + 1 < argc)
      repeats = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--rays") && a + 1 < argc) gather_k = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--sizes") && a + 1 < argc) {
      sizes.clear();
      for (char* tok = std::strtok(argv[++a], ","); tok; tok = std::strtok(nullptr, ","))
        sizes.push_back(std::atoll(tok));
    }
  }
  if (quick) sizes = {2000};

  // 1 + 2: throughput ratio on the Cornell box at ~2,000 patches.
  const PatchMesh mesh = cornell(2000);
  const Bvh bvh(mesh);
  std::vector<std::int64_t> starts;
  const std::vector<Ray> rays = mc_rays(mesh, samples, quick ? 50000 : 300000, &starts);
  std::printf("Cornell box, %d patches, %d threads, %d samples per pair\n", mesh.size(), threads, samples);
  std::vector<double> raw, raw_packet, e2e_mc, e2e_hybrid;
  if (repeats < 1) repeats = quick ? 1 : 3;
  for (int r = 0; r < repeats; ++r) {
    raw.push_back(raw_throughput(bvh, rays, threads));
    raw_packet.push_back(raw_packet_throughput(bvh, rays, starts, threads));
    e2e_mc.push_back(fill_rate(mesh, "mc", samples, threads));
    e2e_hybrid.push_back(fill_rate(mesh, "hybrid", samples, threads));
  }
  const double raw_m = median(raw), mc_m = median(e2e_mc), hy_m = median(e2e_hybrid);
  std::printf("\n%-34s %14s %8s\n", "throughput (median of runs)", "Mrays/s", "ratio");
  std::printf("%-34s %14.2f %8s\n", "raw Embree rtcOccluded1", raw_m / 1e6, "1.00");
  std::printf("%-34s %14.2f %8.2f\n", "raw Embree rtcOccluded16 per pair", median(raw_packet) / 1e6,
              median(raw_packet) / raw_m);
  std::printf("%-34s %14.2f %8.2f\n", "end-to-end fill, estimator mc", mc_m / 1e6, mc_m / raw_m);
  std::printf("%-34s %14.2f %8.2f\n", "end-to-end fill, estimator hybrid", hy_m / 1e6, hy_m / raw_m);

  // 2b: CAD slivers. The heat sink keeps one patch per facet (its 3,852 facets are over the
  // 2,000 target), as `lambert formfactors heat_sink.stl` meshes it.
  const std::filesystem::path sink_path =
      std::filesystem::path(builtin_cornell_box_path()).parent_path().parent_path() / "heat_sink" /
      "heat_sink.stl";
  if (std::filesystem::exists(sink_path)) {
    const PatchMesh sink = mesh_scene(load_scene_path(sink_path.string()), {0.0, 2000});
    std::vector<double> sink_mc, sink_hybrid;
    for (int r = 0; r < repeats; ++r) {
      sink_mc.push_back(fill_rate(sink, "mc", samples, threads));
      sink_hybrid.push_back(fill_rate(sink, "hybrid", samples, threads));
    }
    const Bvh sink_bvh(sink);
    std::vector<std::int64_t> sink_starts;
    const std::vector<Ray> sink_rays = mc_rays(sink, samples, quick ? 50000 : 300000, &sink_starts);
    std::vector<double> sink_raw, sink_raw_packet;
    for (int r = 0; r < repeats; ++r) {
      sink_raw.push_back(raw_throughput(sink_bvh, sink_rays, threads));
      sink_raw_packet.push_back(raw_packet_throughput(sink_bvh, sink_rays, sink_starts, threads));
    }
    std::printf("%-34s %14.2f %8s  %.2f of the Cornell box's per ray\n",
                "heat sink, raw rtcOccluded1", median(sink_raw) / 1e6, "-",
                median(sink_raw) / raw_m);
    std::printf("%-34s %14.2f %8s  %.2f of the Cornell box's per ray\n",
                "heat sink, raw rtcOccluded16", median(sink_raw_packet) / 1e6, "-",
                median(sink_raw_packet) / median(raw_packet));
    const double smc = median(sink_mc), shy = median(sink_hybrid);
    // Its own BVH, so no ratio to the Cornell box's raw rays: the per-ray rate against the
    // Cornell box's fill with the same estimator instead.
    std::printf("%-34s %14.2f %8s  %.2f of the Cornell box's mc per ray\n",
                "heat sink (CAD slivers), mc", smc / 1e6, "-", smc / mc_m);
    std::printf("%-34s %14.2f %8s  %.2f of the Cornell box's hybrid per ray\n",
                "heat sink (CAD slivers), hybrid", shy / 1e6, "-", shy / hy_m);
  }

  // Gather: closest-hit rays, K per patch.
  const std::vector<BenchRay> grays = hemisphere_rays(mesh, gather_k);
  std::vector<double> raw_closest, raw_closest_packet, e2e_gather;
  for (int r = 0; r < repeats; ++r) {
    raw_closest.push_back(raw_closest_hit_rate(bvh, grays, threads));
    raw_closest_packet.push_back(raw_closest_hit_packet_rate(bvh, grays, threads));
    FormFactorOptions o = bench_options("gather", threads);
    o.gather.rays = gather_k;
    const FormFactors ff = compute_form_factors(mesh, o);
    e2e_gather.push_back(ff.stats.rays / ff.stats.seconds);
  }
  const double rc_m = median(raw_closest), ga_m = median(e2e_gather);
  std::printf("%-34s %14.2f %8s\n", "raw Embree rtcIntersect1", rc_m / 1e6, "1.00");
  std::printf("%-34s %14.2f %8.2f\n", "raw Embree rtcIntersect16 per patch",
              median(raw_closest_packet) / 1e6, median(raw_closest_packet) / rc_m);
  std::printf("%-34s %14.2f %8.2f\n", "end-to-end gather (+ averaging)", ga_m / 1e6, ga_m / rc_m);

  // Hemicube: each pixel of a patch's hemicube is one direction's closest hit, what one
  // gather ray finds, so its directions per second (3 res² per row: the top face and four
  // half faces) are compared with the same raw closest-hit rate.
  std::vector<double> e2e_hemicube;
  const int hemi_res = 128;
  for (int r = 0; r < repeats; ++r) {
    FormFactorOptions o = bench_options("hemicube", threads);
    o.hemicube.resolution = hemi_res;
    const FormFactors ff = compute_form_factors(mesh, o);
    e2e_hemicube.push_back(3.0 * hemi_res * hemi_res * mesh.size() / ff.stats.seconds);
  }
  const double hc_m = median(e2e_hemicube);
  std::printf("%-34s %14.2f %8.2f\n", "hemicube 128, directions (pixels)", hc_m / 1e6, hc_m / rc_m);

  // The specular pass (extended form factors) on the specular Cornell box: its segments
  // (closest-hit rays along the paths) per second against raw closest-hit rays on its BVH.
  const std::filesystem::path spec_path =
      std::filesystem::path(builtin_cornell_box_path()).parent_path().parent_path() /
      "cornell_box_specular" / "cornell_box_specular.obj";
  if (std::filesystem::exists(spec_path)) {
    const PatchMesh spec = mesh_scene(load_obj(spec_path.string()), {0.0, 2000});
    const Bvh spec_bvh(spec);
    const std::vector<BenchRay> spec_rays = hemisphere_rays(spec, gather_k);
    std::vector<double> spec_raw, spec_rate;
    for (int r = 0; r < repeats; ++r) {
      spec_raw.push_back(raw_closest_hit_rate(spec_bvh, spec_rays, threads));
      FormFactorOptions o = bench_options("gather", threads);
      o.specular.rays = gather_k;
      Timer t;
      const ff::SpecularTransport sp = ff::compute_specular_transport(spec, o, spec_bvh);
      spec_rate.push_back(static_cast<double>(sp.rays) / t.seconds());
    }
    std::printf("%-34s %14.2f %8s\n", "specular box, raw rtcIntersect1", median(spec_raw) / 1e6,
                "1.00");
    std::printf("%-34s %14.2f %8.2f\n", "specular pass, segments", median(spec_rate) / 1e6,
                median(spec_rate) / median(spec_raw));
  }

  // 3: time and peak memory per size.
  std::printf("\n%-9s %-9s %8s %10s %12s %10s %12s %12s\n", "target", "patches", "est", "samples",
              "rays", "nnz", "time s", "peak RSS MB");
  for (std::int64_t n : sizes) {
    FormFactorOptions o;
    // Beyond ~10,000 patches one ray per pair already gives a per-surface error well
    // below 1 %, and keeps the 30,000-patch fill (~3e8 pairs) within minutes on 2 cores.
    o.estimator = "mc";
    o.pair.samples = n > 10000 ? 1 : n > 2000 ? 4 : samples;
    o.run.threads = threads;
    o.run.progress = false;
    const ChildResult r = fill_in_child(n, o);
    std::printf("%-9lld %-9d %8s %10d %12.3g %10.3g %12.2f %12.0f\n", static_cast<long long>(n),
                r.patches, o.estimator.c_str(), o.pair.samples, r.rays, r.nnz, r.seconds,
                r.max_rss_kb / 1024.0);
    std::fflush(stdout);
  }
  return 0;
}
