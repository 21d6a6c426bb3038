#pragma once
// Views of a form-factor matrix: diagnostics, surface-to-surface factors, and factors
// from a differential sensor area.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"

namespace lambert {

/// Conservation checks of F (row sums, reciprocity, range).
struct FormFactorDiagnostics {
  std::int32_t n = 0;
  std::int64_t nnz = 0;
  double row_sum_min = 0.0, row_sum_max = 0.0, row_sum_mean = 0.0;
  std::vector<std::int64_t> row_sum_histogram;  ///< kHistogramBins bins over [0, kHistogramMax)
  std::vector<std::int32_t> worst_rows;         ///< rows with the largest row sums, descending
  double reciprocity_max = 0.0;  ///< max_ij |A_i F_ij - A_j F_ji| (scene units²)
  double reciprocity_max_relative = 0.0;  ///< the same, divided by max(A_i F_ij, A_j F_ji)
  std::int64_t negative = 0;     ///< entries < 0
  std::int64_t above_one = 0;    ///< entries > 1
  static constexpr int kHistogramBins = 22;
  static constexpr double kHistogramMax = 1.1;  ///< row sums above 1 show over-estimation
};

/// Computes the diagnostics; `worst` rows are reported. O(nnz log) time.
FormFactorDiagnostics diagnose(const PatchMesh& mesh, const SparseF& F, int worst = 5);

/// Surface-to-surface factors F_GH = Σ_{i∈G} A_i Σ_{j∈H} F_ij / A_G and standard errors.
struct SurfaceFactors {
  std::vector<std::string> surfaces;
  std::vector<double> areas;
  Eigen::MatrixXd F;       ///< F(g, h) from surface g to surface h
  Eigen::MatrixXd stderr_F;  ///< zero when no per-entry errors were estimated
};

/// Aggregates F (and ff.stderr_F if present: independent entries, variances add).
SurfaceFactors surface_factors(const PatchMesh& mesh, const FormFactors& ff);

/// View factors from a differential area at a point to every surface.
struct PointFactors {
  std::vector<std::string> surfaces;
  std::vector<double> F;
  std::vector<double> stderr_F;
  std::int64_t rays = 0;
};

/// F_{dA -> surface} = Σ_{j∈surface} F_{dA->j}^{unoccluded} · (visible fraction of j), with
/// the exact point-to-patch factor and `samples` visibility rays per patch (Kronecker
/// points on j). stderr from the delta-method variance of the kernel-weighted visible fractions. The normal
/// need not be unit length. Deterministic for a given seed.
PointFactors point_form_factors(const PatchMesh& mesh, const Eigen::Vector3d& point,
                                const Eigen::Vector3d& normal, const FormFactorOptions& options);

}  // namespace lambert
