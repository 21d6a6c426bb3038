#include "geometry/formfactors/quadrature.hpp"

#include <algorithm>

namespace lambert::ff {

void front_part(const PatchGeom& a, const PatchGeom& b, std::vector<PatchGeom>& pieces) {
  pieces.clear();
  double d[4];
  bool straddles = false;
  for (int k = 0; k < a.n; ++k) {
    d[k] = b.normal.dot(a.p[k] - b.p[0]);
    straddles = straddles || d[k] < 0.0;  // a corner in b's plane only touches it
  }
  if (!straddles) {
    pieces.push_back(a);
    return;
  }
  Eigen::Vector3d poly[kMaxClippedCorners];  // a plane cuts a warped quad into a hexagon
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
    t.centroid = (poly[0] + poly[k] + poly[k + 1]) / 3.0;
    for (int i = 0; i < 3; ++i)
      for (int j = i + 1; j < 3; ++j) t.diameter = std::max(t.diameter, (t.p[i] - t.p[j]).norm());
    if (t.area > 0.0) pieces.push_back(t);
  }
}

double distance_to_patch(const Eigen::Vector3d& x, const PatchGeom& g) {
  const double h = g.normal.dot(x - g.p[0]);
  const Eigen::Vector3d q = x - h * g.normal;  // projection onto the plane
  bool inside = true;
  for (int k = 0; k < g.n && inside; ++k)
    inside = (g.p[(k + 1) % g.n] - g.p[k]).cross(q - g.p[k]).dot(g.normal) >= 0.0;
  if (inside) return std::abs(h);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < g.n; ++k) {
    const Eigen::Vector3d e = g.p[(k + 1) % g.n] - g.p[k];
    const double e2 = e.squaredNorm();
    const double t = e2 > 0.0 ? std::clamp(e.dot(x - g.p[k]) / e2, 0.0, 1.0) : 0.0;
    best = std::min(best, (g.p[k] + t * e - x).norm());
  }
  return best;
}

