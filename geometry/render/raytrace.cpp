#include "geometry/render/raytrace.hpp"

#include <cmath>

#include "core/error.hpp"
#include "core/sampling.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/optics.hpp"

namespace lambert {
namespace {

constexpr std::uint64_t kGatherKey = 0x676174686572ull;  // "gather"

// The stream of branch k (1 reflected, 2 refracted) of a path node's stream.
std::uint64_t branch(std::uint64_t stream, std::uint64_t k) { return mix64(stream ^ (k << 56)); }

}  // namespace

ViewTracer::ViewTracer(const PatchMesh& mesh, const Bvh& bvh, const Eigen::MatrixX3d& patch_B,
                       const VertexField& vertices, const ViewPassSettings& settings,
                       const DirectLight* direct)
    : mesh_(mesh),
      bvh_(bvh),
      patch_B_(patch_B),
      vertices_(vertices),
      settings_(settings),
      direct_(direct),
      offset_(ff::kRayOffset * mesh.scale) {
  LAMBERT_CHECK(patch_B.rows() == mesh.size(), "view pass: radiosity size does not match");
  LAMBERT_CHECK(settings.specular_depth >= 0 && settings.final_gather >= 0,
                "view pass: negative depth or gather count");
  LAMBERT_CHECK(settings.final_gather == 0 || direct, "final gather without direct light");
  LAMBERT_CHECK(
      settings.final_gather > 0 || (vertices.patch_corners.size() == mesh.patches.size() &&
                                    vertices.values.rows() == vertices.size()),
      "view pass: vertex field does not match the mesh");
}

Eigen::Vector3d ViewTracer::radiance(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                     const RayHit& hit, std::uint64_t stream,
                                     std::int64_t& rays) const {
  return shade(origin, dir, hit, settings_.specular_depth, stream, rays);
}

Eigen::Vector3d ViewTracer::trace(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                  int bounces, std::uint64_t stream, std::int64_t& rays) const {
  ++rays;
  const RayHit h = bvh_.intersect(origin.cast<float>(), dir.cast<float>());
  if (h.patch < 0) return Eigen::Vector3d::Zero();
  return shade(origin, dir, h, bounces, stream, rays);
}

Eigen::Vector3d ViewTracer::shade(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                  const RayHit& hit, int bounces, std::uint64_t stream,
                                  std::int64_t& rays) const {
  const std::int32_t j = hit.patch;
  const Patch& p = mesh_.patches[j];
  const Eigen::Vector3d x = origin + hit.t * dir;
  const bool front = p.normal.dot(dir) < 0;
  Eigen::Vector3d L = Eigen::Vector3d::Zero();
  if (front) {
    L = settings_.final_gather > 0 ? Eigen::Vector3d(gathered_radiosity(x, j, stream, rays))
                                   : field_value(mesh_, vertices_, j, x);
    L *= 1.0 / M_PI;
  }
  const Specular* spec = mesh_.specular_of(j);
  if (!spec || bounces == 0) return L;
  const Eigen::Vector3d d = dir.normalized();
  if (spec->dielectric) {
    const Interface in = dielectric_interface(d, p.normal, spec->ior);
    if (in.reflectance > 0.0)
      L += in.reflectance * trace(x + offset_ * in.normal, reflect(d, in.normal), bounces - 1,
                                  branch(stream, 1), rays);
    Eigen::Vector3d t;
    if (in.reflectance < 1.0 && refract(d, in.normal, in.eta, t)) {
      Eigen::Vector3d w = Eigen::Vector3d::Constant(1.0 - in.reflectance);
      if (in.entering) w = w.cwiseProduct(spec->transmission);
      L += w.cwiseProduct(trace(x - offset_ * in.normal, t, bounces - 1, branch(stream, 2), rays));
    }
  } else if (front) {
    L += spec->reflectance.cwiseProduct(
        trace(x + offset_ * p.normal, reflect(d, p.normal), bounces - 1, branch(stream, 1), rays));
  }
  return L;
}

Eigen::Vector3d ViewTracer::gathered_radiosity(const Eigen::Vector3d& x, std::int32_t i,
                                               std::uint64_t stream, std::int64_t& rays) const {
  const Patch& p = mesh_.patches[i];
  Eigen::Vector3d B = p.emission;
  if (!(p.rho.maxCoeff() > 0.0)) return B;
  // Onto the patch's plane: a ray hit is rounded off it by ~1e-7 of the scene's size, and
  // the exact direct light skips the faces whose plane holds the point within 1e-12 only.
  const Eigen::Vector3d xp = x - p.normal * p.normal.dot(x - p.centroid);
  const Eigen::Vector3d H =
      direct_->irradiance(xp, p.normal) + indirect_irradiance(xp, i, stream, rays);
  return B + p.rho.cwiseProduct(H);
}

Eigen::Vector3d ViewTracer::indirect_irradiance(const Eigen::Vector3d& x, std::int32_t i,
                                                std::uint64_t stream, std::int64_t& rays) const {
  const int N = settings_.final_gather;
  const Eigen::Vector3d& n = mesh_.patches[i].normal;
  Eigen::Vector3d t, b;
  ff::orthonormal_frame(n, t, b);
  const Kronecker4 lattice(hash_keys(stream, kGatherKey));
  const Eigen::Vector3d origin = x + offset_ * n;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int s = 0; s < N; ++s) {
    // Cosine-distributed (pdf cos θ / π): H_i = ∫ L cos θ dω ≈ (π / N) Σ L_k = (1/N) Σ B_k.
    const Eigen::Vector3d dir = ff::cosine_direction(n, t, b, lattice.get(s, 0), lattice.get(s, 1));
    sum += gather_ray(origin, dir, hash_keys(stream, kGatherKey, s), rays);
  }
  return sum / N;
}

