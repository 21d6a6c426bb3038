#include "geometry/hierarchical/links.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/quadrature.hpp"
#include "geometry/formfactors/visibility.hpp"

namespace lambert::hr {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// A link's corner values are taken this fraction of the way from the corner to the centroid:
/// far above the ray offset (1e-6 of the scene) for any element lambert builds (>= 1e-5 of
/// the scene's area, so >= ~3e-3 of its size), and close enough to the corner to stand for it.
constexpr double kCornerInset = 1e-2;

/// Where corner k's value is taken: just inside the corner. A corner on an edge shared with
/// the source lies in the source's plane, where the contour formula counts it as behind the
/// source (0, not the limit 1/2 from inside), and a corner on an edge shared with any face,
/// lifted along its normal, lies in that face's plane, where rays graze it and count as
/// blocked: either would zero the irradiance a link spreads to that corner.
Eigen::Vector3d corner_point(const ff::PatchGeom& g, int k) {
  return g.p[k] + kCornerInset * (g.centroid - g.p[k]);
}

std::uint64_t link_key(std::int32_t p, std::int32_t q) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(p)) << 32) |
         static_cast<std::uint32_t>(q);
}

// True when every corner of `box` lies behind (or on) the plane of element g.
bool box_behind(const ff::PatchGeom& g, const Eigen::AlignedBox3d& box, double eps) {
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    if (g.normal.dot(corner - g.p[0]) > eps) return false;
  }
  return true;
}

// Which end to split, or Accept when neither can be.
Action split_choice(const LinkContext& ctx, std::int32_t p, std::int32_t q) {
  const bool sp = splittable(ctx, p), sq = splittable(ctx, q);
  if (!sp && !sq) return Action::Accept;
  if (sp != sq) return sp ? Action::SplitReceiver : Action::SplitSource;
  const Node& np = ctx.h.node(p);
  const Node& nq = ctx.h.node(q);
  const bool larger_p = np.cluster || nq.cluster
                            ? np.box.diagonal().squaredNorm() >= nq.box.diagonal().squaredNorm()
                            : np.area >= nq.area;
  return larger_p ? Action::SplitReceiver : Action::SplitSource;
}

// The two parts of a link's power error (W): receiver (the factor's variation over p,
// visibility; for cluster links the whole bound) and source (q's leaves differ from the
// average B_q the link transfers).
std::pair<double, double> error_parts(const LinkContext& ctx, const Link& link,
                                      const SourceB& b_q) {
  const hr::Node& np = ctx.h.node(link.p);
  if (np.cluster || ctx.h.node(link.q).cluster)
    return {static_cast<double>(link.err) * b_q.high, 0.0};
  return {static_cast<double>(link.err) * b_q.mean,
          np.area * static_cast<double>(link.F) * b_q.spread};
}

Action decide(const LinkContext& ctx, const Link& link, const SourceB& b_q) {
  const auto [receiver, source] = error_parts(ctx, link, b_q);
  if (receiver + source <= ctx.threshold) return Action::Accept;
  // Splitting p does not reduce the source part (its children keep q's average), so split
  // q when that part dominates.
  if (source > receiver && !ctx.h.node(link.q).cluster && splittable(ctx, link.q))
    return Action::SplitSource;
  return split_choice(ctx, link.p, link.q);
}

