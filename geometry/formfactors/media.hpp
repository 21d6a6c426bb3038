#pragma once
// Exchange factors with participating media (the zonal method, Rushmeier & Torrance 1987).
//
// Unknowns: the N patches, then one zone per voxel with σt > 0 (M zones). A zone v of volume
// V and grey extinction σt has the effective area A_v = 4 σt V: a zone whose source radiance
// is S (W m⁻² sr⁻¹) emits and out-scatters the power 4π σt V S = A_v (π S), so its
// "radiosity" B_v = π S plays the part of a patch's B = π L and A_i F_ij = A_j F_ji holds
// across patches and zones. F_ij is the fraction of the power leaving unknown i (diffusely
// from a patch's front; isotropically from a zone) that is extinguished in zone j or arrives
// at the front of patch j.
//
// Blocks, each integrated exactly along every ray through the voxels (medium.hpp):
//  - patch → patch: the surface estimator's F_ij times the pair's transmittance T̄_ij, the
//    kernel-weighted mean transmittance ∫∫ K T / ∫∫ K (K = cosθ_x cosθ_y / r², visibility
//    excluded: the estimator accounts for it), estimated from `transmittance_samples`
//    points x uniform on the lower-numbered patch, each with one point y drawn ∝ K on the
//    other (visibility.hpp's KernelSampler) and weighted by x's point factor F(x → j):
//    Σ F(x) T(x, y) / Σ F(x) (a ratio estimator: bias O(var F(x) / S), small since the point
//    factor varies little over a patch). One estimate per unordered pair, so
//    A_i F_ij = A_j F_ji stays exact; for patches small against 1/σt, T̄ ≈ exp(−σt r).
//  - patch → zone: `rays` cosine rays per patch (closest hit through the BVH); along each,
//    zone v receives exp(−τ up to v)(1 − exp(−σt_v ℓ_v)). The part of those rays that end on
//    the front of a patch is rescaled so that the patch's row keeps the estimator's row sum
//    (Σ_j F_ij (1 − T̄_ij) is what the medium takes from the patch-to-patch part); the part
//    of escaping or back-face rays is kept as it is.
//  - zone → patch: by reciprocity from the patch rays, F_zi = A_i F_iz / A_z (one estimate
//    per pair, so A_i F_iz = A_z F_zi holds exactly).
//  - zone → zone: `rays` rays per zone from uniform points in the voxel in uniform
//    directions; deposits as above, including the zone itself. Each zone row is scaled so
//    that the whole row sums to what its rays reached (a zone or the front of a patch: 1 in
//    a closed scene), i.e. to that minus its zone → patch part (clamped at 0), then the
//    block is averaged and balanced (reciprocity.hpp): G = A F symmetric, every row keeping
//    that sum. The patch rows are never rescaled, so the surface estimator's factors (times
//    T̄) and its row sums survive untouched.
// Cost: N·K + M·K rays and DDA walks (a walk crosses O(voxels per axis)), plus
// nnz(F_surface) · transmittance_samples walks. Memory: F plus M zone rows of at most K
// deposits per voxel crossed (≈ K · voxels per axis entries, fewer once merged).
// Deterministic for any thread count: streams hash_keys(seed, row, salt).

#include <cstdint>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/media/medium.hpp"

namespace lambert {

class Bvh;

/// Settings of the medium's exchange factors.
struct MediumFactorOptions {
  int rays = 256;                  ///< rays per patch and per zone (--medium-rays)
  int transmittance_samples = 16;  ///< point pairs per patch pair (--transmittance-samples)
  std::uint64_t seed = 1;
  int threads = 0;  ///< 0 = all cores
};

/// The zones of a medium: voxels with σt > 0.
struct Zones {
  std::vector<std::int32_t> voxel;    ///< voxel of each zone
  std::vector<std::int32_t> zone_of;  ///< zone of each voxel, -1 when σt = 0
  Eigen::VectorXd area;               ///< effective area 4 σt V of each zone (unit²)
  Eigen::MatrixX3d albedo;            ///< σs / σt per zone and channel (its "rho")
  Eigen::MatrixX3d emission;          ///< e / (4 σt) per zone: its emitted "radiosity" E
  std::int32_t size() const { return static_cast<std::int32_t>(voxel.size()); }
};

/// The zones of `medium`.
Zones make_zones(const Medium& medium);

/// Kernel-weighted mean transmittance between patches a and b of `mesh` (see above) with
/// `samples` point pairs from the stream hash_keys(seed ^ salt, min(a,b), max(a,b)); symmetric in
/// (a, b) bit for bit. 1 when every sampled pair has a zero kernel.
double pair_transmittance(const PatchMesh& mesh, const Medium& medium, std::int32_t a,
                          std::int32_t b, int samples, std::uint64_t seed);

/// An estimate of the peak bytes the medium adds to a computation on `patches` patches with
/// `rays` = K rays per unknown: the extended F's zone columns and rows and their staged rows
/// (the patches' block is copied too: the caller adds its size). The K rays of a zone cover
/// every voxel out to the distance r0 = sqrt(K / 4π) voxels (where 4π r² = K), then about K
/// voxels per voxel of distance out to R, the box's longest side in voxels: a zone row holds
/// min(M, 4π r0³ / 3 + K (R − r0)) entries, and a patch row deposits as many (mirrored into
/// the zone rows). Against medium_bench on the Cornell box at K = 256 (entries estimated /
/// measured): 8³ 1.9 M / 1.0 M, 16³ 24 M / 9.2 M, 32³ 267 M / 158 M; bytes 551 MiB / 455 MB
/// RSS at 16³, 6.0 GiB / 6.1 GB at 32³.
double medium_peak_bytes(std::int64_t patches, const Medium& medium, int rays);

/// The extended (N + M)² F from the surfaces' `surface` F (N x N, reciprocal: a pair
/// estimator's or an averaged one) and the medium (see above). The result's stats add the
/// medium's rays; its options are `surface`'s.
FormFactors extend_with_medium(const PatchMesh& mesh, const Medium& medium, const Zones& zones,
                               const FormFactors& surface, const MediumFactorOptions& options,
                               const Bvh& bvh);

}  // namespace lambert
