#include "geometry/visibility/shadow.hpp"

#include <CGAL/Boolean_set_operations_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Polygon_set_2.h>
#include <CGAL/convex_hull_2.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using Point2 = K::Point_2;
using Polygon2 = CGAL::Polygon_2<K>;
using PolygonWithHoles2 = CGAL::Polygon_with_holes_2<K>;
using PolygonSet2 = CGAL::Polygon_set_2<K>;

// Blocker points closer than this (relative) to x's height above the emitter's plane or to
// the plane itself are dropped before projection (see the header's limits).
constexpr double kSlabMargin = 1e-12;
// Relative widening of the view pyramid (see visible_emitter_region).
constexpr double kPyramidMargin = 1e-6;

// The emitter's plane (polygon.hpp's frame) with exact 2-D coordinates.
struct ExactFrame {
  Eigen::Vector3d o, u, v, w;
  Point2 to2d(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d r = p - o;
    return {r.dot(u), r.dot(v)};
  }
  Eigen::Vector3d to3d(const Point2& q) const {
    return o + CGAL::to_double(q.x()) * u + CGAL::to_double(q.y()) * v;
  }
};

ExactFrame frame_of(const Polygon3& poly) {
  const PlaneFrame f = plane_frame(poly);
  return {f.o, f.u, f.v, f.w};
}

// A simple counter-clockwise polygon from points (duplicates removed); when rounding made
// the loop non-simple, its convex hull (the input loops here are convex up to rounding).
// Empty when degenerate (collinear).
Polygon2 simple_ccw(std::vector<Point2> pts) {
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  while (pts.size() > 1 && pts.front() == pts.back()) pts.pop_back();
  if (pts.size() < 3) return {};
  Polygon2 poly(pts.begin(), pts.end());
  if (!poly.is_simple()) {
    std::vector<Point2> hull;
    CGAL::convex_hull_2(pts.begin(), pts.end(), std::back_inserter(hull));
    poly = Polygon2(hull.begin(), hull.end());
    if (poly.size() < 3) return {};
  }
  const auto orientation = poly.orientation();
  if (orientation == CGAL::COLLINEAR) return {};
  if (orientation == CGAL::CLOCKWISE) poly.reverse_orientation();
  return poly;
}

// Sutherland-Hodgman clip of a convex polygon to f(p) >= 0 for an affine f.
template <class F>
Polygon3 clip(const Polygon3& in, F f) {
  Polygon3 out;
  for (size_t k = 0; k < in.size(); ++k) {
    const Eigen::Vector3d& a = in[k];
    const Eigen::Vector3d& b = in[(k + 1) % in.size()];
    const double fa = f(a), fb = f(b);
    if (fa >= 0.0) out.push_back(a);
    if ((fa >= 0.0) != (fb >= 0.0)) out.push_back(a + (fa / (fa - fb)) * (b - a));
  }
  return out;
}

// A planar polygon as a set in the frame's plane: itself when simple, else the union of its
// ear-clipping triangles.
PolygonSet2 polygon_set(const Polygon3& poly, const ExactFrame& f) {
  std::vector<Point2> pts;
  for (const auto& p : poly) pts.push_back(f.to2d(p));
  Polygon2 simple(pts.begin(), pts.end());
  if (simple.size() >= 3 && simple.is_simple() && simple.orientation() != CGAL::COLLINEAR) {
    if (simple.orientation() == CGAL::CLOCKWISE) simple.reverse_orientation();
    return PolygonSet2(simple);
  }
  PolygonSet2 set;
  std::vector<Polygon2> tris;
  for (const auto& t : triangulate(poly)) {
    Polygon2 tri = simple_ccw({pts[t[0]], pts[t[1]], pts[t[2]]});
    if (!tri.is_empty()) tris.push_back(tri);
  }
  set.join(tris.begin(), tris.end());
  return set;
}

}  // namespace

