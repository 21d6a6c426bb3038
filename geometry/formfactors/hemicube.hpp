#pragma once
// Estimator "hemicube" (internal to geometry/, exposed for its tests and benchmark).
//
// Cohen & Greenberg (1985): F_ij is approximated by the point-to-area factor from the
// centre of patch i, F_{c_i -> j} = Σ_{pixels p showing j} ΔF_p, where every other patch is
// projected onto the five faces of a unit hemicube over c_i (top face z = 1, |x|,|y| <= 1;
// four half side faces) and z-buffered, and ΔF_p is the pixel's delta form factor:
//   top face  (x, y, 1):  ΔF = ΔA / (π (x² + y² + 1)²)
//   side face (1, y, z):  ΔF = z ΔA / (π (y² + z² + 1)²)   (and the three rotations of it).
// Not reciprocal: A_i F_ij ≠ A_j F_ji in general; `--reciprocity average` (alias
// `--symmetrize`, applied by compute_form_factors: reciprocity.hpp) replaces both by their
// mean. Known errors: aliasing (a patch covers a whole number of pixels, so
// small or distant patches are over- or under-counted, an error that falls as the pixel
// size 2/N), and the proximity error (the factor is taken from one point, c_i, not averaged
// over patch i; large for neighbours closer than a few patch diameters, independent of N).

#include <cstdint>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"

namespace lambert::ff {

/// The delta form factors of one hemicube resolution (computed once, shared by all rows).
struct HemicubeDeltas {
  int n = 0;                 ///< top face n x n pixels; side faces n columns
  int m = 0;                 ///< side-face rows: ceil(n / 2), height 1 / m each
  std::vector<double> top;   ///< n x n, row-major; pixel (r, c) at x = -1 + (c+½)·2/n, y likewise
  std::vector<double> side;  ///< m x n, row-major; pixel (r, c) at y = -1 + (c+½)·2/n, z = (r+½)/m
  /// Σ ΔF over the whole hemicube (the top face once, each side face four times); → 1.
  double total() const;
};

/// Midpoint-rule delta form factors for top-face resolution `resolution` (>= 2).
HemicubeDeltas hemicube_deltas(int resolution);

/// What a hemicube run did beyond FormFactorStats.
struct HemicubeStats {
  std::int64_t pixels = 0;  ///< pixel depth tests made while rasterising (all rows)
};

/// Estimator "hemicube": every row of F from one hemicube at the patch's centroid, lifted
/// off the patch by a tiny offset and turned about the normal by an angle hashed from
/// (options.run.seed, row) so that its aliasing is not aligned with the scene's edges. Rows
/// are independent and run in parallel (per-thread buffers), so F is bitwise identical for
/// any thread count. Reciprocity averaging is the caller's (compute_form_factors).
/// Cost O(N_patches² + N_patches · resolution²); stats.rays = 0.
FormFactors compute_hemicube(const PatchMesh& mesh, const FormFactorOptions& options,
                             HemicubeStats* hemicube_stats = nullptr);

}  // namespace lambert::ff
