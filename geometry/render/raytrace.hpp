#pragma once
// The ray-traced view pass: the radiance a camera ray sees through perfect specular surfaces,
// read from a radiosity solution at diffuse hits (Whitted-style, deterministic branching).
//
// Along a ray, at its closest hit on patch j (front normal n, direction d):
//   mirror (front side):   L = L_d(x) + ρ_s ⊙ L(reflect(d, n))
//   dielectric (either side; rays inside glass meet back faces):
//                          L = L_d(x) [front] + R L(reflected) + (1 − R) T L(refracted),
//                          R the Fresnel reflectance (optics.hpp), T = Tf entering through the
//                          front, 1 leaving; total internal reflection: R = 1
//   diffuse (front side):  L = L_d(x);   back face of a non-dielectric, or a miss: 0
// where the diffuse radiance L_d is
//   field (final_gather = 0):  B(x) / π, B interpolated from the vertex field (Gouraud);
//   final gather (N rays):     (E + ρ (H_d + H_i)) / π, H_d the exact direct irradiance
//                              (direct_light.hpp: every emitting face, exact shadows) and
//                              H_i = (1/N) Σ_k g_k over N cosine-distributed rays (a randomly
//                              shifted rank-1 lattice, stratified for any N; unbiased): g_k is
//                              (B − E) of the patch a ray hits first (its direct part is H_d),
//                              or, after specular bounces (chosen by Fresnel at dielectrics,
//                              weighted ρ_s at mirrors and Tf entering glass), the full B of
//                              the diffuse patch reached (light via mirrors is not in H_d).
// A path follows at most `specular_depth` specular bounces; what lies beyond contributes
// nothing (the diffuse part of the last surface still counts). Radiance in W m^-2 sr^-1 (the
// scene's emission units per steradian).
//
// Cost: a camera ray costs up to 2^D rays through glass (D = specular_depth), 1 + D through
// mirrors; final gather adds N gather rays (each up to D + 1 segments) and one exact direct
// evaluation (CGAL polygon booleans per emitting face, O(faces) box tests) per diffuse hit.
// Thread safety: const queries over const inputs; every random number is drawn from the
// stream the caller passes (a hash of seed, pixel and sample), so results do not depend on
// threads.

#include <Eigen/Core>
#include <cstdint>

#include "geometry/mesh/mesh.hpp"
#include "geometry/render/vertex_field.hpp"
#include "geometry/visibility/bvh.hpp"
#include "geometry/visibility/direct_light.hpp"

namespace lambert {

/// Settings of the view pass.
struct ViewPassSettings {
  int specular_depth = 8;  ///< most specular bounces a path follows (0..64)
  int final_gather = 0;    ///< N gather rays per diffuse hit; 0 reads the vertex field
};

/// Radiance along rays through the scene (see the file comment). Keeps references to its
/// inputs, which must outlive it.
class ViewTracer {
 public:
  /// `patch_B` (N x 3) and `vertices` are the solution; `direct` is needed (and read) only
  /// with final gather.
  ViewTracer(const PatchMesh& mesh, const Bvh& bvh, const Eigen::MatrixX3d& patch_B,
             const VertexField& vertices, const ViewPassSettings& settings,
             const DirectLight* direct = nullptr);

  /// Radiance arriving at `origin` from direction `dir` whose closest hit (found by the
  /// caller) is `hit` (hit.patch >= 0), with the full specular depth. Adds rays traced
  /// here to `rays`.
  Eigen::Vector3d radiance(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                           const RayHit& hit, std::uint64_t stream, std::int64_t& rays) const;

  /// Radiance along a ray from `origin` with at most `bounces` specular bounces left.
  Eigen::Vector3d trace(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, int bounces,
                        std::uint64_t stream, std::int64_t& rays) const;

  /// Final-gather radiosity E + ρ (H_d + H_i) at x on the front of patch i (W/m²).
  Eigen::Vector3d gathered_radiosity(const Eigen::Vector3d& x, std::int32_t i, std::uint64_t stream,
                                     std::int64_t& rays) const;

  /// The N-ray estimate H_i of the indirect irradiance at x on the front of patch i (W/m²).
  Eigen::Vector3d indirect_irradiance(const Eigen::Vector3d& x, std::int32_t i,
                                      std::uint64_t stream, std::int64_t& rays) const;

 private:
  Eigen::Vector3d shade(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                        const RayHit& hit, int bounces, std::uint64_t stream,
                        std::int64_t& rays) const;
  Eigen::Vector3d gather_ray(Eigen::Vector3d origin, Eigen::Vector3d dir, std::uint64_t stream,
                             std::int64_t& rays) const;

  const PatchMesh& mesh_;
  const Bvh& bvh_;
  const Eigen::MatrixX3d& patch_B_;
  const VertexField& vertices_;
  ViewPassSettings settings_;
  const DirectLight* direct_;
  double offset_;  ///< ray origins lifted off their surface (kRayOffset × scene size)
};

}  // namespace lambert
