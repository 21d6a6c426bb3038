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

// The four children of a cell: quads split at the bilinear midpoints (each child is the
// bilinear image of a quarter of the parameter square), triangles at the edge midpoints.
void split(const PatchGeom& g, PatchGeom* out) {
  auto make = [&](PatchGeom& c, std::initializer_list<Eigen::Vector3d> corners) {
    c.n = static_cast<int>(corners.size());
    int k = 0;
    for (const Eigen::Vector3d& p : corners) c.p[k++] = p;
    if (c.n == 3) c.p[3] = c.p[2];
    c.normal = g.normal;
  };
  const Eigen::Vector3d m01 = 0.5 * (g.p[0] + g.p[1]), m12 = 0.5 * (g.p[1] + g.p[2]);
  if (g.n == 3) {
    const Eigen::Vector3d m20 = 0.5 * (g.p[2] + g.p[0]);
    make(out[0], {g.p[0], m01, m20});
    make(out[1], {m01, g.p[1], m12});
    make(out[2], {m20, m12, g.p[2]});
    make(out[3], {m01, m12, m20});
  } else {
    const Eigen::Vector3d m23 = 0.5 * (g.p[2] + g.p[3]), m30 = 0.5 * (g.p[3] + g.p[0]);
    const Eigen::Vector3d c = 0.25 * (g.p[0] + g.p[1] + g.p[2] + g.p[3]);
    make(out[0], {g.p[0], m01, c, m30});
    make(out[1], {m01, g.p[1], m12, c});
    make(out[2], {c, m12, g.p[2], m23});
    make(out[3], {m30, c, m23, g.p[3]});
  }
  for (int k = 0; k < 4; ++k) {
    PatchGeom& c = out[k];
    c.area = c.n == 3 ? 0.5 * (c.p[1] - c.p[0]).cross(c.p[2] - c.p[0]).norm()
                      : 0.5 * (c.p[2] - c.p[0]).cross(c.p[3] - c.p[1]).norm();
  }
}

}  // namespace

double integrate_unoccluded(const PatchGeom& a, const PatchGeom& b,
                            const QuadratureAccuracy& accuracy, std::vector<QuadCell>& cells) {
  cells.clear();
  thread_local std::vector<PatchGeom> pieces, bfront;
  thread_local std::vector<std::pair<PatchGeom, int>> stack;
  front_part(a, b, pieces);
  // F(x -> b) is analytic in x away from the lines of the edges of b's part in front of a
  // (the contour it is the integral over), so distances are taken to those edges. Edges in
  // a's plane (a shared edge, a contact line) touch the domain: F stays continuous there
  // with a log-singular derivative, and cells touching them stop at accuracy.touch_depth.
  // Edges off a's plane (a patch hovering close above a) make F steep on the scale of their
  // height, and cells near them are split until small against their distance.
  front_part(b, a, bfront);
  const double in_plane = 1e-9 * (a.diameter + b.diameter);
  auto edge_distances = [&](const Eigen::Vector3d& x, double& touching, double& hovering) {
    touching = hovering = std::numeric_limits<double>::infinity();
    for (const PatchGeom& t : bfront)
      for (int k = 0; k < t.n; ++k) {
        const Eigen::Vector3d& p = t.p[k];
        const Eigen::Vector3d& q = t.p[(k + 1) % t.n];
        const Eigen::Vector3d e = q - p;
        const double e2 = e.squaredNorm();
        const double u = e2 > 0.0 ? std::clamp(e.dot(x - p) / e2, 0.0, 1.0) : 0.0;
        const double dist = (p + u * e - x).norm();
        const bool flat = std::abs(a.normal.dot(p - a.p[0])) <= in_plane &&
                          std::abs(a.normal.dot(q - a.p[0])) <= in_plane;
        (flat ? touching : hovering) = std::min(flat ? touching : hovering, dist);
      }
  };
  double total = 0.0;
  for (const PatchGeom& piece : pieces) {
    stack.assign(1, {piece, 0});
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
      double touching, hovering;
      edge_distances(centre, touching, hovering);
      touching -= radius;  // lower bounds on the distance from the cell
      hovering -= radius;
      if ((hovering < accuracy.kappa * h && depth < accuracy.max_depth) ||
          (touching < accuracy.kappa * h && depth < accuracy.touch_depth)) {
        PatchGeom children[4];
        split(g, children);
        for (const PatchGeom& c : children) stack.push_back({c, depth + 1});
        continue;
      }
      const GaussRule rule = gauss_legendre(cell_order(h, std::min(touching, hovering), accuracy.extra));
      QuadCell cell{g, 0.0};
      for (int u = 0; u < rule.n; ++u)
        for (int v = 0; v < rule.n; ++v) {
          double jac;
          const Eigen::Vector3d x = quadrature_point(g, rule.x[u], rule.x[v], jac);
          cell.G += rule.w[u] * rule.w[v] * jac * point_to_patch(x, a.normal, b);
        }
      if (cell.G > 0.0 && g.area > 0.0) {
        total += cell.G;
        cells.push_back(cell);
      }
    }
  }
  return total;
}

}  // namespace lambert::ff
