#include "geometry/polygon.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/error.hpp"

namespace lambert {
namespace {
// Newell's normal of the polygon scaled by 2^-e, where 2^e bounds its corners' offsets
// from the first corner: the cross products stay near 1 whatever the coordinates'
// magnitude (1e150 would square to infinity), and scaling by a power of two is exact, so
// for ordinary coordinates the result is bitwise the unscaled one times 2^-2e.
Eigen::Vector3d scaled_newell(const std::vector<Eigen::Vector3d>& poly, int& e) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  e = 0;
  const size_t m = poly.size();
  if (m < 3) return n;
  double big = 0.0;
  for (const auto& p : poly) big = std::max(big, (p - poly[0]).cwiseAbs().maxCoeff());
  if (!(big > 0.0) || !std::isfinite(big)) return n;
  std::frexp(big, &e);
  // Sum of (p_k - p_0) x (p_{k+1} - p_0): exact for planar polygons, relative to a vertex
  // to avoid cancellation far from the origin.
  auto at = [&](size_t k) -> Eigen::Vector3d {
    return (poly[k] - poly[0]).unaryExpr([e](double x) { return std::ldexp(x, -e); });
  };
  for (size_t k = 1; k + 1 < m; ++k) n += at(k).cross(at(k + 1));
  return n;
}
}  // namespace

Eigen::Vector3d newell_normal(const std::vector<Eigen::Vector3d>& poly) {
  int e = 0;
  const Eigen::Vector3d n = scaled_newell(poly, e);
  return n.unaryExpr([e](double x) { return std::ldexp(x, 2 * e); });
}

double polygon_area(const std::vector<Eigen::Vector3d>& poly) {
  int e = 0;
  const double half = 0.5 * scaled_newell(poly, e).norm();
  return std::ldexp(half, 2 * e);
}

double planarity_deviation(const std::vector<Eigen::Vector3d>& poly) {
  if (poly.size() <= 3) return 0.0;
  int e = 0;
  const Eigen::Vector3d n = scaled_newell(poly, e);
  if (n.norm() == 0.0) return 0.0;
  const Eigen::Vector3d u = n.normalized();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : poly) mean += p;
  mean /= static_cast<double>(poly.size());
  double dev = 0.0;
  for (const auto& p : poly) dev = std::max(dev, std::abs(u.dot(p - mean)));
  return dev;
}

double polygon_diameter(const std::vector<Eigen::Vector3d>& poly) {
  double d = 0.0;
  for (size_t a = 0; a < poly.size(); ++a)
    for (size_t b = a + 1; b < poly.size(); ++b) d = std::max(d, (poly[a] - poly[b]).norm());
  return d;
}

double polygon_extent(const std::vector<Eigen::Vector3d>& poly) {
  if (poly.empty()) return 0.0;
  Eigen::Vector3d lo = poly[0], hi = poly[0];
  for (const auto& p : poly) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).stableNorm();
}

namespace {
// 2D projection of the polygon onto the plane orthogonal to its normal's dominant axis,
// oriented so that the polygon is counter-clockwise in 2D.
std::vector<Eigen::Vector2d> project(const std::vector<Eigen::Vector3d>& poly) {
  int e = 0;
  const Eigen::Vector3d n = scaled_newell(poly, e);
  int axis = 0;
  n.cwiseAbs().maxCoeff(&axis);
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  const bool flip = n[axis] < 0;
  std::vector<Eigen::Vector2d> out;
  out.reserve(poly.size());
  for (const auto& p : poly) out.emplace_back(flip ? p[b] : p[a], flip ? p[a] : p[b]);
  return out;
}

double cross2(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}
}  // namespace

bool is_convex(const std::vector<Eigen::Vector3d>& poly) {
  const auto p = project(poly);
  const size_t m = p.size();
  for (size_t k = 0; k < m; ++k) {
    if (cross2(p[k], p[(k + 1) % m], p[(k + 2) % m]) <= 0.0) return false;
  }
  return true;
}

std::vector<std::array<int, 3>> triangulate(const std::vector<Eigen::Vector3d>& poly) {
  std::vector<std::array<int, 3>> tris;
  const int m = static_cast<int>(poly.size());
  if (m > 3 && is_convex(poly)) {
    // Ear clipping of a strictly convex polygon clips corner 0, 1, 2, ... in turn (each is
    // an ear with nothing inside): the fan from the last corner, in that order, in O(n).
    for (int k = 0; k + 4 <= m; ++k) tris.push_back({m - 1, k, k + 1});
    tris.push_back({m - 3, m - 2, m - 1});
    return tris;
  }
  const auto p = project(poly);
  if (m > kEarClippingCorners) {
    if (auto cdt = triangulate_simple(p)) return std::move(*cdt);
    if (m > 2000)
      throw SceneError("a face of " + std::to_string(m) +
                       " corners is not a simple polygon (repeated corners or crossing edges)");
  }
  std::vector<int> idx(poly.size());
  for (size_t k = 0; k < idx.size(); ++k) idx[k] = static_cast<int>(k);
  auto inside = [&](int a, int b, int c, int q) {
    return cross2(p[a], p[b], p[q]) >= 0 && cross2(p[b], p[c], p[q]) >= 0 &&
           cross2(p[c], p[a], p[q]) >= 0;
  };
  size_t guard = 0;
  while (idx.size() > 3 && guard++ < 10 * poly.size() * poly.size()) {
    bool clipped = false;
    for (size_t k = 0; k < idx.size(); ++k) {
      const int a = idx[(k + idx.size() - 1) % idx.size()], b = idx[k],
                c = idx[(k + 1) % idx.size()];
      if (cross2(p[a], p[b], p[c]) <= 0.0) continue;  // reflex or degenerate corner
      bool ear = true;
      for (int q : idx) {
        if (q != a && q != b && q != c && inside(a, b, c, q)) {
          ear = false;
          break;
        }
      }
      if (!ear) continue;
      tris.push_back({a, b, c});
      idx.erase(idx.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
      break;
    }
    if (!clipped) break;  // numerically degenerate: fall back to a fan below
  }
  for (size_t k = 1; k + 1 < idx.size(); ++k) tris.push_back({idx[0], idx[k], idx[k + 1]});
  return tris;
}

PlaneFrame plane_frame(const std::vector<Eigen::Vector3d>& poly) {
  PlaneFrame f;
  f.o = poly[0];
  f.w = newell_normal(poly).normalized();
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  for (size_t k = 1; k < poly.size(); ++k)
    if ((poly[k] - poly[0]).squaredNorm() > e.squaredNorm()) e = poly[k] - poly[0];
  f.u = (e - e.dot(f.w) * f.w).normalized();
  f.v = f.w.cross(f.u);
  return f;
}

bool is_degenerate_polygon(const std::vector<Eigen::Vector3d>& poly) {
  if (poly.size() < 3) return true;
  const double extent = polygon_extent(poly);
  return polygon_area(poly) <= kDegenerateRelArea * extent * extent;
}

}  // namespace lambert
