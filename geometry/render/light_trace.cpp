#include "geometry/render/light_trace.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "geometry/formfactors/kernels.hpp"

namespace lambert {
namespace {

using ff::cosine_direction;
using ff::orthonormal_frame;
using ff::PatchGeom;

constexpr int kBatches = 64;
constexpr int kMaxBounces = 10000;  // a photon in a closed white scene would never stop

struct Batch {
  std::vector<Eigen::Vector3d> reflected;  // per surface, W
  Eigen::Vector3d escaped = Eigen::Vector3d::Zero();
  std::int64_t rays = 0, capped = 0;
};

}  // namespace

LightTraceResult light_trace(const PatchMesh& mesh, const Bvh& bvh, std::int64_t photons,
                             std::uint64_t seed, int threads) {
  const std::int32_t n = mesh.size();
  const std::size_t surfaces = mesh.surface_names.size();
  // The emitters' power and the CDF that picks one.
  std::vector<double> cdf;
  std::vector<std::int32_t> emitters;
  Eigen::Vector3d emitted = Eigen::Vector3d::Zero();
  double total = 0.0;
  for (std::int32_t i = 0; i < n; ++i) {
    const Patch& p = mesh.patches[i];
    const double power = p.area * p.emission.sum();
    if (!(power > 0.0)) continue;
    emitted += p.area * p.emission;
    total += power;
    emitters.push_back(i);
    cdf.push_back(total);
  }
  if (emitters.empty()) throw UsageError("light tracing: nothing emits");
  const std::vector<PatchGeom> geom = ff::patch_geometry(mesh);
  const std::int64_t per_batch = std::max<std::int64_t>(1, photons / kBatches);
  const double eps = 1e-6 * mesh.scale;  // start rays off their surface

  std::vector<Batch> batches(kBatches);
  parallel_for(kBatches, 1, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t b = begin; b < end; ++b) {
      Batch& out = batches[static_cast<std::size_t>(b)];
      out.reflected.assign(surfaces, Eigen::Vector3d::Zero());
      Rng rng(hash_keys(seed, 0x11687ace, static_cast<std::uint64_t>(b)));
      for (std::int64_t k = 0; k < per_batch; ++k) {
        const double pick = rng.uniform() * total;
        const std::size_t e = std::min<std::size_t>(
            static_cast<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin()),
            emitters.size() - 1);
        const std::int32_t i = emitters[e];
        const Patch& src = mesh.patches[i];
        double jacobian = 0.0;
        const double u = rng.uniform(), v = rng.uniform();
        Eigen::Vector3d x = ff::sample_patch(geom[i], u, v, jacobian);
        // Power A_i E_i / p_i, p_i = A_i sum(E_i) / total, times J / A_i for a non-uniform
        // bilinear map, shared by the batch's photons.
        Eigen::Vector3d w = src.emission * (total / src.emission.sum()) * (jacobian / src.area) /
                            static_cast<double>(per_batch);
        Eigen::Vector3d normal = src.normal;
        double lift = ff::end_lift(geom[i], eps);  // x is on the emitter's bilinear surface
        Eigen::Vector3d t, bt;
        int bounces = 0;
        for (;; ++bounces) {
          if (bounces == kMaxBounces) {
            ++out.capped;
            break;
          }
          orthonormal_frame(normal, t, bt);
          const Eigen::Vector3d d = cosine_direction(normal, t, bt, rng.uniform(), rng.uniform());
          const Eigen::Vector3d o = x + lift * normal;
          ++out.rays;
          const RayHit hit = bvh.intersect(o.cast<float>(), d.cast<float>());
          if (hit.patch < 0) {
            out.escaped += w;
            break;
          }
          const Patch& p = mesh.patches[hit.patch];
          if (d.dot(p.normal) >= 0.0) break;  // its back: absorbed
          const Eigen::Vector3d reflected = p.rho.cwiseProduct(w);
          out.reflected[static_cast<std::size_t>(p.surface)] += reflected;
          const double survive = p.rho.maxCoeff();
          if (!(survive > 0.0) || rng.uniform() >= survive) break;
          w = reflected / survive;
          x = o + hit.t * d;  // on the traced triangles
          normal = p.normal;
          lift = eps;
        }
      }
    }
  });

  LightTraceResult r;
  r.photons = per_batch * kBatches;
  r.surfaces.resize(surfaces);
  std::vector<Eigen::Vector3d> emission(surfaces, Eigen::Vector3d::Zero());
  for (std::size_t s = 0; s < surfaces; ++s) r.surfaces[s].name = mesh.surface_names[s];
  for (const Patch& p : mesh.patches) {
    r.surfaces[static_cast<std::size_t>(p.surface)].area += p.area;
    emission[static_cast<std::size_t>(p.surface)] += p.area * p.emission;
  }
  // Per surface: the batches' mean and its standard error (each batch's photons carry
  // 1/per_batch of the power: every batch is an unbiased estimate of the whole).
  for (std::size_t s = 0; s < surfaces; ++s) {
    TracedSurface& ts = r.surfaces[s];
    if (!(ts.area > 0.0)) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
    for (const Batch& b : batches) {
      const Eigen::Vector3d est = b.reflected[s] / ts.area;
      sum += est;
      sq += est.cwiseProduct(est);
    }
    const Eigen::Vector3d mean = sum / kBatches;
    const Eigen::Vector3d var =
        (sq / kBatches - mean.cwiseProduct(mean)).cwiseMax(0.0) * kBatches / (kBatches - 1.0);
    ts.average = emission[s] / ts.area + mean;
    ts.stderr_ = (var / kBatches).cwiseSqrt();
  }
  for (const Batch& b : batches) {
    r.escaped += b.escaped;
    r.rays += b.rays;
    r.capped += b.capped;
  }
  r.escaped = (r.escaped / kBatches).cwiseQuotient(emitted.cwiseMax(1e-300));
  return r;
}

}  // namespace lambert
