#include "geometry/formfactors/kernels.hpp"

#include <algorithm>

#include "core/error.hpp"

namespace lambert::ff {

std::vector<PatchGeom> patch_geometry(const PatchMesh& mesh) {
  std::vector<PatchGeom> out(mesh.patches.size());
  for (size_t i = 0; i < out.size(); ++i) {
    const Patch& p = mesh.patches[i];
    PatchGeom& g = out[i];
    g.n = p.vertex_count;
    for (int k = 0; k < g.n; ++k) g.p[k] = mesh.vertices[p.vertices[k]];
    if (g.n == 3) g.p[3] = g.p[2];
    g.normal = p.normal;
    g.centroid = p.centroid;
    g.area = p.area;
    for (int a = 0; a < g.n; ++a)
      for (int b = a + 1; b < g.n; ++b) g.diameter = std::max(g.diameter, (g.p[a] - g.p[b]).norm());
    g.warp = quad_warp(g.p, g.n, g.normal);
    // Rounding of a meshed grid leaves a rectangle's opposite sides equal to ~1e-16 of its
    // size; within 1e-12 the bilinear map's J varies by under ~1e-12 of A, and the linear
    // map strays from the bilinear one by under 1e-12 of the diameter.
    g.parallelogram =
        g.n == 4 && ((g.p[2] - g.p[3]) - (g.p[1] - g.p[0])).norm() <= 1e-12 * g.diameter;
  }
  return out;
}

bool can_exchange(const PatchGeom& a, const PatchGeom& b, double eps) {
  auto front = [eps](const PatchGeom& of, const PatchGeom& plane) {
    for (int k = 0; k < of.n; ++k)
      if (plane.normal.dot(of.p[k] - plane.centroid) > eps) return true;
    return false;
  };
  return front(b, a) && front(a, b);
}

int clip_to_horizon(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, const PatchGeom& g,
                    ClippedCorners& out) {
  // Sutherland-Hodgman clip of the polygon (relative to x) against n_x · r >= 0: at most
  // kMaxClippedCorners corners (a warped quad crossed on all four edges).
  Eigen::Vector3d in[4];
  double d[4];
  bool all_front = true;
  for (int k = 0; k < g.n; ++k) {
    in[k] = g.p[k] - x;
    d[k] = nx.dot(in[k]);
    all_front = all_front && d[k] > 0.0;
  }
  if (all_front) {
    for (int k = 0; k < g.n; ++k) out[k] = in[k];
    return g.n;
  }
  int m = 0;
  for (int k = 0; k < g.n; ++k) {
    const int l = (k + 1) % g.n;
    if (d[k] > 0.0) out[m++] = in[k];
    if ((d[k] > 0.0) != (d[l] > 0.0)) {
      const double t = d[k] / (d[k] - d[l]);
      out[m++] = in[k] + t * (in[l] - in[k]);
    }
  }
  return m;
}

double contour_sum(const Eigen::Vector3d& nx, const Eigen::Vector3d* r, int m) {
  double sum = 0.0;
  for (int k = 0; k < m; ++k) sum += contour_edge_term(nx, r[k], r[k + 1 < m ? k + 1 : 0]);
  return sum;
}

double contour_factor(const Eigen::Vector3d& nx, const Eigen::Vector3d* r, int m) {
  return std::max(0.0, -contour_sum(nx, r, m) / (2.0 * M_PI));
}

double point_to_patch(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, const PatchGeom& g) {
  if (g.normal.dot(x - g.p[0]) <= 0.0) return 0.0;  // x behind the receiving patch
  ClippedCorners out;
  const int m = clip_to_horizon(x, nx, g, out);
  return m < 3 ? 0.0 : contour_factor(nx, out.data(), m);
}

namespace {
// n-point Gauss-Legendre rule on [0, 1]: nodes are the roots of P_n, found by Newton's
// iteration from the Tricomi initial guesses (converges to machine precision in < 10 steps;
// 100 are allowed); weights 1 / ((1 - t^2) P_n'(t)^2) halved for the interval [0, 1].
struct GaussTable {
  std::vector<double> x, w;
};
GaussTable make_rule(int n) {
  GaussTable t;
  for (int i = 1; i <= n; ++i) {
    double z = std::cos(M_PI * (i - 0.25) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n == 1 ? 1.0 : n * (z * p1 - p0) / (z * z - 1.0);
      const double step = p1 / dp;
      z -= step;
      if (std::abs(step) < 1e-16) break;
    }
    t.x.push_back(0.5 * (1.0 - z));
    t.w.push_back(1.0 / ((1.0 - z * z) * dp * dp));
  }
  return t;
}
}  // namespace

GaussRule gauss_legendre(int order) {
  LAMBERT_CHECK(order >= 1 && order <= kMaxGaussOrder, "unsupported Gauss-Legendre order");
  static const std::vector<GaussTable> tables = [] {
    std::vector<GaussTable> all(1);
    for (int n = 1; n <= kMaxGaussOrder; ++n) all.push_back(make_rule(n));
    return all;
  }();
  const GaussTable& t = tables[order];
  return {t.x.data(), t.w.data(), order};
}

}  // namespace lambert::ff
