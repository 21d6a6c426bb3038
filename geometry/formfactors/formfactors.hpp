#pragma once
// Form-factor estimation: the registry of estimators and the shared result type.
//
// F_ij = (1/A_i) ∫_{A_i} ∫_{A_j} V(x,y) cosθ_x cosθ_y / (π r²) dA_y dA_x  (dimensionless),
// the fraction of the power leaving patch i (front side, diffusely) that arrives at patch j.

#include <Eigen/SparseCore>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/sparse.hpp"
#include "geometry/mesh.hpp"

namespace lambert {

/// Row-major sparse form-factor matrix: row i holds F_ij for every j patch i sees.
using SparseF = SparseRowMatrix;

/// Settings of one form-factor computation.
struct FormFactorOptions {
  std::string estimator = "hybrid";  ///< a name from form_factor_estimators()
  int samples = 32;                  ///< sample pairs (rays) per patch pair
  std::uint64_t seed = 1;
  int threads = 0;                   ///< 0 = all cores
  double threshold = 0.0;            ///< drop entries with F_ij < threshold (after estimation)
  bool with_stderr = false;          ///< also estimate the standard error of each entry
  int hemicube_resolution = 128;     ///< hemicube top-face resolution (estimator "hemicube")
  bool symmetrize = false;           ///< average A_i F_ij and A_j F_ji (non-reciprocal estimators)
  bool progress = true;              ///< draw a progress bar (when stderr is a terminal)
};

/// What a computation did (for diagnostics and reports).
struct FormFactorStats {
  std::int64_t pairs_tested = 0;  ///< unordered pairs that can exchange energy
  std::int64_t pairs_culled = 0;  ///< unordered pairs facing away from each other
  std::int64_t rays = 0;          ///< occlusion rays traced
  /// Pairs whose visibility could not be sampled as designed (hybrid: no ray could be
  /// traced, so the unoccluded value was kept; or a kernel-sampling rejection gave up):
  /// reported and warned about, expected 0.
  std::int64_t pairs_unverified = 0;
  double seconds = 0.0;           ///< wall time of the computation
};

/// The estimated matrix, optionally with per-entry standard errors (same sparsity).
/// Moves are cheap: Eigen 3.4's SparseMatrix has no move constructor (std::move copies it),
/// so FormFactors moves its matrices by swapping.
struct FormFactors {
  SparseF F;
  SparseF stderr_F;  ///< empty (0 x 0) unless with_stderr
  FormFactorStats stats;
  FormFactorOptions options;  ///< the settings that produced F

  FormFactors() = default;
  FormFactors(const FormFactors&) = default;
  FormFactors& operator=(const FormFactors&) = default;
  FormFactors(FormFactors&& other) noexcept { *this = std::move(other); }
  FormFactors& operator=(FormFactors&& other) noexcept {
    F.swap(other.F);
    stderr_F.swap(other.stderr_F);
    stats = other.stats;
    options = std::move(other.options);
    return *this;
  }
};

/// Names of the available estimators ("mc", "hybrid", ...).
std::vector<std::string> form_factor_estimators();

/// Upper bound (bytes) on the memory compute_form_factors needs for `patches` patches with
/// these options, before any work: the all-pairs estimators from the N(N-1)/2 pair bound, the
/// hemicube from at most one entry per pixel per row. --threshold prunes only after the
/// estimate, so it does not lower the peak. Throws UsageError for an unknown estimator.
double form_factor_peak_bytes(std::int64_t patches, const FormFactorOptions& options);

class Bvh;

/// Computes F for every patch pair of `mesh` with the chosen estimator. Multi-threaded;
/// for a given seed the result is bitwise identical for any thread count. `bvh` (built over
/// `mesh`) is used for the visibility rays when given, so that one BVH serves a whole run;
/// otherwise one is built. Throws UsageError for an unknown estimator or invalid settings.
FormFactors compute_form_factors(const PatchMesh& mesh, const FormFactorOptions& options,
                                 const Bvh* bvh = nullptr);

}  // namespace lambert
