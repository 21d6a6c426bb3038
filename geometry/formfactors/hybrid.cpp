// Estimator "hybrid": analytic kernel x Monte Carlo visibility.
//
// From the side of patch a towards patch b:
//   G_a = Σ_n w_n F(x_n -> b) · vis,   w_n = Gauss-Legendre weight x Jacobian at node x_n,
// where F(x -> b) is the exact point-to-patch factor (Lambert's contour formula, horizon
// clipped) and vis = Σ_r w_{n_r} K(x_{n_r}, y_r) V_r / Σ_r w_{n_r} K(x_{n_r}, y_r) the
// kernel-weighted visible fraction from rays r, each from a node n_r to a point y_r
// uniform on the part of b in front of a (Kronecker lattice), K = cosθ_x cosθ_y / r².
// With no blocker vis = 1 exactly and G_a is the unoccluded G to quadrature accuracy: the
// 1/r² singularity only enters the ratio vis, where it cancels unless rays are blocked, so
// patches sharing an edge are as cheap as distant ones.
// The node count grows as the patches get closer (order 2 far away .. 12 for neighbours).
// Both sides are estimated with half the rays each and averaged. The variance combines the
// ratio estimator's delta-method variance of each side and the quadrature disagreement
// between the two sides. Cost per pair: 2 m² contour evaluations + k rays.

#include <algorithm>

#include "core/sampling.hpp"
#include "geometry/formfactors/pairwise.hpp"