// Element p <- element q: the exact unoccluded factor (adaptive quadrature of the contour
// formula over p) times the visible fraction at p's Gauss points (header).
Action element_link(const LinkContext& ctx, std::int32_t p, std::int32_t q, const SourceB& b_q,
                    Link& link, std::int64_t& rays) {
  const ff::PatchGeom& gp = ctx.h.geom(p);
  const ff::PatchGeom& gq = ctx.h.geom(q);
  if (!ff::can_exchange(gp, gq, ctx.plane_eps)) return Action::Drop;
  // Unoccluded factor: the 2 x 2 Gauss rule over p (relative error ~ (diameter / 2
  // distance)^4 for separated pairs, bounded by the interpolant check below elsewhere; at
  // shared edges it errs low by a few % of the factor of elements that the oracle has
  // already split to min_area, 0.1 % of the furnace's power at epsilon 1e-4), or, where no
  // Gauss point sees q although p and q can exchange (p mostly behind q's plane), the
  // adaptive quadrature of quadrature.hpp.
  thread_local std::vector<ff::QuadCell> cells;
  cells.clear();
  double unoccluded = 0.0;
  // Visibility points: p's 2 x 2 Gauss points weighted by w F(x -> q), or, when q is seen
  // from none of them (p mostly behind q's plane), the centroids of the quadrature cells
  // with the largest shares.
  struct Point {
    Eigen::Vector3d x;
    double weight;
  };
  Point points[4];
  int count = 0;
  // Test points of the interpolant: the Gauss points and the parametric centre.
  double test_f[5];
  std::array<double, 4> test_w[5];
  const ff::GaussRule rule = ff::gauss_legendre(2);
  for (int a = 0; a < rule.n; ++a)
    for (int b = 0; b < rule.n; ++b) {
      double jacobian = 0.0;
      const Eigen::Vector3d x = ff::quadrature_point(gp, rule.x[a], rule.x[b], jacobian);
      const double f = ff::point_to_patch(x, gp.normal, gq);
      test_f[2 * a + b] = f;
      test_w[2 * a + b] = corner_weights(gp, rule.x[a], rule.x[b]);
      const double w = rule.w[a] * rule.w[b] * jacobian;
      unoccluded += w * f / gp.area;
      if (f > 0.0) points[count++] = {x, w * f};
    }
  if (count == 0) {
    unoccluded = ff::integrate_unoccluded(gp, gq, ff::kEstimatorAccuracy, cells) / gp.area;
    if (!(unoccluded > 0.0)) return Action::Drop;
    std::vector<std::size_t> order(cells.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    const std::size_t keep = std::min<std::size_t>(4, order.size());
    std::partial_sort(order.begin(), order.begin() + keep, order.end(),
                      [&](std::size_t x, std::size_t y) { return cells[x].G > cells[y].G; });
    for (std::size_t k = 0; k < keep; ++k)
      points[count++] = {cells[order[k]].g.centroid, cells[order[k]].G};
  }
  {
    double jacobian = 0.0;
    const double u = gp.n == 3 ? 2.0 / 3.0 : 0.5, v = gp.n == 3 ? 0.5 : 0.5;
    test_f[4] = ff::point_to_patch(ff::quadrature_point(gp, u, v, jacobian), gp.normal, gq);
    test_w[4] = corner_weights(gp, u, v);
  }
  // The corner interpolant, scaled to the exact mean (uniform if no corner sees q).
  double corner_f[4] = {0, 0, 0, 0};
  const std::array<double, 4> mu = corner_masses(gp);
  double corner_mean = 0.0;
  for (int k = 0; k < gp.n; ++k) {
    corner_f[k] = ff::point_to_patch(corner_point(gp, k), gp.normal, gq);
    corner_mean += mu[k] * corner_f[k];
  }
  double shape[4];
  for (int k = 0; k < 4; ++k) shape[k] = corner_mean > 0.0 ? corner_f[k] / corner_mean : 1.0;
  double dev = 0.0;
  for (int t = 0; t < 5; ++t) {
    double interpolated = 0.0;
    for (int k = 0; k < gp.n; ++k) interpolated += test_w[t][k] * shape[k] * unoccluded;
    dev = std::max(dev, std::abs(test_f[t] - interpolated));
  }
  for (int k = 0; k < gp.n; ++k) dev = std::max(dev, std::abs(corner_f[k] - shape[k] * unoccluded));
  const int per_point = std::max(1, ctx.rays / 4);
  double seen_weight = 0.0, weight = 0.0;
  int traced = 0, points_seen = 0, points_blocked = 0, exhausted = 0;
  bool partial = false;
  // Rays drawn with the kernel's density from each point (the count_visible kernel, with the
  // sampled ends kept): their mean end is the kernel centroid y* on q, where the link reads
  // q's linear radiosity (offset from q's centroid, Link::d).
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double centroid_weight = 0.0;
  for (int k = 0; k < count; ++k) {
    const ff::KernelSampler sampler(points[k].x, gp.normal, gq);
    if (sampler.empty()) continue;
    const std::uint64_t stream = hash_keys(ctx.seed, link_key(p, q), k);
    const Kronecker4 seq(stream);
    Rng rng(mix64(stream));
    int seen = 0;
    Eigen::Vector3d ends = Eigen::Vector3d::Zero();
    for (int r = 0; r < per_point; ++r) {
      bool gave_up = false;
      const Eigen::Vector3d y = sampler.sample(seq.get(r, 0), seq.get(r, 1), seq.get(r, 2), rng, gave_up);
      exhausted += gave_up;
      ends += y;
      seen += ff::visible(ctx.bvh, points[k].x, gp.normal, y, gq.normal, ctx.offset);
    }
    traced += per_point;
    partial |= seen > 0 && seen < per_point;
    points_seen += seen > 0;
    points_blocked += seen < per_point;
    seen_weight += points[k].weight * seen / per_point;
    weight += points[k].weight;
    centroid += points[k].weight * ends / per_point;
    centroid_weight += points[k].weight;
  }
  // The corners' visible fractions shape the irradiance the link spreads over p (so light
  // is not pushed into the parts of p that a blocker hides, where it would be absorbed
  // unseen: the floor under a block); they count towards partial visibility too.
  double corner_vis[4] = {1, 1, 1, 1};
  for (int k = 0; k < gp.n; ++k) {
    if (!(corner_f[k] > 0.0)) continue;
    const Eigen::Vector3d x = corner_point(gp, k);
    const ff::KernelSampler sampler(x, gp.normal, gq);
    if (sampler.empty()) continue;
    const std::uint64_t stream = hash_keys(ctx.seed, link_key(p, q), 4 + k);
    const Kronecker4 seq(stream);
    Rng rng(mix64(stream));
    int seen = 0;
    for (int r = 0; r < per_point; ++r) {
      bool gave_up = false;
      const Eigen::Vector3d y = sampler.sample(seq.get(r, 0), seq.get(r, 1), seq.get(r, 2), rng, gave_up);
      exhausted += gave_up;
      seen += ff::visible(ctx.bvh, x, gp.normal, y, gq.normal, ctx.offset);
    }
    traced += per_point;
    partial |= seen > 0 && seen < per_point;
    points_seen += seen > 0;
    points_blocked += seen < per_point;
    corner_vis[k] = static_cast<double>(seen) / per_point;
  }
  rays += traced;
  partial |= points_seen > 0 && points_blocked > 0;
  {
    double mean = 0.0;
    for (int k = 0; k < gp.n; ++k) mean += mu[k] * corner_f[k] * corner_vis[k];
    if (mean > 0.0)
      for (int k = 0; k < 4; ++k) shape[k] = corner_f[k] * corner_vis[k] / mean;
  }
  const double vis = weight > 0.0 ? seen_weight / weight : 0.0;
  link.p = p;
  link.q = q;
  link.F = static_cast<float>(unoccluded * vis);
  const Eigen::Vector3d d =
      centroid_weight > 0.0 ? Eigen::Vector3d(centroid / centroid_weight - gq.centroid)
                            : Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) link.d[k] = static_cast<float>(d[k]);
  for (int k = 0; k < 4; ++k) link.c[k] = static_cast<float>(unoccluded * vis * shape[k]);
  // Visibility is uncertain by 1 where the shadow boundary crosses the link, else by the
  // chance that `traced` rays all agree while the true fraction is not 0 or 1 (~1/(n+1)).
  const double vis_uncertainty = partial ? 1.0 : 1.0 / (traced + 1);
  link.err = static_cast<float>(gp.area * (dev * vis + unoccluded * vis_uncertainty));
  return decide(ctx, link, b_q);
}