std::vector<Polygon3> visible_emitter_region(const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                                             const Polygon3& emitter,
                                             const std::vector<Polygon3>& blockers) {
  if (emitter.size() < 3 || !(polygon_area(emitter) > 0.0)) return {};
  const ExactFrame f = frame_of(emitter);
  const double dx = (x - f.o).dot(f.w);  // x's height above the emitter's front side
  // x within rounding of the emitter's plane sees it edge-on (factor 0); projections from it
  // would divide by rounding noise (a patch touching the emitter's plane along an edge puts
  // refined quadrature points there). The rounding of dx is relative to the coordinates'
  // magnitude, so the tolerance is too (ff::kPlaneEps, the one plane epsilon).
  const double plane_tol = ff::kPlaneEps * (x.norm() + f.o.norm() + polygon_extent(emitter));
  if (!(dx > plane_tol)) return {};
  PolygonSet2 visible = polygon_set(emitter, f);

  // The horizon: emitter points y with n . (y - x) > 0, the half-plane a + b s + c t > 0.
  // Corners within plane_tol of x's tangent plane count as on it: an emitter sharing an edge
  // with x's surface (a wall and the floor) has corners there whose computed height is
  // rounding noise of either sign, and cutting along that noise put a corner at an
  // arbitrary point of the shared edge. What lies behind such corners is a sliver on
  // which cos θ_x <= plane_tol / distance, far below the factor's rounding.
  const double a = n.dot(f.o - x), b = n.dot(f.u), c = n.dot(f.v);
  double lo_val = INFINITY, hi_val = -INFINITY, extent = 0.0;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& p : emitter) {
    const Eigen::Vector2d q((p - f.o).dot(f.u), (p - f.o).dot(f.v));
    const double val = n.dot(p - x);
    lo_val = std::min(lo_val, val);
    hi_val = std::max(hi_val, val);
    centre += q / static_cast<double>(emitter.size());
  }
  for (const auto& p : emitter)
    extent =
        std::max(extent, (Eigen::Vector2d((p - f.o).dot(f.u), (p - f.o).dot(f.v)) - centre).norm());
  if (hi_val <= plane_tol) return {};  // behind x's horizon, or on it within rounding
  if (lo_val < -plane_tol) {
    // A rectangle covering the positive side of the line within the emitter's disc.
    const Eigen::Vector2d normal = Eigen::Vector2d(b, c).normalized();
    const double g = std::hypot(b, c);
    const Eigen::Vector2d foot = centre - ((a + b * centre.x() + c * centre.y()) / g) * normal;
    const Eigen::Vector2d dir(-normal.y(), normal.x());
    const double D = 4.0 * extent + (foot - centre).norm();
    std::vector<Point2> box;
    for (const Eigen::Vector2d& q :
         {Eigen::Vector2d(foot - D * dir), Eigen::Vector2d(foot + D * dir),
          Eigen::Vector2d(foot + D * dir + D * normal),
          Eigen::Vector2d(foot - D * dir + D * normal)})
      box.emplace_back(q.x(), q.y());
    const Polygon2 half = simple_ccw(box);
    if (half.is_empty()) return {};
    visible.intersection(half);
  }

  // The view pyramid from x through the emitter's convex hull: blocker parts outside it
  // hide nothing, and clipping to it keeps the projections within the hull (unclipped,
  // points near x's height would project arbitrarily far, and their rounding with them).
  std::vector<Point2> corners2;
  for (const auto& p : emitter) corners2.push_back(f.to2d(p));
  std::vector<Point2> hull;
  CGAL::convex_hull_2(corners2.begin(), corners2.end(), std::back_inserter(hull));
  std::vector<Eigen::Vector3d> side_normals;  // inward: n . (p - x) >= 0 inside
  Eigen::Vector3d inside = Eigen::Vector3d::Zero();
  for (const auto& q : hull) inside += f.to3d(q) / static_cast<double>(hull.size());
  // The pyramid is widened by kPyramidMargin about the hull's centre, so that a blocker that
  // hides the whole emitter projects onto a region containing it strictly (exactly 0 in
  // the umbra, no rounding sliver along the hull's edges).
  auto widened = [&](const Point2& q) -> Eigen::Vector3d {
    return inside + (1.0 + kPyramidMargin) * (f.to3d(q) - inside);
  };
  for (size_t k = 0; k < hull.size(); ++k) {
    const Eigen::Vector3d ra = widened(hull[k]) - x, rb = widened(hull[(k + 1) % hull.size()]) - x;
    const Eigen::Vector3d nk = ra.cross(rb);
    side_normals.push_back(nk.dot(inside - x) >= 0 ? nk : Eigen::Vector3d(-nk));
  }

  // Project every blocker triangle's part inside the pyramid, between x's height and the
  // emitter's plane.
  std::vector<Polygon2> shadows;
  const double lo = kSlabMargin * dx, hi = dx * (1.0 - kSlabMargin);
  auto height = [&](const Eigen::Vector3d& p) { return (p - f.o).dot(f.w); };
  for (const auto& blocker : blockers) {
    if (blocker.size() < 3) continue;
    std::vector<Polygon3> pieces;
    // Convex blockers are clipped whole: triangulated, the rounding of the two projections
    // of a shared diagonal left visible slivers of ~1e-16 area along it inside the emitter.
    if (blocker.size() == 3 || is_convex(blocker)) {
      pieces.push_back(blocker);
    } else {
      for (const auto& t : triangulate(blocker))
        pieces.push_back({blocker[t[0]], blocker[t[1]], blocker[t[2]]});
    }
    for (const auto& tri : pieces) {
      Polygon3 part = clip(tri, [&](const Eigen::Vector3d& p) { return height(p) - lo; });
      if (part.size() >= 3)
        part = clip(part, [&](const Eigen::Vector3d& p) { return hi - height(p); });
      for (size_t k = 0; k < side_normals.size() && part.size() >= 3; ++k)
        part = clip(part, [&](const Eigen::Vector3d& p) { return side_normals[k].dot(p - x); });
      if (part.size() < 3) continue;
      // The clips keep every height <= hi up to rounding: the denominator is bounded below
      // by dx - hi = kSlabMargin dx > 0, so every projection is finite.
      std::vector<Point2> pts;
      for (const auto& p : part)
        pts.push_back(f.to2d(x + (p - x) * (dx / std::max(dx - height(p), dx - hi))));
      Polygon2 shadow = simple_ccw(pts);
      if (!shadow.is_empty()) shadows.push_back(std::move(shadow));
    }
  }
  if (!shadows.empty()) {
    PolygonSet2 hidden;
    hidden.join(shadows.begin(), shadows.end());
    visible.difference(hidden);
  }

  std::vector<PolygonWithHoles2> parts;
  visible.polygons_with_holes(std::back_inserter(parts));
  std::vector<Polygon3> loops;
  auto add_loop = [&](const Polygon2& loop) {
    Polygon3 out;
    for (auto it = loop.vertices_begin(); it != loop.vertices_end(); ++it)
      out.push_back(f.to3d(*it));
    loops.push_back(std::move(out));
  };
  for (const auto& part : parts) {
    add_loop(part.outer_boundary());
    for (auto h = part.holes_begin(); h != part.holes_end(); ++h) add_loop(*h);
  }
  return loops;
}

double shadowed_point_factor(const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                             const Polygon3& emitter, const std::vector<Polygon3>& blockers) {
  double sum = 0.0;
  std::vector<Eigen::Vector3d> r;
  for (const auto& loop : visible_emitter_region(x, n, emitter, blockers)) {
    r.clear();
    for (const auto& p : loop) r.push_back(p - x);
    sum += ff::contour_sum(n, r.data(), static_cast<int>(r.size()));
  }
  return std::max(0.0, -sum / (2.0 * M_PI));
}

}  // namespace lambert