namespace lambert::ff {
namespace {

// Gauss-Legendre order for integrating over patch `outer` the point-to-patch factor to a
// patch at centroid distance d. The integrand is smooth with derivatives growing like
// (size/d)^p; the tensor rule of order m is exact for degree 2m-1, so the relative error
// falls like (size / 2d)^(2m). Orders below keep it under ~1e-6 for d >= size and make the
// adjacent case (d ≈ size/2, log-singular derivative at the shared edge) ~1e-5.
int quadrature_order(const PatchGeom& outer, const PatchGeom& inner) {
  const double q = (outer.centroid - inner.centroid).norm() / std::max(outer.diameter, 1e-300);
  if (q > 6.0) return 2;
  if (q > 3.0) return 3;
  if (q > 1.5) return 4;
  if (q > 0.9) return 6;
  return 12;
}

struct SideEstimate {
  double G = 0.0, var = 0.0, unoccluded = 0.0;
  std::int64_t rays = 0;
};

// The part of patch a in front of patch b's plane, as one or more integration pieces.
// F(x -> b) is exactly 0 behind b's plane and jumps there (a floor patch running under a
// block whose face stands on it), which Gauss-Legendre rules integrate badly; clipping
// the domain to the front part keeps the integrand continuous.
void integration_domain(const PatchGeom& a, const PatchGeom& b, std::vector<PatchGeom>& pieces) {
  pieces.clear();
  double d[4];
  bool straddles = false;
  for (int k = 0; k < a.n; ++k) {
    d[k] = b.normal.dot(a.p[k] - b.p[0]);
    straddles = straddles || d[k] <= 0.0;
  }
  if (!straddles) {
    pieces.push_back(a);
    return;
  }
  Eigen::Vector3d poly[5];
  int m = 0;
  for (int k = 0; k < a.n; ++k) {
    const int l = (k + 1) % a.n;
    if (d[k] > 0.0) poly[m++] = a.p[k];
    if ((d[k] > 0.0) != (d[l] > 0.0)) poly[m++] = a.p[k] + d[k] / (d[k] - d[l]) * (a.p[l] - a.p[k]);
  }
  for (int k = 1; k + 1 < m; ++k) {
    PatchGeom t;
    t.n = 3;
    t.p = {poly[0], poly[k], poly[k + 1], poly[k + 1]};
    t.normal = a.normal;
    t.area = 0.5 * (poly[k] - poly[0]).cross(poly[k + 1] - poly[0]).norm();
    if (t.area > 0.0) pieces.push_back(t);
  }
}

SideEstimate one_side(const PairContext& ctx, const PatchGeom& a, const PatchGeom& b, int rays,
                      std::uint64_t stream) {
  SideEstimate out;
  const int m = quadrature_order(a, b);
  const GaussRule rule = gauss_legendre(m);
  thread_local std::vector<PatchGeom> pieces, targets;
  thread_local std::vector<Eigen::Vector3d> xs;
  thread_local std::vector<double> nw, wf, target_cdf;
  integration_domain(a, b, pieces);
  // Visibility rays go to points of b in front of a's plane only (every node x lies in that
  // plane, so the horizon is the same for all): points beyond it are not "blocked", they
  // are outside the integral, and counting them as blocked would bias the estimate.
  integration_domain(b, a, targets);
  target_cdf.clear();
  for (const PatchGeom& t : targets) target_cdf.push_back((target_cdf.empty() ? 0.0 : target_cdf.back()) + t.area);
  xs.clear();
  nw.clear();
  wf.clear();
  // Node points and their unoccluded contributions w_n F(x_n -> b).
  for (const PatchGeom& piece : pieces) {
    for (int u = 0; u < m; ++u) {
      for (int v = 0; v < m; ++v) {
        double jac;
        xs.push_back(quadrature_point(piece, rule.x[u], rule.x[v], jac));
        nw.push_back(rule.w[u] * rule.w[v] * jac);
        wf.push_back(nw.back() * point_to_patch(xs.back(), a.normal, b));
        out.unoccluded += wf.back();
      }
    }
  }
  const int nodes = static_cast<int>(xs.size());
  if (out.unoccluded <= 0.0 || rays <= 0 || targets.empty()) return out;
  const Kronecker4 seq(stream);
  double num = 0.0, den = 0.0;
  // Node of ray r: spread evenly over the nodes (randomly rotated) when rays < nodes,
  // otherwise every node gets floor or ceil(rays / nodes) rays.
  const double rotate = seq.get(0, 0);
  thread_local std::vector<std::pair<double, bool>> samples;
  samples.clear();
  for (int r = 0; r < rays; ++r) {
    const int n = rays < nodes
                      ? static_cast<int>((r + rotate) * nodes / rays) % nodes
                      : (r + static_cast<int>(rotate * nodes)) % nodes;
    if (wf[n] <= 0.0) continue;
    double jb;
    const double pick = seq.get(r, 1) * target_cdf.back();
    const size_t t = std::min<size_t>(
        std::lower_bound(target_cdf.begin(), target_cdf.end(), pick) - target_cdf.begin(),
        targets.size() - 1);
    const Eigen::Vector3d y = sample_patch(targets[t], seq.get(r, 2), seq.get(r, 3), jb);
    // Weight of the ray: node weight x kernel K(x_n, y). The visible fraction must be
    // kernel-weighted: with y uniform on b, Σ_r K V / Σ_r K -> ∫ K V dA / ∫ K dA per node,
    // whereas an unweighted fraction of b's area would be biased wherever a blocker shades
    // the near (high-K) part of b differently from the far part.
    const Eigen::Vector3d d = y - xs[n];
    const double r2 = d.squaredNorm();
    const double kernel = r2 > 0.0 ? a.normal.dot(d) * -b.normal.dot(d) / (r2 * r2) : 0.0;
    if (!(kernel > 0.0)) continue;
    const double w = nw[n] * kernel;
    const bool vis = visible(ctx.bvh, xs[n], a.normal, y, b.normal, ctx.offset);
    ++out.rays;
    num += vis ? w : 0.0;
    den += w;
    samples.emplace_back(w, vis);
  }
  if (den <= 0.0) {
    // No usable ray (every node saw b only beyond the horizon of its sample): keep the
    // unoccluded value; cannot happen for pairs that can_exchange with rays > 0 in practice.
    out.G = out.unoccluded;
    return out;
  }
  const double frac = num / den;
  out.G = out.unoccluded * frac;
  // Delta-method variance of the ratio estimator: Σ w_r² (V_r - frac)² / (Σ w_r)².
  double s2 = 0.0;
  for (const auto& [w, vis] : samples) {
    const double dev = (vis ? 1.0 : 0.0) - frac;
    s2 += w * w * dev * dev;
  }
  out.var = out.unoccluded * out.unoccluded * s2 / (den * den);
  return out;
}

}  // namespace

PairEstimate estimate_hybrid(const PairContext& ctx, std::int32_t i, std::int32_t j) {
  const PatchGeom& a = ctx.geom[i];
  const PatchGeom& b = ctx.geom[j];
  const std::uint64_t key = hash_keys(ctx.seed, static_cast<std::uint64_t>(i),
                                      static_cast<std::uint64_t>(j));
  PairEstimate est;
  if (ctx.samples == 1) {
    // One ray: integrate over the smaller patch (its nodes resolve the factor best).
    const bool a_small = a.area <= b.area;
    const SideEstimate s = a_small ? one_side(ctx, a, b, 1, key) : one_side(ctx, b, a, 1, key);
    est.G = s.G;
    est.rays = s.rays;
    return est;
  }
  const int ka = (ctx.samples + 1) / 2;
  const SideEstimate sa = one_side(ctx, a, b, ka, key);
  const SideEstimate sb = one_side(ctx, b, a, ctx.samples - ka, mix64(key));
  est.G = 0.5 * (sa.G + sb.G);
  const double quad = 0.5 * (sa.unoccluded - sb.unoccluded);
  est.var = 0.25 * (sa.var + sb.var) + quad * quad;
  est.rays = sa.rays + sb.rays;
  return est;
}

}  // namespace lambert::ff
