#pragma once
// Daylight on patches and points (geometry/scene.hpp: Daylight):
//
//   sky:  H_sky,i = π L_sky s_i,  s_i = 1 − Σ_j F_ij (+ what mirrors carry on, counted again)
//         the patch's escape fraction: the cosine-weighted share of its hemisphere that sees
//         no patch (for a patch under an open sky s_i = 1 and H = π L: a white floor under a
//         uniform sky has B = π L, radiance L, as bright as the sky);
//   sun:  H_sun(x) = S max(0, n·ℓ) V(x, ℓ),  ℓ = −sun_direction, V = 1 when the ray from x
//         towards the sun escapes. At a point that is one ray, exact; a patch's mean
//         H_sun,i averages V over k × k stratified points (jittered, k = kSunSide), so
//         its error is at most the share of the k² cells the shadow's edge crosses
//         (≈ 2 k⁻¹ per edge across the patch, a few % on a half-shadowed patch, none on a
//         fully lit or fully shadowed one).
//
// Both are first-bounce sources: B_i = E_i + ρ_i (H_sky,i + H_sun,i + Σ_j F_ij B_j).
// Deterministic: each patch's points come from (seed, patch), whatever the thread count.

#include <Eigen/Core>
#include <cstdint>

#include "core/sparse.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/scene.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert {

/// Shadow rays start this far (× the scene's size) off their surface, as the estimators'.
constexpr double kSunRayOffset = 1e-6;

/// Sample points per side of a patch for its mean sun irradiance (k² shadow rays).
constexpr int kSunSide = 16;

/// The escape fraction s_i = clamp(1 − (Σ_j F_ij − continued_i), 0, 1) of each of the
/// first `patches` rows of F (`continued` empty or one entry per row: the part of the row
/// sum carried on by mirrors and counted again further on).
Eigen::VectorXd escape_fractions(const SparseRowMatrix& F, const Eigen::VectorXd& continued,
                                 std::int32_t patches);

/// The sun's irradiance (W/m² per channel) at x on a surface with unit front normal
/// `normal`: one shadow ray from x (lifted by `offset` along the normal) towards the sun.
Eigen::Vector3d sun_irradiance_at(const Bvh& bvh, const Daylight& light, const Eigen::Vector3d& x,
                                  const Eigen::Vector3d& normal, double offset);

/// Each patch's mean sun irradiance (N x 3, W/m²), kSunSide² shadow rays per lit patch.
Eigen::MatrixX3d sun_patch_irradiance(const PatchMesh& mesh, const Bvh& bvh, const Daylight& light,
                                      std::uint64_t seed, int threads = 0);

}  // namespace lambert