// Monte Carlo transfer between two nodes, one of them a cluster (header).
double cluster_transfer(const LinkContext& ctx, std::int32_t p, std::int32_t q,
                        std::int64_t& rays) {
  const Kronecker4 sx(hash_keys(ctx.seed, link_key(p, q), 1));
  const Kronecker4 sy(hash_keys(ctx.seed, link_key(p, q), 2));
  double sum = 0.0;
  for (int s = 0; s < ctx.rays; ++s) {
    Eigen::Vector3d nx, ny;
    const Eigen::Vector3d x = ctx.h.sample_point(p, sx.get(s, 0), sx.get(s, 1), sx.get(s, 2), nx);
    const Eigen::Vector3d y = ctx.h.sample_point(q, sy.get(s, 0), sy.get(s, 1), sy.get(s, 2), ny);
    const Eigen::Vector3d r = y - x;
    const double r2 = r.squaredNorm();
    if (r2 <= 0.0) continue;
    const double cx = nx.dot(r), cy = -ny.dot(r);
    if (cx <= 0.0 || cy <= 0.0) continue;
    ++rays;
    if (ff::visible(ctx.bvh, x, nx, y, ny, ctx.offset)) sum += cx * cy / (kPi * r2 * r2);
  }
  return ctx.h.node(p).area * ctx.h.node(q).area * sum / ctx.rays;
}

