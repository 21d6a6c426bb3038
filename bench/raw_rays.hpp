#pragma once
// Rays for measuring raw Embree throughput against the estimators (benchmarks only): the
// rays are generated first, so only the traversal is timed.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/visibility/bvh.hpp"

struct BenchRay {
  Eigen::Vector3f org, dir;
};

/// `per_patch` rays from every `stride`-th patch: uniform points, cosine-distributed
/// directions (Malley), origins lifted off the patch like gather's (1e-6 x diagonal).
inline std::vector<BenchRay> hemisphere_rays(const lambert::PatchMesh& mesh, int per_patch,
                                             int stride = 1) {
  const auto geom = lambert::ff::patch_geometry(mesh);
  std::vector<BenchRay> rays;
  lambert::Rng rng(54321);
  const double offset = 1e-6 * mesh.scale;
  for (std::int32_t i = 0; i < mesh.size(); i += stride) {
    const auto& g = geom[i];
    const Eigen::Vector3d t = g.normal.unitOrthogonal(), b = g.normal.cross(t);
    for (int s = 0; s < per_patch; ++s) {
      double jac;
      const Eigen::Vector3d x = lambert::ff::sample_patch(g, rng.uniform(), rng.uniform(), jac);
      const double u = rng.uniform(), phi = 2.0 * M_PI * rng.uniform(), r = std::sqrt(u);
      const Eigen::Vector3d d =
          r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(1.0 - u) * g.normal;
      rays.push_back({(x + offset * g.normal).cast<float>(), d.cast<float>()});
    }
  }
  return rays;
}

/// Rays per second of bvh.intersect (closest hit) over `rays` on `threads` threads.
inline double raw_closest_hit_rate(const lambert::Bvh& bvh, const std::vector<BenchRay>& rays,
                                   int threads) {
  std::vector<std::int32_t> hit(rays.size());
  lambert::Timer t;
  lambert::parallel_for(static_cast<std::int64_t>(rays.size()), 4096, threads,
                        [&](std::int64_t b, std::int64_t e) {
                          for (auto k = b; k < e; ++k)
                            hit[k] = bvh.intersect(rays[k].org, rays[k].dir).patch;
                        });
  return static_cast<double>(rays.size()) / t.seconds();
}

/// Rays per second of bvh.intersect_packet over `rays` in packets of 16 consecutive rays
/// (hemisphere_rays: one patch's rays together when per_patch is a multiple of 16).
inline double raw_closest_hit_packet_rate(const lambert::Bvh& bvh,
                                          const std::vector<BenchRay>& rays, int threads) {
  std::vector<std::int32_t> hit(rays.size());
  lambert::Timer t;
  const auto packets = static_cast<std::int64_t>((rays.size() + 15) / 16);
  lambert::parallel_for(packets, 256, threads, [&](std::int64_t b, std::int64_t e) {
    Eigen::Vector3f o[16], d[16];
    lambert::RayHit h[16];
    for (auto p = b; p < e; ++p) {
      const auto k0 = static_cast<size_t>(p) * 16;
      const int n = static_cast<int>(std::min<size_t>(16, rays.size() - k0));
      for (int k = 0; k < n; ++k) o[k] = rays[k0 + k].org, d[k] = rays[k0 + k].dir;
      bvh.intersect_packet(o, d, n, h);
      for (int k = 0; k < n; ++k) hit[k0 + k] = h[k].patch;
    }
  });
  return static_cast<double>(rays.size()) / t.seconds();
}
