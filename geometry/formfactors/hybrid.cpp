// Estimator "hybrid": exact unoccluded factor x an unbiased Monte Carlo visible fraction.
//
// With a the smaller patch of the pair (by area) and b the other,
//   G_ab = ∫_a F(x -> b) vis(x) dA_x,  vis(x) = ∫_b K V dA_y / ∫_b K dA_y,
// F(x -> b) the exact point-to-patch factor (Lambert's contour formula, horizon clipped)
// and K = cosθ_x cosθ_y / r². The unoccluded G0 = ∫_a F(x -> b) dA_x comes from the
// adaptive quadrature (quadrature.hpp: relative error < 1e-6 for any size ratio and
// distance). Rays are drawn before it, from a preview (preview_unoccluded): coarser cells
// (up to 16x their distance to b) valued P_c by one point factor each. Ray r picks a cell c
// with probability P_c / Σ P (the lattice's first coordinate, so cells are stratified), a
// point x_r uniform in it, and a point y_r of b with density ∝ K(x_r, ·) (visibility.hpp),
// so V_r = V(x_r, y_r) is a Bernoulli sample of vis(x_r) and
//   G ≈ G0 Σ_r w_r V_r / Σ_r w_r,   w_r = F(x_r -> b) A_c / P_c.
// For distant cells (x, y) is drawn jointly instead, uniform on cell x b's front part, and
// weighted by K (CellMode below): w_r = K(x_r, y_r) A_c A_b / (π P_c), the same importance
// weight relative to the target density ∝ K on a x b, without a contour evaluation per ray
// (and without the tries of drawing ∝ K by rejection: 1.9 per ray on the Cornell box, for
// the same variance per ray). The rays are traced (in
// packets); only if one is unblocked is G0 integrated (integrate_cells: the preview's cells
// split further into the quadrature's, so G0 is bitwise integrate_unoccluded's): a fully
// blocked pair is 0 whatever G0 is, and most of a CAD part's tested pairs are (92 % of a
// heat sink's).
// Unoccluded pairs get G0 exactly (V = 1) and fully blocked ones exactly 0. The ratio of
// weights is consistent, with a bias O(Var(w) / k), far below the statistical error: over
// the calibration cases (tests/geometry/calibration_test.cpp, 200 seeds) the mean error is
// < 0.1 stderr. The standard error comes from R independent replicates (replicates.hpp)
// plus the quadrature's error bound, 1e-6 G0 (kQuadratureTolerance). Cost per pair: the
// preview (~1-2 contour evaluations on a usual mesh), k rays, and where a ray is unblocked
// the quadrature nodes (9 .. ~500 contour evaluations).

#include <algorithm>
#include <cmath>

#include "core/sampling.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/quadrature.hpp"
#include "geometry/formfactors/replicates.hpp"
#include "geometry/formfactors/visibility.hpp"

