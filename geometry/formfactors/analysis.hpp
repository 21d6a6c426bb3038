#pragma once
// Views of a form-factor matrix: diagnostics, surface-to-surface factors, and factors
// from a differential sensor area.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/formfactors/media.hpp"

namespace lambert {

/// Conservation checks of F (row sums, reciprocity, range).
struct FormFactorDiagnostics {
  std::int32_t n = 0;
  std::int64_t nnz = 0;
  double row_sum_min = 0.0, row_sum_max = 0.0, row_sum_mean = 0.0;
  std::vector<std::int64_t> row_sum_histogram;  ///< kHistogramBins bins over [0, kHistogramMax)
  std::vector<std::int32_t> worst_rows;         ///< rows with the largest row sums, descending
  double reciprocity_max = 0.0;                 ///< max_ij |A_i F_ij - A_j F_ji| (scene units²)
  double reciprocity_max_relative = 0.0;        ///< the same, divided by max(A_i F_ij, A_j F_ji)
  std::int64_t negative = 0;                    ///< entries < 0
  std::int64_t above_one = 0;                   ///< entries > 1
  static constexpr int kHistogramBins = 22;
  static constexpr double kHistogramMax = 1.1;  ///< row sums above 1 show over-estimation
};

/// Computes the diagnostics; `worst` rows are reported. O(nnz log) time, rows on `threads`
/// (the same result for any count).
FormFactorDiagnostics diagnose(const PatchMesh& mesh, const SparseF& F, int worst = 5,
                               int threads = 1);

/// Why a scene would silently come out as B = E (or all zero), found from the mesh's
/// emission and F alone, so it holds for any estimator and for an F loaded from a file.
struct LightingProblems {
  bool no_emitter = false;       ///< no patch has E > 0 in any channel
  bool nothing_visible = false;  ///< at least 2 patches and no positive entry in F
  std::int64_t pairs = 0;        ///< unordered patch pairs, N (N - 1) / 2
  /// Emitting surfaces none of whose patches has a positive entry in its row of F (a tiny
  /// but nonzero row sum is not listed); empty when nothing_visible, which explains them.
  std::vector<std::int32_t> blind_emitters;
  /// True when any problem was found.
  bool any() const { return no_emitter || nothing_visible || !blind_emitters.empty(); }
};

/// Finds the problems above. O(N + nnz) time; F must be N x N for the mesh's N patches.
LightingProblems find_lighting_problems(const PatchMesh& mesh, const SparseF& F);

/// One line per problem found (without a "warning: " prefix), naming the surfaces involved
/// and the likely cause.
std::vector<std::string> lighting_warnings(const PatchMesh& mesh, const LightingProblems& p);

/// A closed set of lossless patches: every patch of it has reflectance 1 in the channel(s)
/// and sends all the light it emits or reflects to patches of the set (none escapes, none
/// reaches a patch that absorbs), within F's error. (I - rho F) is then singular.
struct ClosedLossless {
  std::vector<int> channels;           ///< 0 R, 1 G, 2 B: those with exactly this set
  std::vector<std::int32_t> patches;   ///< the set, ascending
  std::vector<std::int32_t> surfaces;  ///< their surfaces, ascending
  double max_leak = 0.0;               ///< largest fraction of a row of F leaving the set
};

/// Every closed lossless set (one per distinct set; a channel has at most one, the largest).
/// F's error per row: kClosedRowTolerance plus kClosedSigmas row standard errors when
/// `ff.stderr_F` is present. O(N + nnz) time.
std::vector<ClosedLossless> find_closed_lossless(const PatchMesh& mesh, const FormFactors& ff);

/// Row leak below which F cannot tell a closed set from a leaking one, without stderr: the
/// hybrid estimator's quadrature bound (docs/form-factors.md: 1e-6 of the unoccluded G per entry,
/// so at most 1e-6 of a row sum <= 1); rounding of the row sums (~N 1e-16) is far below it.
constexpr double kClosedRowTolerance = 1e-6;
/// Row standard errors added to it when F has them: docs/form-factors.md's stderr covers an entry's
/// error within +-2 stderr at 97 %; a set of many rows must have none misjudged, and a
/// normal tail beyond 5 sigma (3e-7 per row) keeps that probable up to ~1e5 rows.
constexpr double kClosedSigmas = 5.0;

/// One line naming the surfaces and channels of a closed lossless set and the cure.
std::string closed_lossless_message(const PatchMesh& mesh, const ClosedLossless& c);

/// Surface-to-surface factors F_GH = Σ_{i∈G} A_i Σ_{j∈H} F_ij / A_G and standard errors.
struct SurfaceFactors {
  std::vector<std::string> surfaces;
  std::vector<double> areas;
  Eigen::MatrixXd F;         ///< F(g, h) from surface g to surface h
  Eigen::MatrixXd stderr_F;  ///< zero when no per-entry errors were estimated
  bool has_stderr = false;   ///< F came with per-entry standard errors
};

/// The name of the participating medium's group in surface_factors.
inline constexpr const char* kMediumGroup = "(medium)";

/// Aggregates F (and ff.stderr_F if present: independent entries, variances add). With
/// `zone_area` (a medium's zones appended to F after the patches, their effective areas
/// 4 σt V), the zones form one more group, kMediumGroup, of area Σ 4 σt V: A_G F_G,medium
/// and A_medium F_medium,H are the zonal method's direct exchange areas (gs, sg, gg).
SurfaceFactors surface_factors(const PatchMesh& mesh, const FormFactors& ff,
                               const Eigen::VectorXd* zone_area = nullptr);

/// Independent replicates of the medium's factors in medium_surface_factors.
inline constexpr int kMediumReplicates = 8;

/// surface_factors of `extended` (the surfaces' F `surface` extended by the medium's zones
/// with options o: extend_with_medium), with standard errors. The medium's part comes from
/// its estimate repeated with o's rays and transmittance samples split into kMediumReplicates
/// independent replicates (streams hash_keys(o.seed, salt, r)): the variance of their mean
/// (replicates.hpp), which has the samples of the one estimate, stands for that estimate's;
/// the entries within a replicate stay correlated as they are (a ray deposits in many zones,
/// a row's medium share is what its attenuation removes). The table itself is the one
/// estimate's: the replicates' few transmittance samples per pair bias a ratio estimator
/// (O(1/samples)), which shifts their mean but not their spread. Where `surface` carries
/// per-entry errors their aggregate is added: in full to the surfaces' entries (a bound:
/// attenuation only shrinks them) and, summed over the surfaces, to the medium's row and
/// column (the medium takes what attenuation removes).
SurfaceFactors medium_surface_factors(const PatchMesh& mesh, const FormFactors& surface,
                                      const FormFactors& extended, const Medium& medium,
                                      const Zones& zones, const MediumFactorOptions& o,
                                      const Bvh& bvh);

/// View factors from a differential area at a point to every surface.
struct PointFactors {
  std::vector<std::string> surfaces;
  std::vector<double> F;
  std::vector<double> stderr_F;
  std::int64_t rays = 0;
};

/// F_{dA -> surface} = Σ_{j∈surface} F_{dA->j}^{unoccluded} · (visible fraction of j), with
/// the exact point-to-patch factor and `samples` visibility rays per patch to points drawn
/// with the kernel's density (visibility.hpp, the kernel hybrid uses). stderr from
/// replicates (replicates.hpp). The normal need not be unit length. Deterministic for a
/// given seed.
PointFactors point_form_factors(const PatchMesh& mesh, const Eigen::Vector3d& point,
                                const Eigen::Vector3d& normal, const FormFactorOptions& options);

}  // namespace lambert