namespace {

// Gauss order for a cell of diameter h at distance d from the nearest edge of the other
// patch: the relative error ~(h / 2d)^(2m) is kept below ~1e-7 (measured worst over the
// sweep of tests/geometry/quadrature_test.cpp: see there). A cell touching the other patch
// (d <= 0, at touch_depth) holds a log-singular derivative at the contact; order 6 on a
// cell 1/8 of the patch leaves < 1e-9 of G there (shared-edge squares: 7e-11).
int cell_order(double h, double d, int extra) {
  int m = 6;
  if (d > 0.0) {
    const double t = h / d;
    m = t <= 0.05 ? 2 : t <= 0.25 ? 3 : t <= 0.5 ? 4 : t <= 1.0 ? 5 : t <= 2.0 ? 6 : 8;
  }
  return std::min(m + extra, kMaxGaussOrder);
}

// Cells whose long side exceeds kSliverRatio times their short one are halved across their
// length instead of quartered: quartering keeps a cell's shape, so a sliver (a CAD tip facet
// 100 mm by 0.05 mm) split until its length is under kappa times a distance of a few mm
// became 4^6 cells ~1 um wide, the same number as a square of its length (issue 36: 95 % of
// a heat sink's time). Halving makes the cell count grow with the length only (32 cells
// instead of 1024 at length / h = 20). Every split, in two or in four, halves the diameter
// the criterion and cell_order use, so depth still counts halvings. Cells within the ratio
// (every patch of a usual mesh) are quartered as before.
constexpr double kSliverRatio = 4.0;

// The children of a cell, written to out; returns their count (2 or 4). Quads are split at
// the bilinear midpoints (each child the bilinear image of a quarter, or of a half across
// the long direction, of the parameter square). Triangles are quartered at the edge
// midpoints; a sliver one (longest edge L > kSliverRatio x its height) is, when a needle
// (shortest edge <= L / kSliverRatio), cut across at the midpoints of its two long edges
// into an apex triangle and a trapezoid (a quad), and otherwise (a flat "cap") bisected at
// the midpoint of its longest edge. Children keep the parent's winding.
int split(const PatchGeom& g, PatchGeom* out) {
  auto make = [&](PatchGeom& c, std::initializer_list<Eigen::Vector3d> corners) {
    c.n = static_cast<int>(corners.size());
    int k = 0;
    for (const Eigen::Vector3d& p : corners) c.p[k++] = p;
    if (c.n == 3) c.p[3] = c.p[2];
    c.normal = g.normal;
  };
  auto mid = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) { return 0.5 * (p + q); };
  int count = 4;
  if (g.n == 3) {
    double e[3];
    for (int k = 0; k < 3; ++k) e[k] = (g.p[(k + 1) % 3] - g.p[k]).norm();
    const int longest = static_cast<int>(std::max_element(e, e + 3) - e);
    const int shortest = static_cast<int>(std::min_element(e, e + 3) - e);
    const double L = e[longest];
    if (L * L <= kSliverRatio * 2.0 * g.area) {
      const Eigen::Vector3d m01 = mid(g.p[0], g.p[1]), m12 = mid(g.p[1], g.p[2]),
                            m20 = mid(g.p[2], g.p[0]);
      make(out[0], {g.p[0], m01, m20});
      make(out[1], {m01, g.p[1], m12});
      make(out[2], {m20, m12, g.p[2]});
      make(out[3], {m01, m12, m20});
    } else if (e[shortest] * kSliverRatio <= L) {
      // Needle: edge (p, q) short, o the apex far from it.
      const Eigen::Vector3d &p = g.p[shortest], &q = g.p[(shortest + 1) % 3],
                            &o = g.p[(shortest + 2) % 3];
      const Eigen::Vector3d mop = mid(o, p), mqo = mid(q, o);
      make(out[0], {o, mop, mqo});
      make(out[1], {mop, p, q, mqo});
      count = 2;
    } else {
      // Cap: bisect the longest edge (p, q), o opposite.
      const Eigen::Vector3d &p = g.p[longest], &q = g.p[(longest + 1) % 3],
                            &o = g.p[(longest + 2) % 3];
      const Eigen::Vector3d m = mid(p, q);
      make(out[0], {o, p, m});
      make(out[1], {o, m, q});
      count = 2;
    }
  } else {
    const Eigen::Vector3d m01 = mid(g.p[0], g.p[1]), m12 = mid(g.p[1], g.p[2]),
                          m23 = mid(g.p[2], g.p[3]), m30 = mid(g.p[3], g.p[0]);
    const double along_u = (m12 - m30).norm(), along_v = (m23 - m01).norm();
    if (along_u > kSliverRatio * along_v) {
      make(out[0], {g.p[0], m01, m23, g.p[3]});
      make(out[1], {m01, g.p[1], g.p[2], m23});
      count = 2;
    } else if (along_v > kSliverRatio * along_u) {
      make(out[0], {g.p[0], g.p[1], m12, m30});
      make(out[1], {m30, m12, g.p[2], g.p[3]});
      count = 2;
    } else {
      const Eigen::Vector3d c = 0.25 * (g.p[0] + g.p[1] + g.p[2] + g.p[3]);
      make(out[0], {g.p[0], m01, c, m30});
      make(out[1], {m01, g.p[1], m12, c});
      make(out[2], {c, m12, g.p[2], m23});
      make(out[3], {m30, c, m23, g.p[3]});
    }
  }
  for (int k = 0; k < count; ++k) {
    PatchGeom& c = out[k];
    c.area = c.n == 3 ? 0.5 * (c.p[1] - c.p[0]).cross(c.p[2] - c.p[0]).norm()
                      : 0.5 * (c.p[2] - c.p[0]).cross(c.p[3] - c.p[1]).norm();
  }
  return count;
}

