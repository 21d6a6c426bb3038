// Constrained Delaunay meshing of each planar part of every surface (CGAL Mesh_2), with the
// discontinuity lines as constraints (see discontinuity.hpp).

// CGAL's assertions stay on in this file, also in Release builds: with inexact
// constructions the mesher can meet configurations it cannot handle (a split point that
// rounds off its edge next to a sliver), and without its checks it then writes through
// broken invariants (SIGSEGV, SIGFPE in GMP). With them it throws, and mesh_part falls back.
#ifdef NDEBUG
#undef NDEBUG
#endif
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/exceptions.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <tuple>

#include "core/error.hpp"
#include "core/log.hpp"
#include "geometry/mesh/discontinuity.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Delaunay_mesh_vertex_base_2<K>;
using Fb = CGAL::Delaunay_mesh_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
// Exact_predicates_tag: constraints may cross (discontinuity lines do); crossing points are
// constructed in double, every predicate is exact. Nearly coincident constraints (the same
// wedge line found from two events, a line ending on another) would make features at the
// rounding scale, which Delaunay refinement cannot resolve: clean_segments merges them first.
using CDT = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<CDT>;
using Mesher = CGAL::Delaunay_mesher_2<CDT, Criteria>;
using Point2 = K::Point_2;

// CGAL's shape bound: the squared sine of the smallest allowed angle, sin²(20.7°) = 0.125.
const double kShapeBound = std::pow(std::sin(kMinAngleDegrees * M_PI / 180.0), 2.0);
// Faces whose normals agree this closely and whose planes are this close (relative to the
// scene's size) are one planar part of a surface, meshed by one triangulation.
constexpr double kSameNormal = 1e-12;
constexpr double kSamePlane = 1e-9;
// A vertex this close (relative to the edge's length) to a crease edge lies on it.
constexpr double kOnEdge = 1e-9;
// A plane keeps D1/D2 lines of total length up to this many times its area / edge bound.
constexpr double kLineBudget = 2.0;
// Constraint features closer than this (relative to the part's extent) are merged.
constexpr double kSnap = 1e-6;