namespace lambert::ff {
namespace {

// The area of the first of the two triangles a planar quad is cut into by uniform_in_cell
// (its own area for a triangle), computed once per cell rather than once per point.
double first_triangle_area(const PatchGeom& g) {
  return g.n == 4 ? 0.5 * (g.p[1] - g.p[0]).cross(g.p[2] - g.p[0]).norm() : g.area;
}

// A point uniform in area on a cell (triangle, or planar quad as two triangles, `first`
// the area of (p0, p1, p2): first_triangle_area); u picks the triangle, (s, t) place the
// point in it. A parallelogram (a whole patch of a meshed wall) maps (u, s) linearly: u
// keeps the stratification of the pick that chose the cell.
Eigen::Vector3d uniform_in_cell(const PatchGeom& g, double first, double u, double s, double t) {
  if (g.parallelogram) return g.p[0] + u * (g.p[1] - g.p[0]) + s * (g.p[3] - g.p[0]);  // linear
  Eigen::Vector3d a = g.p[0], b = g.p[1], c = g.p[2];
  if (g.n == 4 && u * g.area >= first) {
    b = g.p[2];
    c = g.p[3];
  }
  const double r = std::sqrt(s);
  return (1.0 - r) * a + r * (1.0 - t) * b + r * t * c;
}

// How rays from one cell are drawn. "Joint": x uniform in the cell and y uniform on b's
// front part, weighted by K(x, y) (scale: A_c A_b / (π P_c) per unit K), without a contour
// evaluation per ray. Chosen where K's mean over cell x b is at least kMinJointMeanToBound
// of its bound, so that no weight exceeds about 1 / kMinJointMeanToBound times the mean and
// the variance stays finite (touching cells, where K is unbounded and its square not
// integrable, never are); otherwise "per point": x uniform in the cell with weight
// F(x -> b) A_c / P_c and y drawn from x by KernelSampler (near pairs, where K varies
// strongly over b; a per-point ray costs ~5x a joint one).
struct CellMode {
  bool ready = false, joint = false;
  double scale = 0.0;  // a joint ray's weight per unit K: A_c A_b / (π P_c)
};
// The bound is loose (heights and distance bounded separately), so the worst case, 20x the
// variance of drawing ∝ K, is far from what happens: on the Cornell box at 32 samples,
// lowering this from 0.2 (the rejection sampler's old acceptance floor) to 0.05 raised the
// sum of all entries' variances by 1.1 % (156 of 1.78M entries at over twice their standard
// error, none of the surface factors measurably) and took a quarter less time on the heat
// sink, whose fin faces a few mm apart were all "per point" (per ray 0.45-0.51 -> 0.58-0.63
// of the Cornell box's).
constexpr double kMinJointMeanToBound = 0.05;

// K = (n_a · d)(-n_b · d) / r^4 for x in a's plane and y in b's: n_a · d is y's height above
// a's plane (at most the largest over b's front corners) and -n_b · d is x's height above
// b's plane (at most the largest over the cell's corners); r is at least the distance from
// the cell to b (cell_distance_bound: along a sliver cell's axis, not from its bounding
// sphere, which reaches to within half a sliver's length of b and made every sliver cell
// "per point").
// `ha` is the largest height of b's front part above a's plane (one per pair).
CellMode cell_mode(const QuadCell& cell, const PatchGeom& b, double ha, double bfront_area) {
  CellMode m;
  m.ready = true;
  double hb = 0.0;
  for (int k = 0; k < cell.g.n; ++k) hb = std::max(hb, b.normal.dot(cell.g.p[k] - b.p[0]));
  const double rmin = cell_distance_bound(cell.g, b);
  if (!(rmin > 0.0) || !(ha > 0.0) || !(hb > 0.0)) return m;
  const double kmax = ha * hb / (rmin * rmin * rmin * rmin);
  const double mean_k = M_PI * cell.G / (cell.g.area * bfront_area);
  m.joint = mean_k >= kMinJointMeanToBound * kmax;
  m.scale = cell.g.area * bfront_area / (M_PI * cell.G);
  return m;
}

}  // namespace

PairEstimate estimate_hybrid(const PairContext& ctx, std::int32_t i, std::int32_t j) {
  const bool i_small = ctx.geom[i].area <= ctx.geom[j].area;
  const PatchGeom& a = ctx.geom[i_small ? i : j];
  const PatchGeom& b = ctx.geom[i_small ? j : i];
  PairEstimate est;
  thread_local std::vector<QuadCell> cells;
  thread_local std::vector<CellMode> modes;
  thread_local std::vector<PatchGeom> bfront;
  thread_local std::vector<double> cdf, bcdf, cell_first, bfront_first;
  // The rays are drawn from the cells' midpoint previews; the cells' Gauss rules (G0's
  // exact value, ~10x the preview's cost on a CAD pair) are integrated only once some ray
  // is unblocked: a pair all of whose rays are blocked is 0 whatever G0 is (92 % of the
  // pairs a CAD heat sink tests). A preview with a cell of no value (a degenerate cell)
  // takes the rules at once.
  double G0 = preview_unoccluded(a, b, cells);
  bool integrated = false;
  auto integrate = [&] {
    if (!integrated) G0 = integrate_cells(a, b, cells);
    integrated = true;
  };
  for (const QuadCell& c : cells)
    if (!(c.G > 0.0 && std::isfinite(c.G))) {
      G0 = integrate_unoccluded(a, b, kEstimatorAccuracy, cells);
      integrated = true;
      break;
    }
  if (!(G0 > 0.0)) return est;
  cdf.clear();
  cell_first.clear();
  for (const QuadCell& c : cells) {
    cdf.push_back((cdf.empty() ? 0.0 : cdf.back()) + c.G);
    cell_first.push_back(first_triangle_area(c.g));
  }
  modes.assign(cells.size(), CellMode{});
  front_part(b, a, bfront);
  bcdf.clear();
  bfront_first.clear();
  for (const PatchGeom& t : bfront) {
    bcdf.push_back((bcdf.empty() ? 0.0 : bcdf.back()) + t.area);
    bfront_first.push_back(first_triangle_area(t));
  }
  if (bcdf.empty() || !(bcdf.back() > 0.0)) return est;
  double ha = 0.0;  // for cell_mode
  for (const PatchGeom& t : bfront)
    for (int k = 0; k < t.n; ++k) ha = std::max(ha, a.normal.dot(t.p[k] - a.p[0]));
  // A point uniform on b's front part from three uniforms.
  auto on_b = [&](double u, double s2, double t2) {
    const double pick = u * bcdf.back();
    size_t t = 0;
    while (t + 1 < bfront.size() && pick >= bcdf[t]) ++t;
    const double lo = t ? bcdf[t - 1] : 0.0;
    return uniform_in_cell(bfront[t], bfront_first[t],
                           std::clamp((pick - lo) / bfront[t].area, 0.0, 1.0), s2, t2);
  };
  const std::uint64_t key =
      hash_keys(ctx.seed, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(j));
  const int R = replicate_count(ctx.samples);
  // Per replicate: the rays' weight sums (all, unblocked). A joint ray's weight is known when
  // it is drawn; a per-point ray's, F(x -> b) A_c / P_c (a contour sum), is computed only
  // once some ray of the pair is unblocked: until then the blocked rays wait in `pending` (in
  // order), and a pair all of whose rays are blocked is 0 whatever its weights.
  struct Ray {
    int rep;
    int cell;
    bool joint;
    Eigen::Vector3d x;  // a per-point ray's start
    double w;           // a joint ray's weight
  };
  thread_local SegmentBatch<Ray> batch;
  batch.clear();
  thread_local std::vector<Ray> pending;
  pending.clear();
  double point_all[kReplicates] = {}, point_free[kReplicates] = {};
  int traced[kReplicates] = {};
  bool any_free = false;
  auto weigh = [&](const Ray& ray, bool free) {
    const double w =
        clipped_factor(ray.x, a.normal, b) * cells[ray.cell].g.area / cells[ray.cell].G;
    if (!(w > 0.0)) return;  // only by rounding at a horizon: the ray carries nothing
    point_all[ray.rep] += w;
    if (free) point_free[ray.rep] += w;
  };
  constexpr size_t kMaxPending = 1024;  // bounds the memory under --target-stderr's rays
  auto each = [&](const Ray& ray, bool free) {
    ++traced[ray.rep];
    if (ray.joint) {
      point_all[ray.rep] += ray.w;
      if (free) point_free[ray.rep] += ray.w;
    } else if (any_free || free || pending.size() >= kMaxPending) {
      for (const Ray& p : pending) weigh(p, false);
      pending.clear();
      weigh(ray, free);
    } else {
      pending.push_back(ray);
    }
    any_free = any_free || free;
  };
  const double lift_a = end_lift(a, ctx.offset), lift_b = end_lift(b, ctx.offset);
  bool unverified = false;
  for (int rep = 0; rep < R; ++rep) {
    const Kronecker4 seq(hash_keys(key, static_cast<std::uint64_t>(rep)));
    Rng rng(hash_keys(key, static_cast<std::uint64_t>(rep), 1));
    for (int r = 0, k = replicate_size(ctx.samples, rep); r < k; ++r) {
      const double pick = seq.get(r, 0) * cdf.back();
      const size_t c = std::min<size_t>(
          std::lower_bound(cdf.begin(), cdf.end(), pick) - cdf.begin(), cells.size() - 1);
      const double lo = c ? cdf[c - 1] : 0.0;
      const double within = std::clamp((pick - lo) / cells[c].G, 0.0, 1.0);
      if (!modes[c].ready) modes[c] = cell_mode(cells[c], b, ha, bcdf.back());
      Eigen::Vector3d x, y;
      Ray ray{rep, static_cast<int>(c), true, Eigen::Vector3d::Zero(), 0.0};
      bool exhausted = true;
      if (modes[c].joint) {
        x = uniform_in_cell(cells[c].g, cell_first[c], within, seq.get(r, 1), seq.get(r, 2));
        y = on_b(seq.get(r, 3), rng.uniform(), rng.uniform());
        const Eigen::Vector3d d = y - x;
        const double r2 = d.squaredNorm();
        const double heights = a.normal.dot(d) * -b.normal.dot(d);
        // (x, y) uniform on cell x b's front part, weighted by K (below): a K of 0 (by
        // rounding at an edge) carries nothing.
        if (!(r2 > 0.0 && heights > 0.0)) continue;
        ray.w = heights / (r2 * r2) * modes[c].scale;
        exhausted = false;
      } else {
        x = uniform_in_cell(cells[c].g, cell_first[c], within, seq.get(r, 1), seq.get(r, 2));
        const KernelSampler sampler(x, a.normal, b, /*with_factor=*/false);
        if (sampler.empty()) continue;
        ray.joint = false;
        ray.x = x;
        y = sampler.sample(seq.get(r, 3), rng.uniform(), rng.uniform(), rng, exhausted);
      }
      unverified = unverified || exhausted;
      batch.add(x, a.normal, lift_a, y, b.normal, lift_b, ray);
      if (batch.full()) est.rays += batch.flush(ctx.bvh, each);
    }
  }
  est.rays += batch.flush(ctx.bvh, each);
  double replicate[kReplicates];
  if (!any_free) {
    // Every ray blocked: 0 in every replicate that traced one.
    int used = 0;
    for (int rep = 0; rep < R; ++rep) used += traced[rep] > 0;
    if (used > 0) {
      std::fill(replicate, replicate + used, 0.0);
      const double quad = kQuadratureTolerance * G0;
      est.G = 0.0;
      est.var = replicate_variance(replicate, used) + quad * quad;
      est.unverified = unverified || used < R;
      return est;
    }
  }
  integrate();
  double num = 0.0, den = 0.0;
  int used = 0;
  for (int rep = 0; rep < R; ++rep) {
    const double rnum = point_free[rep], rden = point_all[rep];
    num += rnum;
    den += rden;
    // A replicate all of whose rays were skipped has no estimate: it is left out of the
    // variance as it is of the pooled ratio.
    if (rden > 0.0) replicate[used++] = rnum / rden;
  }
  if (!(den > 0.0)) {
    // No ray could be traced: report the unoccluded value, flagged (the driver warns).
    est.G = G0;
    est.unverified = true;
    return est;
  }
  est.G = G0 * num / den;
  for (int k = 0; k < used; ++k) replicate[k] *= G0;
  // Sampling variance plus the quadrature's error bound (kQuadratureTolerance of G0, the
  // worst case measured by the sweep in tests/geometry/quadrature_test.cpp), so that the
  // error bar of an unoccluded pair (no sampling error) is not zero.
  const double quad = kQuadratureTolerance * G0;
  est.var = replicate_variance(replicate, used) + quad * quad;
  est.unverified = unverified || used < R;
  return est;
}

}  // namespace lambert::ff
