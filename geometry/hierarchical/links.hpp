#pragma once
// Links of the hierarchical method and the refinement oracle (internal to geometry/).
//
// A link p <- q carries F_pq, the area-averaged factor with H_p += F_pq B_q (H the irradiance,
// W/m^2), and err_pq, a bound on the power error of the transfer per unit source radiosity
// (scene units^2): the transfer A_p F_pq B_q is wrong by at most err_pq B_q. The oracle
// refines a link while its power error exceeds threshold (epsilon x emitted power): for an
// element source err_pq B_q + A_p F_pq ΔB_q, the second term the error of transferring q's
// area average where q's leaves differ by ΔB_q (max - min, max over channels); for a cluster
// at either end err_pq max B_q (the bound times the brightest leaf below q).
//
// Element - element (both planar polygons): F_pq = F0 vis, F0 the unoccluded mean factor
// (1/A_p) ∫_p F(x -> q) dA, F(x -> q) the exact contour formula, integrated by the 2 x 2
// Gauss rule over p when q is farther than p's diameter, else by the adaptive quadrature of
// quadrature.hpp; vis the visible fraction at p's Gauss points (weighted by w F(x -> q))
// from link_rays / 4 kernel-sampled rays each (the hybrid estimator's kernel,
// visibility.hpp). The factor varies over p: the link carries it at p's corners
// (c_k = F(corner_k -> q), scaled to mean F), so a receiver gathers a linear (bilinear)
// irradiance, not a constant, and pushes it to its children by interpolation. Error per
// unit B_q:
//   err = A_p (dev vis + F0 u),  dev = max |F(x -> q) - interpolant(x)| over p's corners,
//   Gauss points and centre, u = 1 where rays disagree (a shadow boundary crosses the link),
//   else 1 / (rays + 1) (the chance-level uncertainty of a fraction all rays agree on).
// A pair that cannot exchange (each behind the other's plane, can_exchange) is dropped.
//
// With a cluster at either end: the transfer T = A_p F_pq = (1/π) ∫_p ∫_q cos+ cos+ V / r^2
// is bounded by T_max = min(A_p A_q / (π d^2), A_p, A_q), d the distance between the two
// bounding boxes (cosines <= 1; F_pq <= 1 and F_qp <= 1 by reciprocity) — isotropic, and
// conservative for any orientation, which is why the root cluster can link to itself. err =
// T_max. An accepted cluster link is estimated by Monte Carlo: link_rays pairs (x, y)
// uniform in area below p and q, T ≈ A_p A_q mean(cos+_x cos+_y V / (π r^2)), capped at
// T_max. A cluster receiver hands what it gathers to the faces below it by orientation:
// the samples record which way the receiving faces turned (Link::bins).
// Pairs with an element whose plane has the other end's box entirely behind it are dropped.
//
// Refinement splits the larger end that can be split (clusters: by box diagonal, elements:
// by area; an element can be split while area >= 4 min_area); a self-link of a cluster
// becomes the links between all pairs of its children (and their self-links); an element's
// self-link is dropped (a planar element does not see itself).
//
// Evaluation is a pure function of (hierarchy, p, q, seed): thread-safe and deterministic.

#include <cstdint>

#include "geometry/hierarchical/hierarchy.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert::hr {

/// One link p <- q (68 bytes).
struct Link {
  std::int32_t p = 0;  ///< receiver node
  std::int32_t q = 0;  ///< source node
  float F = 0.0f;      ///< mean factor: H_p += F B_q on average over p
  float err = 0.0f;    ///< power error bound per unit source radiosity (scene units^2)
  /// The factor at p's corners (an element receiver; all F for a cluster): the irradiance
  /// the link delivers is interpolated from corner values c_k B_q (linear on triangles,
  /// bilinear on quads) with mean F (sum_k mu_k c_k = F, corner_masses).
  float c[4] = {0, 0, 0, 0};
  /// Where the link reads q's radiosity: the kernel centroid on q minus q's centroid (scene
  /// units; 0 for cluster links). The transfer uses B_q + grad B_q · d, q's linear fit,
  /// which removes the first-order error of transferring q's average.
  float d[3] = {0, 0, 0};
  /// A cluster receiver: the shares of the transfer that arrived on faces turned towards
  /// +x, -x, +y, -y, +z, -z (n_a^2 of each Monte Carlo sample's receiving normal, to the
  /// bin of n_a's sign); the push hands each share to the faces in that bin by their
  /// projected area (Node::facing).
  float bins[6] = {0, 0, 0, 0, 0, 0};
};

/// What to do with a link.
enum class Action : std::uint8_t { Drop, Accept, SplitReceiver, SplitSource, SplitBoth };

/// What the oracle sees.
struct LinkContext {
  const Hierarchy& h;
  const Bvh& bvh;
  int rays = 16;            ///< visibility rays per element link, MC pairs per cluster link
  std::uint64_t seed = 1;
  double offset = 0.0;      ///< ray ends are lifted this far off their surfaces
  double plane_eps = 0.0;   ///< plane tolerance of culling tests (scene units)
  double min_area = 0.0;    ///< elements are split while area >= 4 min_area
  double threshold = 0.0;   ///< power error allowed per link (W)
};

/// What the oracle knows of a source's radiosity (max over channels): its area average, the
/// spread (max - min) of its leaves' B, and their maximum.
struct SourceB {
  double mean = 0.0, spread = 0.0, high = 0.0;
};

/// True when node i may be split (clusters always; elements while area >= 4 min_area).
bool splittable(const LinkContext& ctx, std::int32_t i);

/// The oracle's verdict on a new link p <- q with source radiosity b_q: its F and err
/// (Accept), or how to split it. Adds the rays it traced.
Action evaluate_link(const LinkContext& ctx, std::int32_t p, std::int32_t q, const SourceB& b_q,
                     Link& link, std::int64_t& rays);

/// The power error (W) of an evaluated link's transfer with source radiosity b_q, the
/// quantity the oracle compares with the threshold.
double link_error(const LinkContext& ctx, const Link& link, const SourceB& b_q);

/// The verdict on an evaluated link against a new source radiosity b_q: Accept, or which end
/// to split (split_choice).
Action recheck_link(const LinkContext& ctx, const Link& link, const SourceB& b_q);

}  // namespace lambert::hr