Eigen::Vector3d ViewTracer::gather_ray(Eigen::Vector3d origin, Eigen::Vector3d dir,
                                       std::uint64_t stream, std::int64_t& rays) const {
  Rng rng(stream);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d w = Eigen::Vector3d::Ones();
  for (int bounce = 0;; ++bounce) {
    ++rays;
    const RayHit h = bvh_.intersect(origin.cast<float>(), dir.cast<float>());
    if (h.patch < 0) return sum;
    const Patch& p = mesh_.patches[h.patch];
    const bool front = p.normal.dot(dir) < 0;
    if (front) {
      // First hit: B − E (its direct part is H_d); after a specular bounce: all of B.
      Eigen::Vector3d B = patch_B_.row(h.patch).transpose();
      if (bounce == 0) B -= p.emission;
      sum += w.cwiseProduct(B);
    }
    const Specular* spec = mesh_.specular_of(h.patch);
    if (!spec || bounce == settings_.specular_depth) return sum;
    const Eigen::Vector3d x = origin + h.t * dir;
    dir.normalize();
    if (spec->dielectric) {
      // One branch, chosen with the probability of its Fresnel weight (unbiased).
      const Interface in = dielectric_interface(dir, p.normal, spec->ior);
      Eigen::Vector3d refracted;
      if (rng.uniform() < in.reflectance || !refract(dir, in.normal, in.eta, refracted)) {
        dir = reflect(dir, in.normal);
        origin = x + offset_ * in.normal;
      } else {
        dir = refracted;
        origin = x - offset_ * in.normal;
        if (in.entering) w = w.cwiseProduct(spec->transmission);
      }
    } else if (front) {
      w = w.cwiseProduct(spec->reflectance);
      dir = reflect(dir, p.normal);
      origin = x + offset_ * p.normal;
    } else {
      return sum;
    }
    if (!(w.maxCoeff() > 0.0)) return sum;
  }
}

}  // namespace lambert
