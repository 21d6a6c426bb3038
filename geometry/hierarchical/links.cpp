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

// What p sees of q without occlusion: the mean factor F0 = (1/A_p) ∫_p F(x -> q) dA by
// the 2 x 2 Gauss rule over p (relative error ~ (diameter / 2 distance)^4 for separated
// pairs; at shared edges it errs low, on elements the oracle has split towards min_area:
// 0.02 % of a closed cube's power at epsilon 1e-4), or by the adaptive quadrature of
// quadrature.hpp where no Gauss point sees q although p and q can exchange (p mostly behind
// q's plane). Also the points visibility is sampled from (the Gauss points weighted by
// w F(x -> q), or the centroids of the largest quadrature cells) and the test points of the
// corner interpolant (the Gauss points and the parametric centre).
struct Unoccluded {
  double mean = 0.0;
  struct Point {
    Eigen::Vector3d x;
    double weight;
  } points[4];
  int count = 0;
  double test_f[5];
  std::array<double, 4> test_w[5];
};

Unoccluded unoccluded_factor(const ff::PatchGeom& gp, const ff::PatchGeom& gq) {
  Unoccluded u;
  const ff::GaussRule rule = ff::gauss_legendre(2);
  for (int a = 0; a < rule.n; ++a)
    for (int b = 0; b < rule.n; ++b) {
      double jacobian = 0.0;
      const Eigen::Vector3d x = ff::quadrature_point(gp, rule.x[a], rule.x[b], jacobian);
      const double f = ff::point_to_patch(x, gp.normal, gq);
      u.test_f[2 * a + b] = f;
      u.test_w[2 * a + b] = corner_weights(gp, rule.x[a], rule.x[b]);
      const double w = rule.w[a] * rule.w[b] * jacobian;
      u.mean += w * f / gp.area;
      if (f > 0.0) u.points[u.count++] = {x, w * f};
    }
  if (u.count == 0) {
    thread_local std::vector<ff::QuadCell> cells;
    u.mean = ff::integrate_unoccluded(gp, gq, ff::kEstimatorAccuracy, cells) / gp.area;
    std::vector<std::size_t> order(cells.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    const std::size_t keep = std::min<std::size_t>(4, order.size());
    std::partial_sort(order.begin(), order.begin() + keep, order.end(),
                      [&](std::size_t x, std::size_t y) { return cells[x].G > cells[y].G; });
    for (std::size_t k = 0; k < keep; ++k)
      u.points[u.count++] = {cells[order[k]].g.centroid, cells[order[k]].G};
  }
  double jacobian = 0.0;
  const double cu = gp.n == 3 ? 2.0 / 3.0 : 0.5, cv = 0.5;  // the centroid's parameters
  u.test_f[4] = ff::point_to_patch(ff::quadrature_point(gp, cu, cv, jacobian), gp.normal, gq);
  u.test_w[4] = corner_weights(gp, cu, cv);
  return u;
}

// Visibility from x to q: `rays` rays to points of q drawn with the kernel's density (the
// count_visible kernel, keeping the sampled ends, whose mean is the kernel centroid on q).
struct Visibility {
  int seen = 0, traced = 0;
  Eigen::Vector3d ends = Eigen::Vector3d::Zero();  ///< sum of the sampled points of q
};

Visibility trace_from(const LinkContext& ctx, const Eigen::Vector3d& x, const Eigen::Vector3d& nx,
                      double x_lift, const ff::PatchGeom& gq, int rays, std::uint64_t stream) {
  Visibility v;
  const ff::KernelSampler sampler(x, nx, gq);
  if (sampler.empty()) return v;
  const Kronecker4 seq(stream);
  Rng rng(mix64(stream));
  for (int r = 0; r < rays; ++r) {
    bool gave_up = false;  // never seen in practice (KernelSampler)
    const Eigen::Vector3d y = sampler.sample(seq.get(r, 0), seq.get(r, 1), seq.get(r, 2), rng, gave_up);
    v.ends += y;
    v.seen += ff::visible(ctx.bvh, x, nx, x_lift, y, gq.normal, ff::end_lift(gq, ctx.offset));
  }
  v.traced = rays;
  return v;
}

// Element p <- element q (header): F = F0 vis, corner values shaped by the corners' exact
// factors and visible fractions, error from the interpolant's deviation and visibility.
Action element_link(const LinkContext& ctx, std::int32_t p, std::int32_t q, const SourceB& b_q,
                    Link& link, std::int64_t& rays) {
  const ff::PatchGeom& gp = ctx.h.geom(p);
  const ff::PatchGeom& gq = ctx.h.geom(q);
  if (!ff::can_exchange(gp, gq, ctx.plane_eps)) return Action::Drop;
  const Unoccluded u = unoccluded_factor(gp, gq);
  if (!(u.mean > 0.0)) return Action::Drop;
  const int per_point = std::max(1, ctx.rays / 4);
  int traced = 0, points_seen = 0, points_blocked = 0;
  auto count = [&](const Visibility& v) {
    traced += v.traced;
    points_seen += v.seen > 0;
    points_blocked += v.seen < v.traced;
  };
  // Visibility at the sample points: the mean visible fraction and the kernel centroid.
  double seen_weight = 0.0, weight = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int k = 0; k < u.count; ++k) {
    const Visibility v = trace_from(ctx, u.points[k].x, gp.normal, ff::end_lift(gp, ctx.offset), gq,
                                    per_point, hash_keys(ctx.seed, link_key(p, q), k));
    if (v.traced == 0) continue;
    count(v);
    seen_weight += u.points[k].weight * v.seen / v.traced;
    weight += u.points[k].weight;
    centroid += u.points[k].weight * v.ends / v.traced;
  }
  // The corners' factors and visible fractions shape the irradiance the link spreads over
  // p, so light is not pushed into the parts of p that q does not reach or a blocker hides
  // (where it would be absorbed unseen: the floor under a block).
  const std::array<double, 4> mu = corner_masses(gp);
  double corner_f[4] = {0, 0, 0, 0}, corner_vis[4] = {1, 1, 1, 1};
  for (int k = 0; k < gp.n; ++k) {
    corner_f[k] = ff::point_to_patch(corner_point(gp, k), gp.normal, gq);
    if (!(corner_f[k] > 0.0)) continue;
    const Visibility v =
        trace_from(ctx, corner_point(gp, k), gp.normal, ff::end_lift(gp, ctx.offset), gq, per_point,
                   hash_keys(ctx.seed, link_key(p, q), 4 + k));
    if (v.traced == 0) continue;
    count(v);
    corner_vis[k] = static_cast<double>(v.seen) / v.traced;
  }
  rays += traced;
  // The interpolant of the unoccluded corner factors (scaled to F0) against the exact factor
  // at the test points and corners.
  double f_mean = 0.0, fv_mean = 0.0;
  for (int k = 0; k < gp.n; ++k) {
    f_mean += mu[k] * corner_f[k];
    fv_mean += mu[k] * corner_f[k] * corner_vis[k];
  }
  double dev = 0.0;
  for (int t = 0; t < 5; ++t) {
    double interpolated = 0.0;
    for (int k = 0; k < gp.n; ++k)
      interpolated += u.test_w[t][k] * (f_mean > 0.0 ? corner_f[k] / f_mean : 1.0) * u.mean;
    dev = std::max(dev, std::abs(u.test_f[t] - interpolated));
  }
  for (int k = 0; k < gp.n && f_mean > 0.0; ++k)
    dev = std::max(dev, std::abs(corner_f[k] - corner_f[k] / f_mean * u.mean));
  const double vis = weight > 0.0 ? seen_weight / weight : 0.0;
  link.p = p;
  link.q = q;
  link.F = static_cast<float>(u.mean * vis);
  for (int k = 0; k < 4; ++k) {
    const double shape = fv_mean > 0.0 ? corner_f[k] * corner_vis[k] / fv_mean : 1.0;
    link.c[k] = static_cast<float>(u.mean * vis * shape);
  }
  const Eigen::Vector3d d = weight > 0.0 ? Eigen::Vector3d(centroid / weight - gq.centroid)
                                         : Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) link.d[k] = static_cast<float>(d[k]);
  // Visibility is uncertain by 1 where the shadow boundary crosses the link (rays disagree),
  // else by the chance that `traced` rays all agree while the true fraction is not 0 or 1
  // (~1/(n+1)).
  const bool partial = points_seen > 0 && points_blocked > 0;
  const double vis_uncertainty = partial ? 1.0 : 1.0 / (traced + 1);
  link.err = static_cast<float>(gp.area * (dev * vis + u.mean * vis_uncertainty));
  return decide(ctx, link, b_q);
}

