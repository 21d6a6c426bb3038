#pragma once
// Direct light per pixel: the irradiance that arrives straight from the emitting faces,
//
//   H_d(x) = Σ_e E_e F(x → e) vis_e(x)        (W/m² per channel, E in the scene's units),
//
// estimated at each camera hit with a few shadow rays, so that shadows (contact shadows
// included) are as sharp as the pixels instead of as the mesh. F(x → e) is exact (Lambert's
// contour formula, kernels.hpp); vis_e is the fraction of rays to points of e drawn with
// density ∝ cosθ_x cosθ_y / r² (visibility.hpp's KernelSampler) that reach it, so every ray
// is an unbiased Bernoulli sample of vis_e and a point that sees all of its lights (or
// none) gets H_d exactly: the noise lives in the penumbrae only. With several emitting
// pieces, each ray picks piece e with probability E_e F(x → e) / Σ (luminance-weighted) and
// weighs its visibility by the inverse: still exact where everything is visible.
//
// The image is then E + ρ (H_d(x) + I(x)), with I = F (B − E) the indirect irradiance
// interpolated from the vertices (render_stages.cpp): the patch solution's direct part is
// replaced, not added to.
//
// Emitters are the scene's emitting faces (not the mesh's patches: the Cornell box's light
// is one face of 16 patches and one contour sum), a face of 3 or 4 corners as one piece,
// a convex face of more corners as its fan of triangles. Cost per hit: one contour sum and
// sampler per piece in front of x plus `rays` occlusion queries; at most kMaxPieces pieces
// (a scene with more emitting faces, or a non-convex emitting face, keeps its direct light
// in the vertex field: `usable()` false, with the reason).
//
// Thread safety: const queries are thread-safe; deterministic (a pure function of x and
// the caller's stream key).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/formfactors/kernels.hpp"
#include "geometry/scene.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert {

/// Direct light of a scene's emitting faces at surface points, sampled with shadow rays.
class PixelDirectLight {
 public:
  /// At most this many emitting pieces: the per-hit cost is one contour sum and sampler per
  /// piece in front of the point (about 0.3 µs each), so 64 pieces cost what ~10 rays do.
  static constexpr int kMaxPieces = 64;

  /// Prepares the emitting faces of `scene` (O(faces)); `rays` shadow rays per query;
  /// ray ends are lifted by `offset` (scene units) along their normals.
  PixelDirectLight(const Scene& scene, int rays, double offset);
  /// False when the scene's emitters cannot be sampled here (`why` says why).
  bool usable() const { return why_.empty(); }
  /// Why not usable (empty when usable).
  const std::string& why() const { return why_; }
  /// Number of emitting pieces.
  int pieces() const { return static_cast<int>(pieces_.size()); }
  /// Shadow rays per query.
  int rays() const { return rays_; }
  /// The estimate of H_d(x) (RGB, W/m²) at x with unit front normal n from points
  /// first .. first + rays - 1 of the low-discrepancy sequence keyed by `stream` (the samples
  /// of one pixel share a stream and take consecutive runs: the pixel's rays are stratified
  /// over the lights together); `cast` counts the rays traced.
  Eigen::Vector3d irradiance(const Bvh& bvh, const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                             std::uint64_t stream, std::int64_t first, std::int64_t& cast) const;

 private:
  std::vector<ff::PatchGeom> pieces_;
  std::vector<Eigen::Vector3d> emission_;
  int rays_ = 0;
  double offset_ = 0.0;
  std::string why_;
};

}  // namespace lambert