// The error of a Gauss rule of order m along one parameter direction of quadrature_point
// falls like (extent / 2d)^(2m) with the cell's extent in that direction, so a sliver cell
// needs its full order along its length only: across it (0.05 mm against distances of
// mm in a CAD heat sink) cell_order's lowest order is already exact to rounding. For a
// sliver (longest extent > kSliverRatio x the other) this writes to `frame` the cell with its
// corners turned (same winding) so that the parameter u runs along the length — a
// triangle's collapsed corner p0 opposite its shortest edge; a quad as it is — and the
// extents bounding |dx/du| (along) and |dx/dv| (across); otherwise returns false and the
// cell gets one order from its diameter, as before. Triangle x = p0 + u (p1 - p0) +
// u v (p2 - p1): |dx/du| <= max(|p1 - p0|, |p2 - p0|), |dx/dv| <= |p2 - p1|; bilinear quad:
// |dx/du| <= max(|p1 - p0|, |p2 - p3|), |dx/dv| <= max(|p3 - p0|, |p2 - p1|).
bool sliver_frame(const PatchGeom& g, PatchGeom& frame, double& along, double& across) {
  frame = g;
  if (g.n == 3) {
    double e[3];
    for (int k = 0; k < 3; ++k) e[k] = (g.p[(k + 1) % 3] - g.p[k]).norm();
    const int shortest = static_cast<int>(std::min_element(e, e + 3) - e);
    for (int k = 0; k < 3; ++k) frame.p[k] = g.p[(shortest + 2 + k) % 3];  // p0: the apex
    frame.p[3] = frame.p[2];
    along = std::max((frame.p[1] - frame.p[0]).norm(), (frame.p[2] - frame.p[0]).norm());
    across = e[shortest];
  } else {
    const double u = std::max((g.p[1] - g.p[0]).norm(), (g.p[2] - g.p[3]).norm());
    const double v = std::max((g.p[3] - g.p[0]).norm(), (g.p[2] - g.p[1]).norm());
    if (v > u) {  // turn so that u runs along the length
      for (int k = 0; k < 4; ++k) frame.p[k] = g.p[(k + 1) % 4];
    }
    along = std::max(u, v);
    across = std::min(u, v);
  }
  return along > kSliverRatio * across;
}