// Monte Carlo transfer between two nodes, one of them a cluster (header).
double cluster_transfer(const LinkContext& ctx, std::int32_t p, std::int32_t q,
                        std::int64_t& rays, float* bins) {
  const Kronecker4 sx(hash_keys(ctx.seed, link_key(p, q), 1));
  const Kronecker4 sy(hash_keys(ctx.seed, link_key(p, q), 2));
  double sum = 0.0, share[6] = {0, 0, 0, 0, 0, 0};
  // The pairs' descents in blocks, a block's descents interleaved (Hierarchy::descend).
  constexpr int kBlock = 32;
  std::int32_t ex[kBlock], ey[kBlock];
  double ux[kBlock], uy[kBlock];
  for (int s = 0; s < ctx.rays; ++s) {
    const int j = s % kBlock;
    if (j == 0) {
      const int n = std::min(kBlock, ctx.rays - s);
      for (int k = 0; k < n; ++k) {
        ux[k] = sx.get(s + k, 0);
        uy[k] = sy.get(s + k, 0);
      }
      ctx.h.descend(p, n, ex, ux);
      ctx.h.descend(q, n, ey, uy);
    }
    Eigen::Vector3d nx, ny;
    double wx = 0.0, wy = 0.0;
    const Eigen::Vector3d x = ctx.h.element_point(ex[j], ux[j], sx.get(s, 1), sx.get(s, 2), nx, wx);
    const Eigen::Vector3d y = ctx.h.element_point(ey[j], uy[j], sy.get(s, 1), sy.get(s, 2), ny, wy);
    const Eigen::Vector3d r = y - x;
    const double r2 = r.squaredNorm();
    if (r2 <= 0.0) continue;
    const double cx = nx.dot(r), cy = -ny.dot(r);
    if (cx <= 0.0 || cy <= 0.0) continue;
    ++rays;
    if (!ff::visible(ctx.bvh, x, nx, ctx.offset + wx, y, ny, ctx.offset + wy)) continue;
    const double k = cx * cy / (kPi * r2 * r2);
    sum += k;
    // Where it arrived: the receiving face's orientation, n_a^2 to the bin of n_a's sign.
    for (int a = 0; a < 3; ++a) share[nx[a] >= 0.0 ? 2 * a : 2 * a + 1] += k * nx[a] * nx[a];
  }
  for (int b = 0; b < 6; ++b) bins[b] = sum > 0.0 ? static_cast<float>(share[b] / sum) : 0.0f;
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
  const double t = std::min(cluster_transfer(ctx, p, q, rays, link.bins), t_max);
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