using Key3 = std::array<double, 3>;
Key3 key(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

struct Triangle {
  std::array<Eigen::Vector3d, 3> p;
  std::int32_t face = 0;
};

// A planar part of a surface: its faces and its frame (u x v = w, the front normal).
struct Part {
  std::vector<std::int32_t> faces;
  Eigen::Vector3d o, u, v, w;
  Point2 to2d(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d r = p - o;
    return {r.dot(u), r.dot(v)};
  }
};

Polygon3 face_polygon(const Scene& scene, std::int32_t f) {
  Polygon3 poly;
  for (auto v : scene.faces[f].vertices) poly.push_back(scene.vertices[v]);
  return poly;
}

std::vector<Part> planar_parts(const Scene& scene, std::int32_t surface, double scale) {
  std::vector<Part> parts;
  for (size_t f = 0; f < scene.faces.size(); ++f) {
    if (scene.faces[f].surface != surface) continue;
    const Polygon3 poly = face_polygon(scene, static_cast<std::int32_t>(f));
    if (!(polygon_area(poly) > 0.0)) continue;
    const Eigen::Vector3d n = newell_normal(poly).normalized();
    Part* part = nullptr;
    for (auto& p : parts) {
      bool coplanar = p.w.dot(n) > 1.0 - kSameNormal;
      for (const auto& c : poly)
        coplanar = coplanar && std::abs((c - p.o).dot(p.w)) <= kSamePlane * scale;
      if (coplanar) {
        part = &p;
        break;
      }
    }
    if (!part) {
      Part p;
      p.o = poly[0];
      p.w = n;
      // u along the face's first non-degenerate edge: on axis-aligned faces the frame is
      // axis-aligned and axis-aligned lines keep exact coordinates (a frame along the
      // diagonal rounds them to chains bent by 1e-16, on which CGAL's refinement failed).
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      for (size_t k = 1; k < poly.size() && !(e.squaredNorm() > 0); ++k) e = poly[k] - poly[0];
      p.u = (e - e.dot(n) * n).normalized();
      p.v = n.cross(p.u);
      parts.push_back(p);
      part = &parts.back();
    }
    part->faces.push_back(static_cast<std::int32_t>(f));
  }
  return parts;
}

// Splits segments at their crossings so that the triangulation receives segments meeting
// only at shared endpoints: each proper crossing (interiors of both) is computed in double
// and merged by `snap_point` with every point within the snap distance, so crossings of
// nearly concurrent lines become one vertex instead of a cluster at the rounding scale (on
// which CGAL's refinement built degenerate triangles and crashed); every point goes through
// `snap_point`, so no two vertices are closer than the snap distance. O(S²) for S segments
// (a few hundred per plane).
template <class Snap>
std::vector<std::array<Point2, 2>> split_at_crossings(const std::vector<std::array<Point2, 2>>& in,
                                                      Snap&& snap_point) {
  const size_t n = in.size();
  std::vector<Eigen::Vector2d> a(n), b(n);
  std::vector<Eigen::Vector2d> lo(n), hi(n);
  for (size_t i = 0; i < n; ++i) {
    a[i] = {in[i][0].x(), in[i][0].y()};
    b[i] = {in[i][1].x(), in[i][1].y()};
    lo[i] = a[i].cwiseMin(b[i]);
    hi[i] = a[i].cwiseMax(b[i]);
  }
  auto cross2 = [](const Eigen::Vector2d& x, const Eigen::Vector2d& y) {
    return x.x() * y.y() - x.y() * y.x();
  };
  std::vector<std::vector<std::pair<double, Eigen::Vector2d>>> cuts(n);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      if ((lo[i].array() > hi[j].array()).any() || (lo[j].array() > hi[i].array()).any()) continue;
      const Eigen::Vector2d d = b[i] - a[i], e = b[j] - a[j];
      const double den = cross2(d, e);
      if (den == 0.0) continue;
      const double t = cross2(a[j] - a[i], e) / den, u = cross2(a[j] - a[i], d) / den;
      if (!(t > 0.0 && t < 1.0 && u > 0.0 && u < 1.0)) continue;
      const Eigen::Vector2d p = snap_point(Point2(a[i].x() + t * d.x(), a[i].y() + t * d.y()));
      if (p != a[i] && p != b[i]) cuts[i].push_back({t, p});
      if (p != a[j] && p != b[j]) cuts[j].push_back({u, p});
    }
  std::vector<std::array<Point2, 2>> out;
  for (size_t i = 0; i < n; ++i) {
    std::sort(cuts[i].begin(), cuts[i].end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    Eigen::Vector2d from = a[i];
    cuts[i].push_back({1.0, b[i]});
    for (const auto& c : cuts[i]) {
      if (c.second == from) continue;
      out.push_back({Point2(from.x(), from.y()), Point2(c.second.x(), c.second.y())});
      from = c.second;
    }
  }
  // Merged crossings may make two pieces coincide: keep one of each.
  for (auto& s : out)
    if (std::make_pair(s[1].x(), s[1].y()) < std::make_pair(s[0].x(), s[0].y()))
      std::swap(s[0], s[1]);
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) {
    return std::make_tuple(x[0].x(), x[0].y(), x[1].x(), x[1].y()) <
           std::make_tuple(y[0].x(), y[0].y(), y[1].x(), y[1].y());
  });
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Constraint segments in a part's plane, cleaned so that no two features are closer than
// `snap` unless they coincide: endpoints within `snap` of an earlier point are that point,
// segments on one line (both ends within `snap` of it) are replaced by the chain of their
// sorted endpoints, each link kept where some segment covers it, and a segment passing
// within `snap` of another's endpoint is split there. Face edges come first, so their
// corners are kept exactly.
std::vector<std::array<Point2, 2>> clean_segments(const std::vector<std::array<Point2, 2>>& in,
                                                  double snap) {
  constexpr double kSameDirection = 1e-6;  // angle bucket (radians)
  // Points, found by a hash grid of cell `snap` (the 3 x 3 cells around a point).
  std::vector<Eigen::Vector2d> points;
  std::map<std::pair<long long, long long>, std::vector<size_t>> grid;
  auto cell = [&](double x) { return static_cast<long long>(std::floor(x / snap)); };
  auto snapped = [&](const Point2& p) {
    const Eigen::Vector2d q(p.x(), p.y());
    const long long cx = cell(q.x()), cy = cell(q.y());
    for (long long i = cx - 1; i <= cx + 1; ++i)
      for (long long j = cy - 1; j <= cy + 1; ++j) {
        const auto it = grid.find({i, j});
        if (it == grid.end()) continue;
        for (size_t k : it->second)
          if ((points[k] - q).norm() <= snap) return points[k];
      }
    grid[{cx, cy}].push_back(points.size());
    points.push_back(q);
    return q;
  };
  struct Seg {
    Eigen::Vector2d a, b;
  };
  std::vector<Seg> segs;
  for (const auto& s : in) {
    const Eigen::Vector2d a = snapped(s[0]), b = snapped(s[1]);
    if (a != b) segs.push_back({a, b});
  }
  // Lines by (direction angle in (-π/2, π/2], offset) buckets; neighbours are checked.
  auto line_of = [&](const Seg& g, double& angle, double& offset) {
    Eigen::Vector2d d = (g.b - g.a).normalized();
    if (d.x() < 0 || (d.x() == 0 && d.y() < 0)) d = -d;
    angle = std::atan2(d.y(), d.x());
    offset = Eigen::Vector2d(-d.y(), d.x()).dot(g.a);
  };
  std::map<std::pair<long long, long long>, std::vector<size_t>> lines;
  auto bucket = [&](double angle, double offset) {
    return std::make_pair(static_cast<long long>(std::floor(angle / kSameDirection)), cell(offset));
  };
  for (size_t i = 0; i < segs.size(); ++i) {
    double angle, offset;
    line_of(segs[i], angle, offset);
    lines[bucket(angle, offset)].push_back(i);
  }
  std::vector<char> used(segs.size(), 0);
  std::vector<std::array<Point2, 2>> out;
  for (size_t i = 0; i < segs.size(); ++i) {
    if (used[i]) continue;
    const Eigen::Vector2d o = segs[i].a, d = (segs[i].b - segs[i].a).normalized();
    const Eigen::Vector2d nrm(-d.y(), d.x());
    double angle, offset;
    line_of(segs[i], angle, offset);
    std::vector<size_t> group;
    auto visit = [&](double ang, double off) {
      const auto [ba, bo] = bucket(ang, off);
      for (long long x = ba - 1; x <= ba + 1; ++x)
        for (long long y = bo - 1; y <= bo + 1; ++y) {
          const auto it = lines.find({x, y});
          if (it == lines.end()) continue;
          for (size_t j : it->second) {
            if (used[j]) continue;
            if (std::abs(nrm.dot(segs[j].a - o)) > snap || std::abs(nrm.dot(segs[j].b - o)) > snap)
              continue;
            used[j] = 1;
            group.push_back(j);
          }
        }
    };
    visit(angle, offset);
    if (std::abs(angle) > M_PI / 2 - 1e-6) visit(angle > 0 ? angle - M_PI : angle + M_PI, -offset);
    std::vector<std::pair<double, Eigen::Vector2d>> ends;
    for (size_t j : group)
      for (const auto& p : {segs[j].a, segs[j].b}) ends.push_back({d.dot(p - o), p});
    std::sort(ends.begin(), ends.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    std::vector<std::pair<double, Eigen::Vector2d>> chain;
    for (const auto& e : ends)
      if (chain.empty() || e.first - chain.back().first > snap) chain.push_back(e);
    for (size_t k = 0; k + 1 < chain.size(); ++k) {
      const double mid = 0.5 * (chain[k].first + chain[k + 1].first);
      bool covered = false;
      for (size_t j : group) {
        const double ta = d.dot(segs[j].a - o), tb = d.dot(segs[j].b - o);
        covered = covered || (mid > std::min(ta, tb) && mid < std::max(ta, tb));
      }
      if (covered)
        out.push_back({Point2(chain[k].second.x(), chain[k].second.y()),
                       Point2(chain[k + 1].second.x(), chain[k + 1].second.y())});
    }
  }
  // T-junctions: split a segment whose interior passes within `snap` of an endpoint.
  std::vector<Eigen::Vector2d> ends;
  for (const auto& s : out)
    for (const auto& p : s) ends.emplace_back(p.x(), p.y());
  std::sort(ends.begin(), ends.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
  std::vector<std::array<Point2, 2>> split;
  for (const auto& s : out) {
    const Eigen::Vector2d a(s[0].x(), s[0].y()), b(s[1].x(), s[1].y());
    const Eigen::Vector2d d = b - a;
    const double len2 = d.squaredNorm();
    std::vector<std::pair<double, Eigen::Vector2d>> cuts;
    const double xlo = std::min(a.x(), b.x()) - snap, xhi = std::max(a.x(), b.x()) + snap;
    const double ylo = std::min(a.y(), b.y()) - snap, yhi = std::max(a.y(), b.y()) + snap;
    auto first = std::lower_bound(ends.begin(), ends.end(), Eigen::Vector2d(xlo, -INFINITY),
                                  [](const auto& p, const auto& q) { return p.x() < q.x(); });
    for (auto it = first; it != ends.end() && it->x() <= xhi; ++it) {
      const Eigen::Vector2d& p = *it;
      if (p.y() < ylo || p.y() > yhi || p == a || p == b) continue;
      const double t = (p - a).dot(d) / len2;
      if (t <= 0 || t >= 1 || (a + t * d - p).norm() > snap) continue;
      cuts.push_back({t, p});
    }
    std::sort(cuts.begin(), cuts.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    Eigen::Vector2d from = a;
    for (const auto& c : cuts) {
      split.push_back({Point2(from.x(), from.y()), Point2(c.second.x(), c.second.y())});
      from = c.second;
    }
    split.push_back({Point2(from.x(), from.y()), s[1]});
  }
  return split_at_crossings(split, snapped);
}

// What went short of the plan on the planes of a mesh, summed over them for one warning
// per cause (a CAD part has hundreds of planes: one line each flooded the log).
struct PlaneShortfalls {
  std::size_t stopped = 0;            ///< planes whose refinement hit the vertex budget
  std::size_t stopped_vertices = 0;   ///< the most vertices such a plane had
  std::size_t thin = 0;               ///< their triangles below the angle bound
  std::size_t triangles = 0;          ///< all their triangles
  double thinnest = 180.0;            ///< the smallest angle among them (degrees)
  std::string first_stopped;          ///< the surface of the first such plane
  std::size_t unrefined = 0;          ///< planes meshed without their lines (CGAL failed)
  std::string first_unrefined, cgal;  ///< the first such surface and CGAL's expression
};

// An angle in degrees for a log line, 2 significant digits ("0.31", "7.4").
std::string angle_text(double degrees) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g", degrees);
  return buf;
}

// The smallest angle of a triangle (degrees; 0 when degenerate).
double smallest_angle(const Point2& a, const Point2& b, const Point2& c) {
  const Eigen::Vector2d p[3] = {{CGAL::to_double(a.x()), CGAL::to_double(a.y())},
                                {CGAL::to_double(b.x()), CGAL::to_double(b.y())},
                                {CGAL::to_double(c.x()), CGAL::to_double(c.y())}};
  double smallest = 180.0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d u = p[(k + 1) % 3] - p[k], v = p[(k + 2) % 3] - p[k];
    const double d = u.norm() * v.norm();
    smallest = std::min(
        smallest, d > 0 ? std::acos(std::clamp(u.dot(v) / d, -1.0, 1.0)) * 180.0 / M_PI : 0.0);
  }
  return smallest;
}

// Triangles of one planar part, meshed by a refined constrained Delaunay triangulation.
std::vector<Triangle> triangulate_part(const Scene& scene, const Part& part, double max_edge,
                                       const std::vector<const DiscontinuitySegment*>& lines,
                                       PlaneShortfalls& shortfalls) {
  CDT cdt;
  std::map<std::pair<double, double>, Eigen::Vector3d> corners;  // exact 3-D input corners
  // Each face as triangles in 2-D, for the point-in-face tests.
  std::vector<std::vector<std::array<Point2, 3>>> face_tris;
  std::vector<std::array<Point2, 2>> segments;  // face edges first, then the lines
  for (auto f : part.faces) {
    const Polygon3 poly = face_polygon(scene, f);
    std::vector<Point2> pts;
    for (const auto& c : poly) {
      pts.push_back(part.to2d(c));
      corners.emplace(
          std::make_pair(CGAL::to_double(pts.back().x()), CGAL::to_double(pts.back().y())), c);
    }
    for (size_t k = 0; k < pts.size(); ++k) segments.push_back({pts[k], pts[(k + 1) % pts.size()]});
    std::vector<std::array<Point2, 3>> tris;
    if (poly.size() == 3)
      tris.push_back({pts[0], pts[1], pts[2]});
    else
      for (const auto& t : triangulate(poly)) tris.push_back({pts[t[0]], pts[t[1]], pts[t[2]]});
    face_tris.push_back(std::move(tris));
  }
  for (const auto* s : lines) segments.push_back({part.to2d(s->a), part.to2d(s->b)});
  double extent = 0;
  for (const auto& s : segments)
    extent = std::max({extent, std::abs(s[0].x()), std::abs(s[0].y())});
  for (const auto& s : clean_segments(segments, kSnap * std::max(extent, 1e-300))) {
    cdt.insert_constraint(s[0], s[1]);
  }
  // The face containing a point (exact orientation tests against its triangles), or -1.
  auto face_at = [&](const Point2& c) -> int {
    for (size_t f = 0; f < face_tris.size(); ++f) {
      for (const auto& t : face_tris[f]) {
        const auto o = CGAL::orientation(t[0], t[1], t[2]);
        if (o == CGAL::COLLINEAR) continue;
        if (CGAL::orientation(t[0], t[1], c) != -o && CGAL::orientation(t[1], t[2], c) != -o &&
            CGAL::orientation(t[2], t[0], c) != -o)
          return static_cast<int>(f);
      }
    }
    return -1;
  };
  auto centroid = [](CDT::Face_handle fh) {
    return CGAL::centroid(fh->vertex(0)->point(), fh->vertex(1)->point(), fh->vertex(2)->point());
  };
  // Seeds: one point in each region (faces connected across unconstrained edges) that lies
  // outside every face (holes, concavities, the rest of the convex hull); the mesher
  // refines the other regions.
  std::vector<Point2> seeds;
  std::set<CDT::Face_handle> seen;
  for (auto start : cdt.finite_face_handles()) {
    if (seen.count(start)) continue;
    const bool inside = face_at(centroid(start)) >= 0;
    if (!inside) seeds.push_back(centroid(start));
    std::vector<CDT::Face_handle> stack{start};
    seen.insert(start);
    while (!stack.empty()) {
      const auto fh = stack.back();
      stack.pop_back();
      for (int i = 0; i < 3; ++i) {
        const auto nb = fh->neighbor(i);
        if (fh->is_constrained(i) || cdt.is_infinite(nb) || seen.count(nb)) continue;
        seen.insert(nb);
        stack.push_back(nb);
      }
    }
  }
  // A vertex budget: the size bound alone needs about 2 A / (h² sin 60°) vertices; beyond
  // 16 times that (and 64 per input vertex), the refinement is chasing features at the
  // rounding scale (constraints crossing at tiny angles, self-intersecting faces), and stops
  // with a warning: the mesh is still valid and conforming, some triangles are thin.
  double budget = -1.0;  // set once the first pass has marked the domain
  bool stopped = false;
  // Two passes: the size bound alone first (no angle bound: it only splits triangles larger
  // than the bound, so it ends near the size plan's vertex count), then the angle bound.
  // Where the second pass runs out of budget (constraints at tiny angles), every triangle
  // still meets the size bound; a single pass could spend the budget on one cluster of
  // small angles and leave the rest of the plane coarse.
  Mesher mesher(cdt, Criteria(0.0, max_edge));
  mesher.set_seeds(seeds.begin(), seeds.end(), /*mark=*/false);
  mesher.init(/*domain_specified=*/false);
  for (const double shape : {0.0, kShapeBound}) {
    if (shape > 0.0) mesher.set_criteria(Criteria(shape, max_edge));
    if (budget < 0) {
      double area = 0;
      for (auto fh : cdt.finite_face_handles())
        if (fh->is_in_domain()) area += std::abs(CGAL::to_double(cdt.triangle(fh).area()));
      budget = 64.0 * static_cast<double>(cdt.number_of_vertices()) + 1000.0 +
               (max_edge > 0 ? 16.0 * 2.0 * area / (max_edge * max_edge * 0.866) : 0.0);
    }
    while (!mesher.is_refinement_done()) {
      if (static_cast<double>(cdt.number_of_vertices()) > budget) {
        stopped = true;
        break;
      }
      mesher.step_by_step_refine_mesh();
    }
  }
  if (stopped) {  // the size of the effect: how many triangles are thin, and how thin
    if (shortfalls.stopped++ == 0)
      shortfalls.first_stopped = scene.surfaces[scene.faces[part.faces[0]].surface].name;
    shortfalls.stopped_vertices =
        std::max<std::size_t>(shortfalls.stopped_vertices, cdt.number_of_vertices());
    for (auto fh : cdt.finite_face_handles()) {
      if (!fh->is_in_domain()) continue;
      const double a =
          smallest_angle(fh->vertex(0)->point(), fh->vertex(1)->point(), fh->vertex(2)->point());
      ++shortfalls.triangles;
      if (a < kMinAngleDegrees) ++shortfalls.thin;
      shortfalls.thinnest = std::min(shortfalls.thinnest, a);
    }
  }

  std::vector<Triangle> out;
  for (auto fh : cdt.finite_face_handles()) {
    if (!fh->is_in_domain()) continue;
    const int f = face_at(centroid(fh));
    if (f < 0) continue;
    Triangle t;
    t.face = part.faces[f];
    for (int k = 0; k < 3; ++k) {
      const Point2& q = fh->vertex(k)->point();
      const double x = CGAL::to_double(q.x()), y = CGAL::to_double(q.y());
      const auto it = corners.find({x, y});
      t.p[k] = it != corners.end() ? it->second : Eigen::Vector3d(part.o + x * part.u + y * part.v);
    }
    out.push_back(t);
  }
  return out;
}

// The lines a part keeps: every D0 line, then D1/D2 lines longest first while their total
// length stays within kLineBudget x (the part's area / the edge bound), the length of
// lines one edge bound apart covering the part. Each line costs
// about its length / edge bound vertices, so this keeps the mesh within a small multiple
// of the size plan's patches; tessellated
// curved blockers (a silhouette of hundreds of short edges, each casting lines onto every
// wall) otherwise made 70x the requested patches. 0 edge bound: no budget.
std::vector<const DiscontinuitySegment*> lines_within_budget(
    const Scene& scene, const Part& part, double max_edge,
    const std::vector<const DiscontinuitySegment*>& lines) {
  if (!(max_edge > 0)) return lines;
  double area = 0;
  for (auto f : part.faces) area += polygon_area(face_polygon(scene, f));
  double budget = kLineBudget * area / max_edge;
  std::vector<const DiscontinuitySegment*> sorted = lines;
  std::stable_sort(sorted.begin(), sorted.end(), [](const auto* a, const auto* b) {
    if (a->order != b->order) return a->order < b->order;
    return (a->b - a->a).squaredNorm() > (b->b - b->a).squaredNorm();
  });
  std::vector<const DiscontinuitySegment*> kept;
  for (const auto* l : sorted) {
    const double cost = (l->b - l->a).norm();
    if (l->order > 0 && cost > budget) continue;
    if (l->order > 0) budget -= cost;
    kept.push_back(l);
  }
  return kept;
}

// Triangles of one planar part: with its lines, or, where CGAL's refinement fails on them
// (an assertion inside the mesher: lines at the rounding scale of each other that the
// cleaning did not merge), without them, with a warning naming the surface. Face edges
// alone are simple polygons, which the mesher handles; if even that fails the scene is
// refused with a SceneError.
std::vector<Triangle> mesh_part(const Scene& scene, const Part& part, double max_edge,
                                const std::vector<const DiscontinuitySegment*>& lines,
                                PlaneShortfalls& shortfalls) {
  const std::string& name = scene.surfaces[scene.faces[part.faces[0]].surface].name;
  try {
    PlaneShortfalls attempt = shortfalls;  // kept only if the attempt succeeds
    std::vector<Triangle> tris = triangulate_part(scene, part, max_edge, lines, attempt);
    shortfalls = attempt;
    return tris;
  } catch (const CGAL::Failure_exception& e) {
    if (lines.empty())
      throw SceneError(scene.source + ": surface '" + name +
                       "': constrained Delaunay meshing failed (CGAL: " + e.expression() + ")");
    if (shortfalls.unrefined++ == 0) {
      shortfalls.first_unrefined = name;
      shortfalls.cgal = e.expression();
    }
  }
  try {
    return triangulate_part(scene, part, max_edge, {}, shortfalls);
  } catch (const CGAL::Failure_exception& e) {
    throw SceneError(scene.source + ": surface '" + name +
                     "': constrained Delaunay meshing failed (CGAL: " + e.expression() + ")");
  }
}

// Makes the triangles of a folded surface conforming across its creases: every vertex on a
// crease edge (one shared by faces of two planar parts) is put on the edge exactly and
// inserted into the triangles of the other side by fan splits.
void conform_creases(const Scene& scene, const std::vector<Part>& parts,
                     std::vector<Triangle>& tris) {
  if (parts.size() < 2) return;
  std::map<std::array<Key3, 2>, int> edge_part;  // an edge -> the first part holding it
  std::vector<std::array<Eigen::Vector3d, 2>> creases;
  std::map<std::array<Key3, 2>, char> is_crease;
  for (size_t pi = 0; pi < parts.size(); ++pi) {
    for (auto f : parts[pi].faces) {
      const Polygon3 poly = face_polygon(scene, f);
      for (size_t k = 0; k < poly.size(); ++k) {
        Eigen::Vector3d a = poly[k], b = poly[(k + 1) % poly.size()];
        if (key(b) < key(a)) std::swap(a, b);
        const std::array<Key3, 2> e{key(a), key(b)};
        const auto it = edge_part.emplace(e, static_cast<int>(pi));
        if (!it.second && it.first->second != static_cast<int>(pi) && !is_crease[e]) {
          is_crease[e] = 1;
          creases.push_back({a, b});
        }
      }
    }
  }
  if (creases.empty()) return;
  // Parameters of the vertices on each crease, merged across sides.
  std::vector<std::vector<double>> us(creases.size());
  std::map<Key3, std::vector<std::pair<int, double>>> on;  // vertex -> (crease, u)
  auto param = [&](size_t c, const Eigen::Vector3d& x, double& u) {
    const Eigen::Vector3d d = creases[c][1] - creases[c][0];
    u = (x - creases[c][0]).dot(d) / d.squaredNorm();
    return (x - creases[c][0] - u * d).norm() <= kOnEdge * d.norm() && u > -kOnEdge &&
           u < 1 + kOnEdge;
  };
  for (const auto& t : tris) {
    for (const auto& x : t.p) {
      for (size_t c = 0; c < creases.size(); ++c) {
        double u;
        if (param(c, x, u)) us[c].push_back(std::clamp(u, 0.0, 1.0));
      }
    }
  }
  std::vector<std::vector<Eigen::Vector3d>> points(creases.size());
  for (size_t c = 0; c < creases.size(); ++c) {
    auto& u = us[c];
    u.push_back(0.0);
    u.push_back(1.0);
    std::sort(u.begin(), u.end());
    std::vector<double> merged;
    for (double x : u)
      if (merged.empty() || x - merged.back() > kOnEdge) merged.push_back(x);
    merged.back() = 1.0;
    u = merged;
    for (double x : u)
      points[c].push_back(
          x == 0.0   ? creases[c][0]
          : x == 1.0 ? creases[c][1]
                     : Eigen::Vector3d(creases[c][0] + x * (creases[c][1] - creases[c][0])));
  }
  // Snap every vertex on a crease to its canonical point and record (crease, index).
  for (auto& t : tris) {
    for (auto& x : t.p) {
      for (size_t c = 0; c < creases.size(); ++c) {
        double u;
        if (!param(c, x, u)) continue;
        const auto it =
            std::lower_bound(us[c].begin(), us[c].end(), std::clamp(u, 0.0, 1.0) - kOnEdge);
        const int i =
            static_cast<int>(std::min<std::ptrdiff_t>(it - us[c].begin(), us[c].size() - 1));
        x = points[c][i];
        on[key(x)].push_back({static_cast<int>(c), static_cast<double>(i)});
      }
    }
  }
  // Fan-split triangles whose edge on a crease skips crease points.
  std::vector<Triangle> work = std::move(tris), done;
  while (!work.empty()) {
    Triangle t = work.back();
    work.pop_back();
    bool split = false;
    for (int k = 0; k < 3 && !split; ++k) {
      const auto ia = on.find(key(t.p[k])), ib = on.find(key(t.p[(k + 1) % 3]));
      if (ia == on.end() || ib == on.end()) continue;
      for (const auto& [ca, ua] : ia->second) {
        for (const auto& [cb, ub] : ib->second) {
          if (ca != cb || std::abs(ua - ub) <= 1.0) continue;
          const int c = ca, step = ub > ua ? 1 : -1;
          const Eigen::Vector3d opposite = t.p[(k + 2) % 3];
          for (int i = static_cast<int>(ua); i != static_cast<int>(ub); i += step)
            work.push_back({{points[c][i], points[c][i + step], opposite}, t.face});
          split = true;
          break;
        }
        if (split) break;
      }
    }
    if (!split) done.push_back(t);
  }
  tris = std::move(done);
}

}  // namespace