// Distance between the segments [p1, q1] and [p2, q2] (Ericson, Real-Time Collision
// Detection, 5.1.9: the closest parameters clamped to [0, 1] in turn). A point is a
// segment of length 0.
double segment_distance(const Eigen::Vector3d& p1, const Eigen::Vector3d& q1,
                        const Eigen::Vector3d& p2, const Eigen::Vector3d& q2) {
  const Eigen::Vector3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (!(a > 0.0)) {
    t = e > 0.0 ? std::clamp(f / e, 0.0, 1.0) : 0.0;
  } else {
    const double c = d1.dot(r);
    if (!(e > 0.0)) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return (p1 + s * d1 - (p2 + t * d2)).norm();
}

// A sliver cell's axis, the segment [from, to] along its length in the frame of
// sliver_frame (a triangle's apex to the midpoint of its short edge; a quad's midpoints of
// its two short sides), and the largest distance of its corners from that axis: every
// point of the (convex) cell lies within `across_radius` of the axis, so its distance to an
// edge is at least the axis's distance minus across_radius. For a sliver this bound is the
// true distance to within its width, where the bounding sphere (centre distance minus half
// the length) undercuts it by up to half its length, and cut cells twice as short as the
// integrand needs.
void sliver_axis(const PatchGeom& frame, Eigen::Vector3d& from, Eigen::Vector3d& to,
                 double& across_radius) {
  if (frame.n == 3) {
    from = frame.p[0];
    to = 0.5 * (frame.p[1] + frame.p[2]);
  } else {
    from = 0.5 * (frame.p[0] + frame.p[3]);
    to = 0.5 * (frame.p[1] + frame.p[2]);
  }
  across_radius = 0.0;
  for (int k = 0; k < frame.n; ++k)
    across_radius = std::max(across_radius, segment_distance(frame.p[k], frame.p[k], from, to));
}

// How far, along a sliver cell's length, F(x -> b) stays analytic near the edge [p, q] of
// b (along_lines and line_root_distance, with the ends' distances from the cell's axis):
// the distance from the cell's u-lines (sliver_frame's parameter lines along its length,
// taken at v = 0, 1/2, 1) to the nearest complex singularity of the edge's
// contour term as x runs along them. With x = o + s e_u (e_u a unit direction) the term is
// analytic in s except where |x - p|² |x - q|² = 0, at s = s_p ± i ρ_p (s_p the projection
// of p, ρ_p its distance from the line: within the 3D distance of p from the axis; likewise
// q), and where |(x - p) × (q - p)|² = 0, a quadratic A s² + B s + C positive on the real
// line with roots σ ± iτ, A = |e_u × e|², σ = -(w × e)·(e_u × e) / A, τ = |(w × e) × (e_u ×
// e)| / A (w = o - p, e = q - p; Lagrange's identity, no cancellation). An edge parallel
// to the cell (A = 0) has no such root: the term varies along the cell only near the
// edge's ends, however close the edge runs beside it. So a sliver beside a long parallel
// edge (a CAD fin's tip facet and the next fin's face) is a smooth integrand along its
// length, where the edge's distance (segment_distance) would cut it into pieces a few
// times that distance long (78 % of a heat sink's quadrature nodes). Gauss-Legendre's
// error depends on the distance to the nearest singularity, which is this one.
//
// A sliver cell's u-lines at v = 0, 1/2, 1 (those of positive length): start, unit
// direction, length; set up once per cell.
struct AlongLines {
  Eigen::Vector3d o[3], eu[3];
  double length[3];
  int n = 0;
};
AlongLines along_lines(const PatchGeom& frame) {
  AlongLines lines;
  const Eigen::Vector3d o0 = frame.p[0], e0 = frame.p[1], e1 = frame.p[2];
  const Eigen::Vector3d o1 = frame.n == 3 ? o0 : frame.p[3];
  const Eigen::Vector3d starts[3] = {o0, 0.5 * (o0 + o1), o1}, ends[3] = {e0, 0.5 * (e0 + e1), e1};
  for (int k = 0; k < 3; ++k) {
    const double length = (ends[k] - starts[k]).norm();
    if (!(length > 0.0)) continue;
    lines.o[lines.n] = starts[k];
    lines.eu[lines.n] = (ends[k] - starts[k]) / length;
    lines.length[lines.n++] = length;
  }
  return lines;
}
// The distance to the line roots of the edge [p, q] (the ends' distances are the caller's).
double line_root_distance(const AlongLines& lines, const Eigen::Vector3d& p,
                          const Eigen::Vector3d& q) {
  double dist = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d e = q - p;
  for (int k = 0; k < lines.n; ++k) {
    const Eigen::Vector3d w = lines.o[k] - p;
    const Eigen::Vector3d ue = lines.eu[k].cross(e), we = w.cross(e);
    const double A = ue.squaredNorm();
    if (!(A > 0.0)) continue;
    const double sigma = -we.dot(ue) / A, tau = we.cross(ue).norm() / A;
    const double beyond = std::max({0.0, -sigma, sigma - lines.length[k]});
    dist = std::min(dist, std::sqrt(beyond * beyond + tau * tau));
  }
  return dist;
}

}  // namespace

