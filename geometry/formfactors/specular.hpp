#pragma once
// Extended form factors (Wallace, Cohen & Greenberg 1987; Sillion & Puech 1989): the part
// of F_ij carried by paths with at least one perfect specular bounce.
//
// F_ij^ext is the fraction of the (diffuse) power leaving patch i that arrives at the front
// of patch j directly or after specular bounces, each bounce weighting the path by what it
// carries on: a mirror its reflectance ρ_s; a dielectric the Fresnel reflectance R when it
// reflects, (1 − R) Tf when light refracts in through the front and (1 − R) when it leaves
// through the back. Arrival counts in full at every front hit (a mirror that is also
// diffuse reflects ρ_d of what arrives and carries ρ_s of it on), so rows may sum past 1;
// `continued` keeps the bookkeeping: Σ_j F_ij − continued_i is the fraction of i's power
// that ends (absorbed or diffusely reflected) somewhere, 1 minus it escapes or is cut off
// by the depth limit.
//
// Reciprocity: a specular path is reversible (mirror reflection and Snell refraction
// between two points in the same medium, the Fresnel R and the products of the weights are
// the same both ways, and the étendue n² dA cosθ dω is conserved through each bounce), so
// A_i F_ij^S = A_j F_ji^S. The estimate is made from both ends (each row shoots its own
// rays) and averaged, G = (A_i S_ij + A_j S_ji) / 2, so the result is reciprocal to rounding.
//
// Estimate: row i, K = specular_rays cosine-distributed rays from stratified points (the
// gather estimator's randomised Kronecker lattice with replicates, replicates.hpp). A ray
// that hits a specular face continues (mirror: reflection; dielectric: reflection with
// probability R, else refraction, its expected weight exact), up to specular_depth bounces;
// every front hit after the first bounce adds (J / A_i) · w / K to S_ij (w the product of
// the bounces' weights). The direct (zero-bounce) part is the matrix estimator's own.
// The weights are one number for all three channels: specular reflectance and transmission
// must be grey (check_grey_specular).
//
// Cost O(N · K · bounces) rays, parallel over rows; memory K hits per thread and the
// entries of S. Deterministic for any thread count (streams hash_keys(seed, i, replicate)).

#include <Eigen/Core>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert::ff {

/// The specular part of the extended form factors.
struct SpecularTransport {
  SparseF S;         ///< reciprocal (averaged), paths with >= 1 specular bounce
  SparseF stderr_S;  ///< empty unless options.run.with_stderr
  /// Per row: the expected weight carried on past every front arrival counted in F (direct
  /// arrivals at specular faces included).
  Eigen::VectorXd continued;
  std::int64_t rays = 0;  ///< ray segments traced
};

/// Refuses (SceneError) specular surfaces whose reflectance or transmission differs between
/// channels: extended form factors carry one weight for all three.
void check_grey_specular(const PatchMesh& mesh);

/// The specular part of F for `mesh` (which has specular surfaces) with `options`'
/// specular block and its run settings (seed, threads, with_stderr, progress). `average` false
/// keeps each row's own estimate S_ij (not reciprocal to rounding; for tests of the reversibility
/// the averaging relies on).
SpecularTransport compute_specular_transport(const PatchMesh& mesh,
                                             const FormFactorOptions& options, const Bvh& bvh,
                                             bool average = true);

/// Adds the specular part to a matrix estimate in place: F += S, standard errors combined
/// as independent (sqrt of the sum of squares), `continued` and the rays recorded.
void add_specular_transport(const PatchMesh& mesh, const FormFactorOptions& options,
                            const Bvh& bvh, FormFactors& out);

}  // namespace lambert::ff