PatchMesh mesh_scene_constrained(const Scene& scene, double max_edge,
                                 const std::vector<DiscontinuitySegment>& constraints,
                                 const ConstrainedLimits& limits) {
  PatchMesh mesh;
  copy_surfaces(scene, mesh);
  const auto [lo, hi] = scene.bounds();
  mesh.max_edge = max_edge;
  mesh.scale = scene.faces.empty() ? 1.0 : std::max((hi - lo).norm(), 1e-300);
  std::vector<std::vector<const DiscontinuitySegment*>> by_face(scene.faces.size());
  for (const auto& s : constraints) by_face.at(s.face).push_back(&s);
  size_t lines_found = 0, lines_kept = 0, surfaces_cut = 0;
  std::string first_cut;
  PlaneShortfalls shortfalls;
  for (size_t s = 0; s < scene.surfaces.size(); ++s) {
    const auto surface = static_cast<std::int32_t>(s);
    const std::vector<Part> parts = planar_parts(scene, surface, mesh.scale);
    std::vector<Triangle> tris;
    size_t found = 0, kept = 0;
    for (const auto& part : parts) {
      std::vector<const DiscontinuitySegment*> lines;
      for (auto f : part.faces) lines.insert(lines.end(), by_face[f].begin(), by_face[f].end());
      found += lines.size();
      lines = lines_within_budget(scene, part, max_edge, lines);
      kept += lines.size();
      const auto part_tris = mesh_part(scene, part, max_edge, lines, shortfalls);
      tris.insert(tris.end(), part_tris.begin(), part_tris.end());
      const auto made = static_cast<std::int64_t>(mesh.patches.size() + tris.size());
      if (made > limits.max_patches)
        throw UsageError(
            "discontinuity meshing passed " + thousands(made) + " patches" +
            (limits.planned > 0 ? " (" + thousands(limits.planned) + " planned)" : "") +
            " on surface '" + scene.surfaces[s].name +
            "': its shadow lines meet at angles or distances too small to resolve (CAD "
            "slivers, coincident faces); mesh it without --discontinuity, or raise "
            "--patches or --max-edge");
    }
    lines_found += found;
    lines_kept += kept;
    if (kept < found && surfaces_cut++ == 0) first_cut = scene.surfaces[s].name;
    conform_creases(scene, parts, tris);
    // Weld by exact position within the surface and emit.
    std::map<Key3, std::int32_t> ids;
    const Material& mat = scene.material_of(surface);
    for (const auto& t : tris) {
      std::array<std::int32_t, 4> v{};
      for (int k = 0; k < 3; ++k) {
        const auto it = ids.emplace(key(t.p[k]), static_cast<std::int32_t>(mesh.vertices.size()));
        if (it.second) {
          mesh.vertices.push_back(t.p[k]);
          mesh.vertex_surface.push_back(surface);
        }
        v[k] = it.first->second;
      }
      if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) continue;
      Patch p = make_patch(mesh, v, 3);
      if (!(p.area > 0.0)) continue;
      const Face& face = scene.faces[t.face];
      p.rho = face.rho ? *face.rho : mat.rho;
      p.emission = mat.emission;
      p.surface = surface;
      mesh.patches.push_back(p);
    }
  }
  if (limits.warn && shortfalls.stopped > 0)
    log_warn("discontinuity meshing: stopped refining " +
             thousands(static_cast<std::int64_t>(shortfalls.stopped)) +
             (shortfalls.stopped == 1 ? " plane" : " planes") + " (the first of surface '" +
             shortfalls.first_stopped + "', the largest at " +
             thousands(static_cast<std::int64_t>(shortfalls.stopped_vertices)) +
             " vertices): constraints meet at angles or distances too small to resolve; " +
             thousands(static_cast<std::int64_t>(shortfalls.thin)) + " of their " +
             thousands(static_cast<std::int64_t>(shortfalls.triangles)) +
             " triangles are thinner than the " + std::to_string(kMinAngleDegrees).substr(0, 4) +
             " degree bound (the thinnest " + angle_text(shortfalls.thinnest) + " degrees)");
  if (limits.warn && shortfalls.unrefined > 0)
    log_warn("discontinuity meshing: CGAL could not refine the lines on " +
             thousands(static_cast<std::int64_t>(shortfalls.unrefined)) +
             (shortfalls.unrefined == 1 ? " plane" : " planes") + " (the first of surface '" +
             shortfalls.first_unrefined + "': " + shortfalls.cgal +
             "); they are meshed without them");
  if (limits.warn && lines_kept < lines_found)
    log_warn("discontinuity meshing: kept " + std::to_string(lines_kept) + " of " +
             std::to_string(lines_found) + " lines, the longest on each plane within a budget of " +
             std::to_string(kLineBudget).substr(0, 3) + " x its area / the edge bound (" +
             std::to_string(surfaces_cut) + " surfaces, first '" + first_cut +
             "'); a smaller --max-edge or more --patches keeps more");
  return mesh;
}

}  // namespace lambert