namespace {

// A cell's Gauss rule, its orders over `frame` (the cell in its rule's parameters):
// Σ w_u w_v jac F(x(u, v) -> b) over its nodes.
double cell_rule(const QuadCell& cell, const PatchGeom& frame, const PatchGeom& b,
                 const Eigen::Vector3d& na) {
  const GaussRule ru = gauss_legendre(cell.order_u), rv = gauss_legendre(cell.order_v);
  double G = 0.0;
  for (int u = 0; u < ru.n; ++u)
    for (int v = 0; v < rv.n; ++v) {
      double jac;
      const Eigen::Vector3d x = quadrature_point(frame, ru.x[u], rv.x[v], jac);
      G += ru.w[u] * rv.w[v] * jac * point_to_patch(x, na, b);
    }
  return G;
}

// Splits each root (a cell and its depth) by `accuracy`'s criterion, depth first, and
// hands every leaf to leaf(root, cell, frame): the index of its root, a QuadCell with its
// Gauss orders (G unset) and the cell in its rule's parameters (sliver_frame's, or itself),
// in a fixed order. A leaf of a coarser
// criterion (smaller kappa and depths) split again by a finer one gives the finer one's leaves from
// that root in the same order: the finer tree refines it.
template <typename Leaf>
void subdivide(const PatchGeom& a, const PatchGeom& b, const QuadratureAccuracy& accuracy,
               const std::vector<std::pair<PatchGeom, int>>& roots, Leaf&& leaf) {
  thread_local std::vector<PatchGeom> bfront;
  thread_local std::vector<std::pair<PatchGeom, int>> stack;
  // F(x -> b) is analytic in x away from the lines of the edges of b's part in front of a
  // (the contour it is the integral over), so distances are taken to those edges. Edges in
  // a's plane (a shared edge, a contact line) touch the domain: F stays continuous there
  // with a log-singular derivative, and cells touching them stop at accuracy.touch_depth.
  // Edges off a's plane (a patch hovering close above a) make F steep on the scale of their
  // height, and cells near them are split until small against their distance.
  front_part(b, a, bfront);
  const double in_plane = 1e-9 * (a.diameter + b.diameter);
  // Distances from the point x (to == nullptr) or the segment [x, *to] to the edges; for a
  // sliver's axis also the distance along it to the edges' singularities
  // (along_lines, line_root_distance: of the hovering edges).
  auto edge_distances = [&](const Eigen::Vector3d& x, const Eigen::Vector3d* to,
                            const PatchGeom* frame, double& touching, double& hovering,
                            double& along) {
    touching = hovering = along = std::numeric_limits<double>::infinity();
    AlongLines lines;
    if (frame) lines = along_lines(*frame);
    for (const PatchGeom& t : bfront) {
      double ends[4];  // the corners' distances from the axis (each shared by two edges)
      if (frame)
        for (int k = 0; k < t.n; ++k) ends[k] = segment_distance(x, *to, t.p[k], t.p[k]);
      for (int k = 0; k < t.n; ++k) {
        const Eigen::Vector3d& p = t.p[k];
        const Eigen::Vector3d& q = t.p[(k + 1) % t.n];
        const double dist = segment_distance(x, to ? *to : x, p, q);
        const bool flat = std::abs(a.normal.dot(p - a.p[0])) <= in_plane &&
                          std::abs(a.normal.dot(q - a.p[0])) <= in_plane;
        (flat ? touching : hovering) = std::min(flat ? touching : hovering, dist);
        if (!flat && frame)
          along = std::min({along, ends[k], ends[(k + 1) % t.n], line_root_distance(lines, p, q)});
      }
    }
  };
  for (size_t r = 0; r < roots.size(); ++r) {
    stack.assign(1, roots[r]);
    while (!stack.empty()) {
      const auto [g, depth] = stack.back();
      stack.pop_back();
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (int k = 0; k < g.n; ++k) centre += g.p[k] / g.n;
      double h = 0.0, radius = 0.0;
      for (int i = 0; i < g.n; ++i) {
        radius = std::max(radius, (g.p[i] - centre).norm());
        for (int j = i + 1; j < g.n; ++j) h = std::max(h, (g.p[i] - g.p[j]).norm());
      }
      // Lower bounds on the distance from the cell to the edges: from its bounding sphere,
      // or for a sliver from its axis (sliver_axis).
      PatchGeom frame;
      double along = h, across = h;
      const bool sliver = sliver_frame(g, frame, along, across);
      double touching, hovering, hover_along;
      if (sliver) {
        Eigen::Vector3d from, to;
        double across_radius;
        sliver_axis(frame, from, to, across_radius);
        edge_distances(from, &to, &frame, touching, hovering, hover_along);
        touching -= across_radius;
        hovering -= across_radius;
        hover_along -= across_radius;
      } else {
        edge_distances(centre, nullptr, nullptr, touching, hovering, hover_along);
        touching -= radius;
        hovering -= radius;
        hover_along = hovering;
      }
      // A sliver is split when its length is long against the distance to the singularities
      // along it (hover_along) or its width against the hovering edges' distance; any
      // other cell when its diameter is long against that distance.
      const bool hover_split =
          sliver ? hover_along < accuracy.kappa * h || hovering < accuracy.kappa * across
                 : hovering < accuracy.kappa * h;
      if ((hover_split && depth < accuracy.max_depth) ||
          (touching < accuracy.kappa * h && depth < accuracy.touch_depth)) {
        PatchGeom children[4];
        const int count = split(g, children);
        for (int k = 0; k < count; ++k) stack.push_back({children[k], depth + 1});
        continue;
      }
      // A sliver gets the order its width needs across it (sliver_frame), any other cell
      // one order both ways. Along a sliver the order is that of twice its length: d is
      // its axis's distance, the true one to within its width, where a square cell's is its
      // centre's less its radius, so that a sliver cell kept at length / d <= 2 is up to
      // twice as long against its true distance as any square one (50 mm from a strip 3 mm
      // aside, order 6 left 2.2e-6 of G; order 8: 4e-8, HybridQuadrature.SliverStrips...).
      const double d = std::min(touching, hovering), d_along = std::min(touching, hover_along);
      leaf(r,
           QuadCell{g, 0.0, cell_order(sliver ? 2.0 * along : along, d_along, accuracy.extra),
                    cell_order(across, d, accuracy.extra), sliver, depth},
           sliver ? frame : g);
    }
  }
}

// The roots of a's partition: the pieces of its front part (front_part), at depth 0.
const std::vector<std::pair<PatchGeom, int>>& front_roots(const PatchGeom& a, const PatchGeom& b) {
  thread_local std::vector<PatchGeom> pieces;
  thread_local std::vector<std::pair<PatchGeom, int>> roots;
  front_part(a, b, pieces);
  roots.clear();
  for (const PatchGeom& piece : pieces) roots.push_back({piece, 0});
  return roots;
}

}  // namespace

