#pragma once
// Reference form factors for scenes without occlusion (the built-in analytic cases).

#include <cstdint>

#include "geometry/formfactors/formfactors.hpp"

namespace lambert {

/// F_ij for every pair by composite Gauss-Legendre quadrature over patch i of the exact
/// point-to-patch factor to patch j, to ~1e-8 even for patches sharing an edge. Ignores
/// visibility: valid only for scenes in which no patch blocks another (convex enclosures,
/// the analytic cases). Rows in parallel; O(N² x nodes).
FormFactors unoccluded_quadrature(const PatchMesh& mesh, int threads);

/// Centroid distance of patches i and j in units of the larger patch diameter (small:
/// near pairs, where point-sampled estimators such as the hemicube are least accurate).
double proximity(const PatchMesh& mesh, std::int32_t i, std::int32_t j);

}  // namespace lambert