Action cluster_link(const LinkContext& ctx, std::int32_t p, std::int32_t q, const SourceB& b_q,
                    Link& link, std::int64_t& rays) {
  const Node& np = ctx.h.node(p);
  const Node& nq = ctx.h.node(q);
  if (!np.cluster && box_behind(ctx.h.geom(p), nq.box, ctx.plane_eps)) return Action::Drop;
  if (!nq.cluster && box_behind(ctx.h.geom(q), np.box, ctx.plane_eps)) return Action::Drop;
  double t_max = std::min(np.area, nq.area);
  const double d2 = box_distance_squared(np.box, nq.box);
  if (d2 > 0.0) t_max = std::min(t_max, np.area * nq.area / (kPi * d2));
  link.p = p;
  link.q = q;
  link.err = static_cast<float>(t_max);
  const Action action = decide(ctx, link, b_q);
  if (action != Action::Accept) return action;
  const double t = std::min(cluster_transfer(ctx, p, q, rays), t_max);
  link.F = static_cast<float>(t / np.area);
  for (float& c : link.c) c = link.F;
  return Action::Accept;
}

}  // namespace

bool splittable(const LinkContext& ctx, std::int32_t i) {
  const Node& n = ctx.h.node(i);
  return n.cluster || n.area >= 4.0 * ctx.min_area;
}

Action evaluate_link(const LinkContext& ctx, std::int32_t p, std::int32_t q, const SourceB& b_q,
                     Link& link, std::int64_t& rays) {
  if (p == q) return ctx.h.node(p).cluster ? Action::SplitBoth : Action::Drop;
  if (!ctx.h.node(p).cluster && !ctx.h.node(q).cluster)
    return element_link(ctx, p, q, b_q, link, rays);
  return cluster_link(ctx, p, q, b_q, link, rays);
}

double link_error(const LinkContext& ctx, const Link& link, const SourceB& b_q) {
  const auto [receiver, source] = error_parts(ctx, link, b_q);
  return receiver + source;
}

Action recheck_link(const LinkContext& ctx, const Link& link, const SourceB& b_q) {
  return decide(ctx, link, b_q);
}

}  // namespace lambert::hr