double integrate_unoccluded(const PatchGeom& a, const PatchGeom& b,
                            const QuadratureAccuracy& accuracy, std::vector<QuadCell>& cells) {
  cells.clear();
  double total = 0.0;
  subdivide(a, b, accuracy, front_roots(a, b), [&](size_t, QuadCell cell, const PatchGeom& frame) {
    cell.G = cell_rule(cell, frame, b, a.normal);
    if (cell.G > 0.0 && cell.g.area > 0.0) {
      total += cell.G;
      cells.push_back(cell);
    }
  });
  return total;
}

double preview_unoccluded(const PatchGeom& a, const PatchGeom& b, std::vector<QuadCell>& cells) {
  cells.clear();
  double total = 0.0;
  subdivide(a, b, kPreviewAccuracy, front_roots(a, b),
            [&](size_t, QuadCell cell, const PatchGeom& frame) {
              if (!(cell.g.area > 0.0)) return;
              double jac;
              const Eigen::Vector3d x = quadrature_point(frame, 0.5, 0.5, jac);
              cell.G = jac * point_to_patch(x, a.normal, b);
              total += cell.G;
              cells.push_back(cell);
            });
  return total;
}

double integrate_cells(const PatchGeom& a, const PatchGeom& b, const std::vector<QuadCell>& cells,
                       std::vector<double>* exact) {
  if (exact) exact->assign(cells.size(), 0.0);
  double total = 0.0;
  // Every preview cell is a root (b's front part and the criterion set up once per pair).
  thread_local std::vector<std::pair<PatchGeom, int>> roots;
  roots.clear();
  for (const QuadCell& cell : cells) roots.push_back({cell.g, cell.depth});
  subdivide(a, b, kEstimatorAccuracy, roots,
            [&](size_t c, const QuadCell& cell, const PatchGeom& frame) {
              const double G = cell_rule(cell, frame, b, a.normal);
              if (G > 0.0 && cell.g.area > 0.0) {
                if (exact) (*exact)[c] += G;
                total += G;
              }
            });
  return total;
}

double cell_distance_bound(const PatchGeom& cell, const PatchGeom& b) {
  PatchGeom frame;
  double along, across;
  if (sliver_frame(cell, frame, along, across)) {
    Eigen::Vector3d from, to;
    double across_radius;
    sliver_axis(frame, from, to, across_radius);
    double dist = std::min(distance_to_patch(from, b), distance_to_patch(to, b));
    for (int k = 0; k < b.n; ++k)
      dist = std::min(dist, segment_distance(from, to, b.p[k], b.p[(k + 1) % b.n]));
    return dist - across_radius;
  }
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int k = 0; k < cell.n; ++k) centre += cell.p[k] / cell.n;
  double radius = 0.0;
  for (int k = 0; k < cell.n; ++k) radius = std::max(radius, (cell.p[k] - centre).norm());
  return distance_to_patch(centre, b) - radius;
}

}  // namespace lambert::ff
