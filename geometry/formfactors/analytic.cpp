#include "geometry/formfactors/analytic.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <boost/container/small_vector.hpp>
#include <cmath>
#include <queue>

#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/visibility/shadow.hpp"

namespace lambert::ff {
namespace {

// The partition of a along the event segments, a CGAL constrained Delaunay triangulation:
// first with exact predicates and the constraints' crossings rounded to double (a third of
// the time of the exact GMP rational crossings on a room), which suffices for --ff-tol down
// to ~1e-7; a pair that does not converge so (a 4-box room's floor and ceiling at 1e-8 ran
// out of its budget: cells cut off their event lines by rounding fail their pattern check
// cell after cell) is done again with exact crossings (analytic_pair_G).
using RoundedCDT =
    CGAL::Constrained_Delaunay_triangulation_2<CGAL::Exact_predicates_inexact_constructions_kernel,
                                               CGAL::Default, CGAL::Exact_predicates_tag>;
using ExactCDT =
    CGAL::Constrained_Delaunay_triangulation_2<CGAL::Exact_predicates_exact_constructions_kernel,
                                               CGAL::Default, CGAL::Exact_intersections_tag>;

// Gauss-Legendre orders per direction of a triangle's two rules (the value is the low one's,
// the estimate their difference). On an analytic integrand the order-6 rule's error is
// about (h/2d)^4 times the order-4 rule's, so the difference is the order-4 error to a few
// per cent for cells well below the size of their distance to b, which the event cells of
// an obstructed pair are and refinement ensures. 4/6 (52 points) rather than 5/8 (89): a
// room's pairs meet --ff-tol 1e-4..1e-6 in their initial cells, so the rule's cost per cell
// is the cost; 3/5 fell outside ErrorEstimateIsCalibrated's 5 % (estimates > 10x the error
// at 1e-9, where the order-5 rule's own error is not negligible).
constexpr int kLowOrder = 4;
constexpr int kHighOrder = 6;
// Rounding floor of a pair's error estimate, relative to G: the contour formula and the
// visible pieces' rounded corners are good to ~1e-15 relative per point, and a sum of cells
// cannot be trusted below ~10x that (so --tol below it is met at the floor, not chased).
constexpr double kRoundingFloor = 1e-14;
// Lengths relative to b's size: a blocker corner within kMatchTol of a patch's plane stands
// on it; event segments closer than kSameTol are the same.
constexpr double kMatchTol = 1e-9;
constexpr double kSameTol = 1e-12;
// Verification of a cell's pattern against the point factor from the blockers themselves
// (visible_pieces at the check point), relative to the unoccluded
// point factor: a change of combinatorics between the centroid and a check point changes the
// factor by far more (the check points sit a few per cent of the cell inside its corners).
constexpr double kVerifyTol = 1e-10;
// Check points are the cell's corners moved this fraction towards its centroid.
constexpr double kCheckInset = 0.05;
// Event segments closer than this to a singular point (the line through v and the edge runs
// parallel to a's plane) are cut there, relative to the edge's parameter.
constexpr double kParamMargin = 1e-9;
// Event segments a pair's partition takes at most: a CDT of k crossing segments has O(k²)
// cells, each classified at four points. Beyond it, the blocker-blocker events are left to
// refinement first, then all.
constexpr size_t kMaxEvents = 400;
// Point factors computed from the blockers directly (visible_pieces: ~1-20 us each, growing
// with the blockers) a pair may spend, beside the budget on all point factors.
constexpr std::int64_t kMaxDirectEvaluations = 400000;

using Frame = PlaneFrame;

Frame frame_of(const Polygon3& p) { return plane_frame(p); }

// The part of a convex polygon with height >= 0 above f's plane (Sutherland-Hodgman).
Polygon3 clip_front(const Polygon3& in, const Frame& f) {
  Polygon3 out;
  for (size_t k = 0; k < in.size(); ++k) {
    const Eigen::Vector3d& a = in[k];
    const Eigen::Vector3d& b = in[(k + 1) % in.size()];
    const double ha = f.height(a), hb = f.height(b);
    if (ha >= 0.0) out.push_back(a);
    if ((ha > 0.0 && hb < 0.0) || (ha < 0.0 && hb > 0.0)) out.push_back(a + (ha / (ha - hb)) * (b - a));
  }
  if (out.size() < 3 || !(polygon_area(out) > 0.0)) return {};
  return out;
}

// A line s a + t b + c = 0 in b's plane (2-D coordinates of Frame fb).
using Line = Eigen::Vector3d;

// A corner of the visible polygon by what defines it.
struct Source {
  enum Kind : int { kEmitterCorner, kBlockerCorner, kCrossing } kind;
  int i = 0, j = 0;  // corner index, or the two line indices (i < j) of a crossing
  bool operator==(const Source& o) const { return kind == o.kind && i == o.i && j == o.j; }
};
// The visible region's boundary by what defines it: its distinct corners and its directed
// edges between them. The convex pieces' edges between two pieces (the same two corners, in
// opposite directions) cancel in the contour sum term by term (bitwise: the reversed edge's
// term is the negated one), so they are left out: fewer corners and terms per point.
struct Pattern {
  std::vector<Source> sources;
  std::vector<std::array<int, 2>> edges;
  bool empty() const { return edges.empty(); }
};

// The geometry a pair's visible polygon is built from.
struct Features {
  Frame fa, fb;
  Polygon3 emitter;                      // b in front of a's plane
  std::vector<Eigen::Vector2d> emitter2;  // its corners in fb
  std::vector<Polygon3> pieces;          // blockers in front of both planes
  // Per piece, the plane (n, d) of a face of a closed convex solid, its solid on the side
  // n . y + d < 0: from a point on that side the face is a back face and hides nothing the
  // solid's front faces do not (solid_back_planes); zero for any other piece.
  std::vector<Eigen::Vector4d> back;
  // The solids: per piece its solid (-1: none), per solid its pieces and their corners, and
  // per piece and edge the piece of its solid across that edge (-1: none, or one dropped as
  // turned away from all of a: either way not a front face).
  std::vector<int> solid;
  std::vector<std::vector<int>> solids;
  std::vector<std::vector<Eigen::Vector3d>> solid_corners;
  std::vector<std::vector<int>> neighbour;
  std::vector<Eigen::Vector3d> corners;  // the pieces' distinct corners
  std::vector<std::array<int, 2>> edges;  // the pieces' distinct edges (corner indices)
  std::vector<std::vector<int>> piece_lines;  // per piece, the line of each of its edges
  double scale = 1.0;                    // b's diameter

  int line_count() const { return static_cast<int>(emitter2.size() + edges.size()); }

  // Line k at x: the emitter's edge k (fixed), or blocker edge k - nE projected from x.
  Line line(int k, const Eigen::Vector3d& x) const {
    const int ne = static_cast<int>(emitter2.size());
    if (k < ne) {
      const Eigen::Vector2d& p = emitter2[k];
      const Eigen::Vector2d d = emitter2[(k + 1) % ne] - p;
      return {d.y(), -d.x(), d.x() * p.y() - d.y() * p.x()};
    }
    const auto& e = edges[k - ne];
    const Eigen::Vector3d m = (corners[e[0]] - x).cross(corners[e[1]] - x);
    return {m.dot(fb.u), m.dot(fb.v), m.dot(fb.o - x)};
  }

  // The point of `s` at x (2-D in fb); false when it is undefined there.
  bool point(const Source& s, const Eigen::Vector3d& x, double dx, Eigen::Vector2d& out) const {
    switch (s.kind) {
      case Source::kEmitterCorner:
        out = emitter2[s.i];
        return true;
      case Source::kBlockerCorner: {
        const Eigen::Vector3d& c = corners[s.i];
        const double denom = dx - fb.height(c);
        if (!(denom > 0.0)) return false;
        out = fb.to2d(x + (c - x) * (dx / denom));
        return true;
      }
      case Source::kCrossing: {
        const Line l1 = line(s.i, x), l2 = line(s.j, x);
        const double det = l1.x() * l2.y() - l2.x() * l1.y();
        const double norm = l1.head<2>().norm() * l2.head<2>().norm();
        if (!(std::abs(det) > 1e-14 * norm)) return false;
        out = {(l1.y() * l2.z() - l2.y() * l1.z()) / det, (l2.x() * l1.z() - l1.x() * l2.z()) / det};
        return true;
      }
    }
    return false;
  }
};

// The unoccluded point factor of the emitter at x (normal n).
double unoccluded(const Features& f, const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
  std::vector<Eigen::Vector3d> r;
  for (const auto& p : f.emitter) r.push_back(p - x);
  return -contour_sum(n, r.data(), static_cast<int>(r.size())) / (2.0 * M_PI);
}

// The factor of the visible polygon given by `pattern` at x; NaN when a corner is undefined.
double pattern_factor(const Features& f, const Pattern& pattern, const Eigen::Vector3d& x,
                      const Eigen::Vector3d& n, std::vector<Eigen::Vector3d>& r) {
  const double dx = f.fb.height(x);
  r.clear();
  for (const Source& s : pattern.sources) {
    Eigen::Vector2d q;
    if (!f.point(s, x, dx, q)) return std::nan("");
    r.push_back(f.fb.to3d(q) - x);
  }
  double sum = 0.0;  // contour_sum's terms, one per edge
  for (const auto& e : pattern.edges) sum += contour_edge_term(n, r[e[0]], r[e[1]]);
  return -sum / (2.0 * M_PI);
}

// The visible part of the emitter at x as convex pieces, by floating-point half-plane
// splitting instead of polygon booleans (~100x cheaper). A convex blocker piece P hides from
// x the emitter points y whose segment to x meets P: the cone from x over P, which is the
// intersection of the half-spaces bounded by the planes through x and each edge of P (P is
// convex and x is not in its plane). On b's plane these are the half-planes of the edge
// lines (Features::line), bounded or not, whatever the corners' heights. So the visible part
// is the emitter minus each cone in turn: a convex piece Q minus the half-planes H_1..H_m is
// the union of Q ∩ !H_1, Q ∩ H_1 ∩ !H_2, ... (disjoint, convex). Every vertex made is the
// crossing of two feature lines, recorded as a Source: the pieces at a cell's centroid are
// the cell's pattern (pattern_factor evaluates them anywhere), and the pieces at a point are
// its exact point factor up to rounding (~1e-15 relative: each piece's contour sum is exact
// for the piece, and a rounding sliver contributes its own area's share).
// Cost: O(pieces x blocker edges x piece corners) per point; thread-safe.
struct PieceCorner {
  Eigen::Vector2d q;  // in fb
  Source s;
  int line = 0;  // the feature line of the edge from this corner to the next
};
// Inline storage: a piece rarely has more corners than the emitter plus a few cuts.
using Piece = boost::container::small_vector<PieceCorner, 12>;

// Pieces below this area, relative to the emitter's (diameter²), are rounding slivers of a
// split along a line through a corner; dropping them changes the point factor by their own
// area's share (below the rounding floor kRoundingFloor), and keeps umbrae exactly 0.
constexpr double kSliverArea = 1e-15;
// Pieces a point may split the emitter into before it is refused (NaN: the pair is then
// integrated crudely); far above a room's few dozen.
constexpr size_t kMaxPieces = 20000;

Source crossing(int a, int b) { return {Source::kCrossing, std::min(a, b), std::max(a, b)}; }

double piece_area(const Piece& p) {
  double a = 0.0;
  for (size_t k = 0; k < p.size(); ++k) {
    const Eigen::Vector2d& u = p[k].q;
    const Eigen::Vector2d& v = p[(k + 1) % p.size()].q;
    a += u.x() * v.y() - u.y() * v.x();
  }
  return 0.5 * std::abs(a);
}

// A corner made by line `id` lies on it: its value there is exactly 0, not rounding noise of
// either sign (which would cut a piece along its own edge and make a corner of a line with
// itself: shared edges of adjacent blocker faces give the same line twice).
double side_value(const PieceCorner& c, const Line& l, int id, int emitter_corners) {
  if (c.s.kind == Source::kCrossing && (c.s.i == id || c.s.j == id)) return 0.0;
  if (c.s.kind == Source::kEmitterCorner && id < emitter_corners &&
      (c.s.i == id || (c.s.i + emitter_corners - 1) % emitter_corners == id))
    return 0.0;
  return l.x() * c.q.x() + l.y() * c.q.y() + l.z();
}

// The part of q where l . (y, 1) >= 0 (keep) or <= 0 (!keep); `id` is l's line.
Piece clip_piece(const Piece& q, const Line& l, int id, bool keep, int emitter_corners) {
  const double sign = keep ? 1.0 : -1.0;
  Piece out;
  for (size_t k = 0; k < q.size(); ++k) {
    const PieceCorner& a = q[k];
    const PieceCorner& b = q[(k + 1) % q.size()];
    const double fa = sign * side_value(a, l, id, emitter_corners);
    const double fb = sign * side_value(b, l, id, emitter_corners);
    // A corner on l is kept and no crossing is made at it (that would repeat the corner);
    // the edge that leaves the kept part runs along l.
    if (fa >= 0.0) out.push_back({a.q, a.s, fa == 0.0 && fb < 0.0 ? id : a.line});
    if ((fa > 0.0 && fb < 0.0) || (fa < 0.0 && fb > 0.0)) {
      // Exiting: the new corner's edge runs along l; entering: along a's edge.
      const Eigen::Vector2d x = a.q + (fa / (fa - fb)) * (b.q - a.q);
      out.push_back({x, crossing(a.line, id), fa > 0.0 ? id : a.line});
    }
  }
  return out;
}

// The half-planes (line, its id, the sign inside) of the cone from x over `piece`; empty
// when x sees it edge-on (it hides no area).
using ConeSides = boost::container::small_vector<std::pair<Line, int>, 8>;
ConeSides cone_sides(const Features& f, const Polygon3& piece, const std::vector<int>& lines,
                     const Eigen::Vector3d& x) {
  ConeSides sides;
  for (size_t k = 0; k < piece.size(); ++k) {
    const Eigen::Vector3d m = (piece[k] - x).cross(piece[(k + 1) % piece.size()] - x);
    double far = 0.0;  // the corner farthest from the edge's plane through x, signed
    for (const auto& c : piece)
      if (std::abs(m.dot(c - x)) > std::abs(far)) far = m.dot(c - x);
    if (!(std::abs(far) > 1e-12 * m.norm() * f.scale)) return {};  // edge-on
    const double s = far > 0.0 ? 1.0 : -1.0;
    sides.push_back({s * Line(m.dot(f.fb.u), m.dot(f.fb.v), m.dot(f.fb.o - x)), lines[k]});
  }
  return sides;
}

// The half-planes of the cone from x over closed convex solid s: the planes through x and
// its silhouette edges (between a face turned towards x and one turned away, or on the
// open cap, which is turned away from every point of a); empty when x sees it edge-on. One
// convex cone per solid instead of one per front face: fewer cuts of the visible pieces,
// and a pattern that changes only where the silhouette does (where a face's plane meets
// a's plane: an event line).
ConeSides silhouette_sides(const Features& f, int s, const Eigen::Vector3d& x) {
  const std::vector<int>& members = f.solids[s];
  auto front = [&](int p) { return f.back[p].head<3>().dot(x) + f.back[p].w() > 0.0; };
  ConeSides sides;
  for (const int p : members) {
    if (!front(p)) continue;
    const Polygon3& piece = f.pieces[p];
    for (size_t k = 0; k < piece.size(); ++k) {
      const int nb = f.neighbour[p][k];
      if (nb >= 0 && front(nb)) continue;  // between two front faces: inside the silhouette
      const Eigen::Vector3d m = (piece[k] - x).cross(piece[(k + 1) % piece.size()] - x);
      double far = 0.0;  // the solid's corner farthest from the edge's plane through x
      for (const auto& c : f.solid_corners[s])
        if (std::abs(m.dot(c - x)) > std::abs(far)) far = m.dot(c - x);
      if (!(std::abs(far) > 1e-12 * m.norm() * f.scale)) return {};  // edge-on
      const double sign = far > 0.0 ? 1.0 : -1.0;
      sides.push_back(
          {sign * Line(m.dot(f.fb.u), m.dot(f.fb.v), m.dot(f.fb.o - x)), f.piece_lines[p][k]});
    }
  }
  return sides;
}

// The visible pieces of the emitter at x (`next` is scratch); false when there are too many.
// `units`, when given, restricts the blockers to those pieces (each a lone piece or the first
// piece of its solid, standing for the whole solid), in increasing order.
bool visible_pieces(const Features& f, const Eigen::Vector3d& x, std::vector<Piece>& out,
                    std::vector<Piece>& next, const std::vector<int>* units = nullptr) {
  const int ne = static_cast<int>(f.emitter2.size());
  Piece emitter;
  for (int k = 0; k < ne; ++k)
    emitter.push_back({f.emitter2[k], {Source::kEmitterCorner, k, 0}, k});
  const double sliver = kSliverArea * f.scale * f.scale;
  out.assign(1, emitter);
  const size_t count = units ? units->size() : f.pieces.size();
  for (size_t u = 0; u < count && !out.empty(); ++u) {
    const size_t p = units ? static_cast<size_t>((*units)[u]) : u;
    const int s = f.solid[p];
    if (s >= 0 && f.solids[s][0] != static_cast<int>(p)) continue;  // its solid's done
    const auto sides =
        s >= 0 ? silhouette_sides(f, s, x) : cone_sides(f, f.pieces[p], f.piece_lines[p], x);
    if (sides.empty()) continue;
    // The cheapest test: a cone that misses the whole emitter (all of it outside one side)
    // changes no piece.
    bool misses = false;
    for (size_t k = 0; k < sides.size() && !misses; ++k)
      misses = std::all_of(emitter.begin(), emitter.end(), [&](const PieceCorner& c) {
        return side_value(c, sides[k].first, sides[k].second, ne) <= 0.0;
      });
    if (misses) continue;
    next.clear();
    for (Piece& q : out) {
      // Cheap test first: q wholly outside one side keeps it whole.
      bool apart = false;
      for (size_t k = 0; k < sides.size() && !apart; ++k) {
        const Line& l = sides[k].first;
        apart = std::all_of(q.begin(), q.end(), [&](const PieceCorner& c) {
          return side_value(c, l, sides[k].second, ne) <= 0.0;
        });
      }
      if (apart) {
        next.push_back(std::move(q));
        continue;
      }
      Piece rest = std::move(q);
      for (size_t k = 0; k < sides.size() && rest.size() >= 3; ++k) {
        Piece outside = clip_piece(rest, sides[k].first, sides[k].second, false, ne);
        if (outside.size() >= 3 && piece_area(outside) > sliver) next.push_back(std::move(outside));
        rest = clip_piece(rest, sides[k].first, sides[k].second, true, ne);
      }
    }
    out.swap(next);
    if (out.size() > kMaxPieces) return false;
  }
  return true;
}

// The point factor of the visible pieces at x (their corners as computed there).
double pieces_factor(const Features& f, const std::vector<Piece>& pieces, const Eigen::Vector3d& x,
                     const Eigen::Vector3d& n, std::vector<Eigen::Vector3d>& r) {
  double sum = 0.0;
  for (const Piece& p : pieces) {
    r.clear();
    for (const PieceCorner& c : p) r.push_back(f.fb.to3d(c.q) - x);
    sum += contour_sum(n, r.data(), static_cast<int>(r.size()));
  }
  return -sum / (2.0 * M_PI);
}

Pattern pattern_of(const std::vector<Piece>& pieces) {
  Pattern pattern;
  std::vector<Source> all;
  std::vector<std::array<int, 2>> edges;
  auto index = [&](const Source& s) {
    const auto it = std::find(all.begin(), all.end(), s);
    if (it != all.end()) return static_cast<int>(it - all.begin());
    all.push_back(s);
    return static_cast<int>(all.size()) - 1;
  };
  for (const Piece& p : pieces)
    for (size_t k = 0; k < p.size(); ++k)
      edges.push_back({index(p[k].s), index(p[(k + 1) % p.size()].s)});
  // An edge and its reverse cancel (sorted by their unordered corners, then direction).
  std::sort(edges.begin(), edges.end(), [](const auto& a, const auto& b) {
    const std::array<int, 3> ka{std::min(a[0], a[1]), std::max(a[0], a[1]), a[0]};
    const std::array<int, 3> kb{std::min(b[0], b[1]), std::max(b[0], b[1]), b[0]};
    return ka < kb;
  });
  std::vector<std::array<int, 2>> kept;
  for (size_t k = 0; k < edges.size();) {
    size_t end = k;
    int net = 0;  // copies from the lower corner to the higher, minus the reverse
    const int lo = std::min(edges[k][0], edges[k][1]), hi = std::max(edges[k][0], edges[k][1]);
    while (end < edges.size() && std::min(edges[end][0], edges[end][1]) == lo &&
           std::max(edges[end][0], edges[end][1]) == hi) {
      net += edges[end][0] == lo ? 1 : -1;
      ++end;
    }
    for (int c = 0; c < std::abs(net); ++c)
      kept.push_back(net > 0 ? std::array<int, 2>{lo, hi} : std::array<int, 2>{hi, lo});
    k = end;
  }
  // Only the corners the kept edges use, renumbered in order of first use.
  std::vector<int> renumber(all.size(), -1);
  for (auto& e : kept)
    for (int& v : e) {
      if (renumber[v] < 0) {
        renumber[v] = static_cast<int>(pattern.sources.size());
        pattern.sources.push_back(all[v]);
      }
      v = renumber[v];
    }
  pattern.edges = std::move(kept);
  return pattern;
}

// One triangle of the partition of a.
struct Cell;
template <class CDT>
void partition(const Features& f, const std::vector<Eigen::Vector2d>& r2,
               const std::vector<std::array<Eigen::Vector2d, 2>>& segments,
               std::vector<Cell>& cells);

struct Cell {
  std::array<Eigen::Vector3d, 3> p;
  bool fast = true;  // integrand from `pattern`; else from the blockers at every point
  int pattern = -1;
  bool crude = false;  // over the direct budget: the centroid rule, est = |value|
  double low = 0.0, high = 0.0, est = 0.0;
};

// The cells of a's partition (r2: a's corners in fa) along the event segments.
template <class CDT>
void partition(const Features& f, const std::vector<Eigen::Vector2d>& r2,
               const std::vector<std::array<Eigen::Vector2d, 2>>& segments,
               std::vector<Cell>& cells) {
  using Point2 = typename CDT::Point;
  CDT cdt;
  std::vector<Point2> boundary;
  for (const auto& q : r2) boundary.emplace_back(q.x(), q.y());
  cdt.insert_constraint(boundary.begin(), boundary.end(), true);
  for (const auto& s : segments)
    cdt.insert_constraint(Point2(s[0].x(), s[0].y()), Point2(s[1].x(), s[1].y()));
  for (auto fh = cdt.finite_faces_begin(); fh != cdt.finite_faces_end(); ++fh) {
    const Point2 c =
        CGAL::centroid(fh->vertex(0)->point(), fh->vertex(1)->point(), fh->vertex(2)->point());
    bool inside = true;
    for (size_t k = 0; k < boundary.size() && inside; ++k)
      inside =
          CGAL::orientation(boundary[k], boundary[(k + 1) % boundary.size()], c) == CGAL::LEFT_TURN;
    if (!inside) continue;
    Cell cell;
    for (int k = 0; k < 3; ++k) {
      const Point2& q = fh->vertex(k)->point();
      cell.p[k] = f.fa.to3d({CGAL::to_double(q.x()), CGAL::to_double(q.y())});
    }
    if ((cell.p[1] - cell.p[0]).cross(cell.p[2] - cell.p[0]).dot(f.fa.w) <= 0.0) continue;
    cells.push_back(cell);
  }
}

struct Integrator {
  const Features& f;
  Eigen::Vector3d n;  // a's normal
  std::vector<Pattern> patterns;
  std::vector<Eigen::Vector3d> scratch;
  AnalyticEstimate out;

  std::vector<Piece> pieces, spare, whole;
  // direct() returns the hidden part of the emitter's point factor (unoccluded - visible).
  bool hidden = false;
  const std::vector<int>* units = nullptr;  // direct()'s blockers (visible_pieces); all if null

  // The point factor at x from the blockers themselves (visible_pieces); NaN when they make
  // too many pieces.
  double direct(const Eigen::Vector3d& x) {
    ++out.direct_evaluations;
    if (!visible_pieces(f, x, pieces, spare, units)) return std::nan("");
    const double visible = pieces_factor(f, pieces, x, n, scratch);
    if (!hidden) return visible;
    // The hidden part: the whole emitter's factor by the same corners and arithmetic, so
    // that it is exactly 0 where nothing is hidden (visible_pieces then returns the emitter
    // piece untouched).
    whole.assign(1, Piece());
    for (int k = 0; k < static_cast<int>(f.emitter2.size()); ++k)
      whole[0].push_back({f.emitter2[k], {Source::kEmitterCorner, k, 0}, k});
    return pieces_factor(f, whole, x, n, scratch) - visible;
  }

  double integrand(const Cell& c, const Eigen::Vector3d& x) {
    ++out.evaluations;
    if (c.fast) return c.pattern < 0 ? 0.0 : pattern_factor(f, patterns[c.pattern], x, n, scratch);
    return direct(x);
  }

  // Classifies a cell: its pattern from the centroid, verified at the inset corners.
  void classify(Cell& c) {
    const Eigen::Vector3d centre = (c.p[0] + c.p[1] + c.p[2]) / 3.0;
    ++out.direct_evaluations;
    c.fast = visible_pieces(f, centre, pieces, spare);
    Pattern pattern = pattern_of(pieces);
    for (int k = 0; k < 3 && c.fast; ++k) {
      const Eigen::Vector3d y = c.p[k] + kCheckInset * (centre - c.p[k]);
      const double exact = direct(y);
      const double fast = pattern.empty() ? 0.0 : pattern_factor(f, pattern, y, n, scratch);
      c.fast = std::abs(fast - exact) <= kVerifyTol * std::abs(unoccluded(f, y, n)) + 1e-300;
    }
    if (!c.fast) return;
    if (pattern.empty()) {
      c.pattern = -1;
    } else {
      patterns.push_back(std::move(pattern));
      c.pattern = static_cast<int>(patterns.size()) - 1;
    }
  }

  // Both rules on the collapsed map x = p0 + u (p1 - p0) + u v (p2 - p1), J = 2 A u.
  void integrate(Cell& c) {
    const double area = 0.5 * (c.p[1] - c.p[0]).cross(c.p[2] - c.p[0]).norm();
    if (c.fast && c.pattern < 0) {
      c.low = c.high = c.est = 0.0;  // umbra: exactly 0
      return;
    }
    if (!c.fast && out.direct_evaluations >= kMaxDirectEvaluations) {
      // Over budget: the centroid's value for the cell, wholly uncertain (it is 0 to twice
      // that as far as anyone knows); the pair ends unconverged.
      const Eigen::Vector3d centre = (c.p[0] + c.p[1] + c.p[2]) / 3.0;
      const double v = integrand(c, centre);
      c.low = c.high = std::isfinite(v) ? area * v : 0.0;
      c.est = std::isfinite(v) ? std::abs(c.low) : area * std::abs(unoccluded(f, centre, n));
      c.crude = true;
      out.converged = false;
      return;
    }
    double q[2] = {0.0, 0.0};
    const int orders[2] = {kLowOrder, kHighOrder};
    for (int r = 0; r < 2; ++r) {
      const GaussRule g = gauss_legendre(orders[r]);
      for (int i = 0; i < g.n; ++i) {
        const double u = g.x[i];
        double inner = 0.0;
        for (int j = 0; j < g.n; ++j) {
          const Eigen::Vector3d x = c.p[0] + u * (c.p[1] - c.p[0]) + u * g.x[j] * (c.p[2] - c.p[1]);
          inner += g.w[j] * integrand(c, x);
        }
        q[r] += g.w[i] * 2.0 * area * u * inner;
      }
    }
    if (!(std::isfinite(q[0]) && std::isfinite(q[1]))) {
      // A pattern undefined somewhere in the cell (two of its lines parallel there): the
      // cell from the blockers instead; where even that fails, the cell is left crude (0,
      // its whole unoccluded share as the error) and the pair unconverged.
      if (c.fast) {
        c.fast = false;
        integrate(c);
        return;
      }
      c.low = c.high = 0.0;
      c.est = area * std::abs(unoccluded(f, (c.p[0] + c.p[1] + c.p[2]) / 3.0, n));
      c.crude = true;
      out.converged = false;
      return;
    }
    c.low = q[0];
    c.high = q[1];
    c.est = std::abs(q[1] - q[0]);
  }
};

// The error estimate of a sum of low-rule cells from the cells' differences d = high - low:
// the signed sum Σd is the sum's error where the high rule is the more accurate (errors of
// different cells cancel in the sum as they do in the estimate), widened by kErrorSafety for
// the high rule's own error, plus kAbsShare of Σ|d| in case Σd cancelled by accident.
// Calibrated on the closed-form cases of tests/geometry/analytic_ff_test.cpp (true/estimate
// between 0.1 and 1 in every run).
constexpr double kErrorSafety = 1.25;
constexpr double kAbsShare = 0.05;
double pair_error(double diff, double abs_diff) {
  return kErrorSafety * std::abs(diff) + kAbsShare * abs_diff;
}

// Clips the 2-D segment [p, q] to the convex counter-clockwise polygon r; false when nothing
// of it lies inside (or it runs along an edge).
bool clip_segment(Eigen::Vector2d& p, Eigen::Vector2d& q, const std::vector<Eigen::Vector2d>& r,
                  double eps) {
  double t0 = 0.0, t1 = 1.0;
  const Eigen::Vector2d d = q - p;
  for (size_t k = 0; k < r.size(); ++k) {
    const Eigen::Vector2d e = r[(k + 1) % r.size()] - r[k];
    const double len = e.norm();
    const double f0 = (e.x() * (p - r[k]).y() - e.y() * (p - r[k]).x()) / len;  // distance inside
    const double fd = (e.x() * d.y() - e.y() * d.x()) / len;
    if (std::abs(fd) * (t1 - t0) <= eps) {  // parallel to the edge (over what is left)
      if (f0 + fd * t0 <= eps) return false;
      continue;
    }
    const double t = -f0 / fd;
    if (fd > 0.0) t0 = std::max(t0, t);
    else t1 = std::min(t1, t);
    if (t1 <= t0) return false;
  }
  const Eigen::Vector2d a = p + t0 * d, b = p + t1 * d;
  if ((b - a).norm() <= eps) return false;
  p = a;
  q = b;
  return true;
}

// Whether the lines through v and the points s(t) = p + t (q - p), t in [t0, t1], meet b's
// plane inside the emitter (else their event changes nothing b shows): conservative where
// the meeting point runs off to infinity.
bool reaches_emitter(const Features& f, const Eigen::Vector3d& v, const Eigen::Vector3d& p,
                     const Eigen::Vector3d& q, double t0, double t1, double eps) {
  const double hv = f.fb.height(v), hp = f.fb.height(p), hq = f.fb.height(q);
  if (hq != hp) {
    const double ts = (hv - hp) / (hq - hp);
    if (ts >= t0 && ts <= t1) return true;
  } else if (hp == hv) {
    return true;
  }
  auto at = [&](double t) {
    const Eigen::Vector3d s = p + t * (q - p);
    const double hs = hp + t * (hq - hp);
    return f.fb.to2d(v + (s - v) * (hv / (hv - hs)));
  };
  Eigen::Vector2d y0 = at(t0), y1 = at(t1);
  if (!y0.allFinite() || !y1.allFinite()) return true;
  if ((y1 - y0).norm() <= eps) y1 = y0 + Eigen::Vector2d(2.0 * eps, 0.0);
  return clip_segment(y0, y1, f.emitter2, 0.0);
}

// The event segments on a (2-D in fa), clipped to the receiver polygon r2.
std::vector<std::array<Eigen::Vector2d, 2>> event_segments(const Features& f,
                                                            const std::vector<Eigen::Vector2d>& r2,
                                                            double eps) {
  std::vector<std::array<Eigen::Vector2d, 2>> direct, between;  // with b; blocker-blocker
  double radius = 0.0;
  for (const auto& q : r2) radius = std::max(radius, (q - r2[0]).norm());
  // A line through v nearly parallel to a's plane meets it at rounding-noise distances
  // (hv / (hv - hs) overflows or is 0/0): such a segment is dropped, which only leaves its
  // event to refinement (events speed the quadrature up; they are never needed for it).
  auto add = [&](std::vector<std::array<Eigen::Vector2d, 2>>& out, Eigen::Vector2d p,
                 Eigen::Vector2d q) {
    if (!p.allFinite() || !q.allFinite() || !clip_segment(p, q, r2, eps)) return;
    if (!p.allFinite() || !q.allFinite()) return;
    if (q.x() < p.x() || (q.x() == p.x() && q.y() < p.y())) std::swap(p, q);
    out.push_back({p, q});
  };
  const double eps_b = kSameTol * f.scale;
  // Objects: 0 the emitter, 1.. the pieces; each as corners and edges.
  std::vector<const Polygon3*> objects{&f.emitter};
  for (const auto& piece : f.pieces) objects.push_back(&piece);
  for (size_t A = 0; A < objects.size(); ++A) {
    for (size_t B = 0; B < objects.size(); ++B) {
      if (A == B) continue;
      const Polygon3& va = *objects[A];
      const Polygon3& eb = *objects[B];
      for (const auto& v : va) {
        const double hv = f.fa.height(v);
        if (!(hv > 0.0)) continue;  // on a's plane: every line through it meets a at v
        for (size_t k = 0; k < eb.size(); ++k) {
          const Eigen::Vector3d& p = eb[k];
          const Eigen::Vector3d& q = eb[(k + 1) % eb.size()];
          const double hp = f.fa.height(p), hq = f.fa.height(q);
          // x(t) = v + (s - v) hv / (hv - hs) for s = p + t (q - p): undefined where hs = hv.
          std::vector<double> cuts{0.0, 1.0};
          if (hq != hp) {
            const double ts = (hv - hp) / (hq - hp);
            if (ts > 0.0 && ts < 1.0) cuts = {0.0, ts - kParamMargin, ts + kParamMargin, 1.0};
            else if (ts == 0.0) cuts = {kParamMargin, 1.0};
            else if (ts == 1.0) cuts = {0.0, 1.0 - kParamMargin};
          } else if (hp == hv) {
            continue;  // the edge runs at v's height: its lines through v are parallel to a
          }
          auto at = [&](double t) {
            const Eigen::Vector3d s = p + t * (q - p);
            const double hs = hp + t * (hq - hp);
            return f.fa.to2d(v + (s - v) * (hv / (hv - hs)));
          };
          for (size_t c = 0; c + 1 < cuts.size(); c += 2) {
            if (A == 0 || B == 0) {
              add(direct, at(cuts[c]), at(cuts[c + 1]));
            } else if (reaches_emitter(f, v, p, q, cuts[c], cuts[c + 1], eps_b)) {
              add(between, at(cuts[c]), at(cuts[c + 1]));
            }
          }
        }
      }
    }
  }
  // Where a piece's plane meets a's plane (seen edge-on from there).
  for (const auto& piece : f.pieces) {
    const Eigen::Vector3d m = newell_normal(piece).normalized();
    const Eigen::Vector3d l(m.dot(f.fa.u), m.dot(f.fa.v), m.dot(f.fa.o - piece[0]));
    const double g = l.head<2>().norm();
    if (!(g > 1e-12)) continue;
    const Eigen::Vector2d normal = l.head<2>() / g, foot = -(l.z() / g) * normal;
    const Eigen::Vector2d dir(-normal.y(), normal.x());
    const double reach = (foot - r2[0]).norm() + 2.0 * radius;
    add(direct, foot - reach * dir, foot + reach * dir);
  }
  // Duplicates (aligned geometry repeats lines) sorted together and dropped; beyond
  // kMaxEvents the blocker-blocker events go first, then all (refinement takes over).
  auto dedupe = [&](std::vector<std::array<Eigen::Vector2d, 2>>& v) {
    std::sort(v.begin(), v.end(), [](const auto& x, const auto& y) {
      return x[0].x() != y[0].x() ? x[0].x() < y[0].x() : x[0].y() < y[0].y();
    });
    std::vector<std::array<Eigen::Vector2d, 2>> out;
    for (const auto& seg : v) {
      bool dup = false;
      for (size_t k = out.size(); k-- > 0 && out[k][0].x() >= seg[0].x() - eps && !dup;)
        dup = (out[k][0] - seg[0]).norm() <= eps && (out[k][1] - seg[1]).norm() <= eps;
      if (!dup) out.push_back(seg);
    }
    v.swap(out);
  };
  dedupe(direct);
  dedupe(between);
  if (direct.size() > kMaxEvents) return {};
  if (direct.size() + between.size() <= kMaxEvents) direct.insert(direct.end(), between.begin(), between.end());
  return direct;
}

// The side planes of the shaft between two convex polygons (Haines & Wallace): the planes
// through an edge of one and a corner of the other with both polygons on their inner side
// (n . p + d <= eps), i.e. the faces of their convex hull other than the polygons' own.
std::vector<Eigen::Vector4d> shaft_planes(const Polygon3& a, const Polygon3& b, double eps) {
  std::vector<Eigen::Vector4d> planes;
  auto side = [&](const Polygon3& e, const Polygon3& c) {
    for (size_t k = 0; k < e.size(); ++k) {
      const Eigen::Vector3d& p = e[k];
      const Eigen::Vector3d& q = e[(k + 1) % e.size()];
      for (const auto& r : c) {
        Eigen::Vector3d n = (q - p).cross(r - p);
        if (!(n.norm() > 0.0)) continue;
        n.normalize();
        double lo = INFINITY, hi = -INFINITY;
        for (const Polygon3* poly : {&a, &b})
          for (const auto& v : *poly) {
            lo = std::min(lo, n.dot(v - p));
            hi = std::max(hi, n.dot(v - p));
          }
        if (hi <= eps) planes.push_back({n.x(), n.y(), n.z(), -n.dot(p)});
        else if (lo >= -eps) planes.push_back({-n.x(), -n.y(), -n.z(), n.dot(p)});
      }
    }
  };
  side(a, b);
  side(b, a);
  return planes;
}

// True when the piece lies outside the shaft or on its boundary (then no segment between the
// polygons passes through its inside: it touches them at most).
bool outside_shaft(const Polygon3& piece, const std::vector<Eigen::Vector4d>& planes, double eps) {
  for (const auto& pl : planes) {
    bool out = true;
    for (const auto& v : piece) out = out && pl.head<3>().dot(v) + pl.w() >= -eps;
    if (out) return true;
  }
  return false;
}

// The back planes (Features::back) of the pieces that are faces of closed convex solids,
// seen from the receiver a towards the emitter b. A convex solid hides from x exactly what
// its faces turned towards x hide: a segment from x (outside it) to any point behind it
// enters it through a face with x on that face's outer side. So from x the solid hides the
// cone over its silhouette (silhouette_sides), and a face with all of a on its inner side
// can be dropped from the pair (fewer events, fewer cells). A solid is a set of pieces connected by
// shared edges (exactly equal corners), each edge in at most two of them, with every corner of the
// set on one side of each piece's plane (within eps; some corner clear of it: not flat), and the
// edges in only one piece (its open "cap": a box standing on a floor has no bottom face) all in one
// plane with both polygons on the solid's side of it (a segment between them then cannot pass
// through the cap) and a not in it (from a point on the cap the solid may hide everything,
// not only what its front faces hide). a must lie outside the solid. Anything else gets
// zero planes and solid -1 (each piece its own cone). `solid` receives each piece's solid
// (an id, or -1).
std::vector<Eigen::Vector4d> solid_back_planes(const std::vector<Polygon3>& pieces,
                                               const Polygon3& a, const Polygon3& b, double eps,
                                               std::vector<int>& solid) {
  const int n = static_cast<int>(pieces.size());
  std::vector<Eigen::Vector4d> back(n, Eigen::Vector4d::Zero());
  solid.assign(n, -1);
  // Edges keyed by their corners (ordered), with the piece using them.
  using Key = std::array<double, 6>;
  std::vector<std::pair<Key, int>> edges;
  for (int p = 0; p < n; ++p)
    for (size_t k = 0; k < pieces[p].size(); ++k) {
      Eigen::Vector3d u = pieces[p][k], v = pieces[p][(k + 1) % pieces[p].size()];
      if (std::lexicographical_compare(v.data(), v.data() + 3, u.data(), u.data() + 3))
        std::swap(u, v);
      edges.push_back({{u.x(), u.y(), u.z(), v.x(), v.y(), v.z()}, p});
    }
  std::sort(edges.begin(), edges.end());
  std::vector<int> root(n);
  for (int p = 0; p < n; ++p) root[p] = p;
  auto find = [&](int p) {
    while (root[p] != p) p = root[p] = root[root[p]];
    return p;
  };
  std::vector<char> bad(n, 0);                       // by root, after the union
  std::vector<std::array<Eigen::Vector3d, 2>> open;  // edges in one piece
  std::vector<int> open_piece;
  for (size_t e = 0; e < edges.size();) {
    size_t end = e;
    while (end < edges.size() && edges[end].first == edges[e].first) ++end;
    for (size_t k = e + 1; k < end; ++k) root[find(edges[k].second)] = find(edges[e].second);
    if (end - e > 2) bad[edges[e].second] = 1;  // marked on a piece, moved to its root below
    if (end - e == 1) {
      const Key& q = edges[e].first;
      open.push_back({Eigen::Vector3d(q[0], q[1], q[2]), Eigen::Vector3d(q[3], q[4], q[5])});
      open_piece.push_back(edges[e].second);
    }
    e = end;
  }
  for (int p = 0; p < n; ++p)
    if (bad[p]) bad[find(p)] = 1;
  for (int r = 0; r < n; ++r) {
    if (find(r) != r || bad[r]) continue;
    std::vector<int> members;
    std::vector<Eigen::Vector3d> corners;
    for (int p = 0; p < n; ++p)
      if (find(p) == r) {
        members.push_back(p);
        corners.insert(corners.end(), pieces[p].begin(), pieces[p].end());
      }
    if (members.size() < 2) continue;
    // Each piece's plane, oriented with the solid inside (negative); convex and not flat.
    std::vector<Eigen::Vector4d> planes;
    bool ok = true, thick = false;
    for (const int p : members) {
      const Eigen::Vector3d m = newell_normal(pieces[p]).normalized();
      const double d = -m.dot(pieces[p][0]);
      double lo = INFINITY, hi = -INFINITY;
      for (const auto& c : corners) {
        lo = std::min(lo, m.dot(c) + d);
        hi = std::max(hi, m.dot(c) + d);
      }
      for (const auto& c : pieces[p]) ok = ok && std::abs(m.dot(c) + d) <= eps;
      if (hi <= eps)
        planes.push_back({m.x(), m.y(), m.z(), d});
      else if (lo >= -eps)
        planes.push_back({-m.x(), -m.y(), -m.z(), -d});
      else
        ok = false;
      thick = thick || std::max(hi, -lo) > 10.0 * eps;
    }
    if (!ok || !thick) continue;
    // The open edges: all in one plane (the cap), the solid, a and b on one side, a off it.
    std::vector<Eigen::Vector3d> rim;
    for (size_t k = 0; k < open.size(); ++k)
      if (find(open_piece[k]) == r) rim.insert(rim.end(), {open[k][0], open[k][1]});
    bool outside = false;  // a's centroid outside the solid
    Eigen::Vector3d ca = Eigen::Vector3d::Zero();
    for (const auto& c : a) ca += c / static_cast<double>(a.size());
    for (const auto& pl : planes) outside = outside || pl.head<3>().dot(ca) + pl.w() > eps;
    if (!rim.empty()) {
      // The cap's plane through three rim corners far apart.
      const Eigen::Vector3d& p0 = rim[0];
      Eigen::Vector3d p1 = p0, normal = Eigen::Vector3d::Zero();
      for (const auto& c : rim)
        if ((c - p0).norm() > (p1 - p0).norm()) p1 = c;
      for (const auto& c : rim) {
        const Eigen::Vector3d m = (p1 - p0).cross(c - p0);
        if (m.norm() > normal.norm()) normal = m;
      }
      if (!(normal.norm() > eps * (p1 - p0).norm())) continue;
      normal.normalize();
      double lo = INFINITY, hi = -INFINITY;
      for (const auto& c : corners) {
        lo = std::min(lo, normal.dot(c - p0));
        hi = std::max(hi, normal.dot(c - p0));
      }
      if (hi < -lo) {  // the solid on the other side: turn the normal towards it
        normal = -normal;
        const double t = lo;
        lo = -hi;
        hi = -t;
      }
      bool cap = lo >= -eps && hi > 10.0 * eps;
      for (const auto& c : rim) cap = cap && std::abs(normal.dot(c - p0)) <= eps;
      double a_high = -INFINITY;
      for (const auto& c : a) {
        cap = cap && normal.dot(c - p0) >= -eps;
        a_high = std::max(a_high, normal.dot(c - p0));
      }
      for (const auto& c : b) cap = cap && normal.dot(c - p0) >= -eps;
      if (!cap || !(a_high > eps)) continue;
      outside = outside || normal.dot(ca - p0) < -eps;
    }
    if (!outside) continue;
    for (size_t k = 0; k < members.size(); ++k) {
      back[members[k]] = planes[k];
      solid[members[k]] = r;
    }
  }
  return back;
}

// The hidden part's direct quadrature (direct_G) is tried where tol_G is at least this
// fraction of the receiver's area (F to 1e-6; tighter, the event partition's analytic cells
// win) and the pair keeps at least kDirectMinPieces blocker pieces, with at most kMaxDirect
// point factors (~5-100 us each) before the event partition takes over. The error budget
// goes kHiddenShare to the hidden part and kUnoccludedShare to the unoccluded integral.
constexpr double kDirectMinRelTol = 1e-6;
constexpr size_t kDirectMinPieces = 2;
constexpr std::int64_t kMaxDirect = 100000;
constexpr double kHiddenShare = 0.75;
constexpr double kUnoccludedShare = 0.25;

// How pair_G integrates: over a's partition along the event segments (by the rounded or the
// exact CDT), or by direct quadrature (direct_G).
enum class Mode { kRoundedCdt, kExactCdt, kDirect };

AnalyticEstimate direct_G(const Features& f, const Polygon3& receiver, double tol_G,
                          std::int64_t max_direct);

// analytic_pair_G in one mode.
AnalyticEstimate pair_G(const Polygon3& a, const Polygon3& b, const std::vector<Polygon3>& blockers,
                        double tol_G, std::int64_t max_evaluations, Mode mode,
                        std::int64_t max_direct = 0, bool* applies = nullptr,
                        bool plain_sum = false) {
  Features f;
  f.fa = frame_of(a);
  f.fb = frame_of(b);
  const Polygon3 receiver = clip_front(a, f.fb);
  f.emitter = clip_front(b, f.fa);
  if (receiver.empty() || f.emitter.empty()) return {};
  for (const auto& p : f.emitter) f.emitter2.push_back(f.fb.to2d(p));
  f.scale = polygon_diameter(f.emitter);
  const double scale = std::max(polygon_diameter(a), f.scale);
  const double plane_eps = 1e-12 * scale;

  const std::vector<Eigen::Vector4d> shaft = shaft_planes(receiver, f.emitter, plane_eps);
  // The blockers' parts in front of both planes (convex pieces), their corners and edges.
  for (const auto& blocker : blockers) {
    if (blocker.size() < 3 || !(polygon_area(blocker) > 0.0)) continue;
    std::vector<Polygon3> convex;
    if (is_convex(blocker)) {
      convex.push_back(blocker);
    } else {
      for (const auto& t : triangulate(blocker)) convex.push_back({blocker[t[0]], blocker[t[1]], blocker[t[2]]});
    }
    for (const auto& c : convex) {
      Polygon3 piece = clip_front(c, f.fa);
      if (!piece.empty()) piece = clip_front(piece, f.fb);
      if (piece.empty()) continue;
      double ha = 0.0, hb = 0.0;
      for (const auto& p : piece) {
        ha = std::max(ha, f.fa.height(p));
        hb = std::max(hb, f.fb.height(p));
      }
      if (ha <= plane_eps || hb <= plane_eps) continue;  // in a's or b's plane: hides nothing
      if (outside_shaft(piece, shaft, plane_eps)) continue;
      f.pieces.push_back(std::move(piece));
    }
  }
  // Faces of closed convex solids: those turned away from all of a hide nothing.
  std::vector<int> solid_root;
  f.back = solid_back_planes(f.pieces, receiver, f.emitter, plane_eps, solid_root);
  {
    size_t kept = 0;
    for (size_t p = 0; p < f.pieces.size(); ++p) {
      bool away = solid_root[p] >= 0;
      for (const auto& c : receiver)
        away = away && f.back[p].head<3>().dot(c) + f.back[p].w() <= 0.0;
      if (away) continue;
      if (kept != p) f.pieces[kept] = std::move(f.pieces[p]);  // (a self-move empties it)
      f.back[kept] = f.back[p];
      solid_root[kept++] = solid_root[p];
    }
    f.pieces.resize(kept);
    f.back.resize(kept);
    solid_root.resize(kept);
  }
  auto corner_index = [&](const Eigen::Vector3d& p) {
    for (size_t k = 0; k < f.corners.size(); ++k)
      if (f.corners[k] == p) return static_cast<int>(k);
    f.corners.push_back(p);
    return static_cast<int>(f.corners.size()) - 1;
  };
  for (const auto& piece : f.pieces) {
    std::vector<int>& lines = f.piece_lines.emplace_back();
    for (size_t k = 0; k < piece.size(); ++k) {
      int i = corner_index(piece[k]), j = corner_index(piece[(k + 1) % piece.size()]);
      if (i > j) std::swap(i, j);
      auto it = std::find(f.edges.begin(), f.edges.end(), std::array<int, 2>{i, j});
      if (it == f.edges.end()) it = f.edges.insert(f.edges.end(), {i, j});
      lines.push_back(static_cast<int>(f.emitter2.size() + (it - f.edges.begin())));
    }
  }
  // The solids, numbered in the order of their first piece, and their pieces' neighbours.
  f.solid.assign(f.pieces.size(), -1);
  f.neighbour.resize(f.pieces.size());
  for (size_t p = 0; p < f.pieces.size(); ++p) {
    if (solid_root[p] < 0) continue;
    for (size_t q = 0; q < p && f.solid[p] < 0; ++q)
      if (solid_root[q] == solid_root[p]) f.solid[p] = f.solid[q];
    if (f.solid[p] < 0) {
      f.solid[p] = static_cast<int>(f.solids.size());
      f.solids.emplace_back();
      f.solid_corners.emplace_back();
    }
    f.solids[f.solid[p]].push_back(static_cast<int>(p));
    auto& corners = f.solid_corners[f.solid[p]];
    corners.insert(corners.end(), f.pieces[p].begin(), f.pieces[p].end());
  }
  for (size_t p = 0; p < f.pieces.size(); ++p) {
    f.neighbour[p].assign(f.piece_lines[p].size(), -1);
    if (f.solid[p] < 0) continue;
    for (size_t k = 0; k < f.piece_lines[p].size(); ++k)
      for (const int q : f.solids[f.solid[p]])
        if (q != static_cast<int>(p) &&
            std::count(f.piece_lines[q].begin(), f.piece_lines[q].end(), f.piece_lines[p][k]))
          f.neighbour[p][k] = q;
  }

  if (mode == Mode::kDirect) {
    // Few pieces: the events are few and cheap, and give far more than the tolerance.
    if (applies) *applies = f.pieces.size() >= kDirectMinPieces;
    if (f.pieces.size() < kDirectMinPieces) return {};
    return direct_G(f, receiver, tol_G, max_direct);
  }
  // The partition of the receiver: its fan, or its CDT with the event segments.
  std::vector<Eigen::Vector2d> r2;
  for (const auto& p : receiver) r2.push_back(f.fa.to2d(p));
  std::vector<Cell> cells;
  std::int64_t events = 0;
  if (f.pieces.empty()) {
    for (size_t k = 1; k + 1 < receiver.size(); ++k) cells.push_back({{receiver[0], receiver[k], receiver[k + 1]}});
  } else {
    const auto segments = event_segments(f, r2, plane_eps);
    if (mode == Mode::kExactCdt)
      partition<ExactCDT>(f, r2, segments, cells);
    else
      partition<RoundedCDT>(f, r2, segments, cells);
    events = static_cast<std::int64_t>(segments.size());
  }
  Integrator in{f, f.fa.w, {}, {}, {}, {}, {}, {}, false};
  in.out.events = events;
  if (f.pieces.empty()) {  // unoccluded: the whole emitter everywhere
    Pattern full;
    const int ne = static_cast<int>(f.emitter2.size());
    for (int k = 0; k < ne; ++k) {
      full.sources.push_back({Source::kEmitterCorner, k, 0});
      full.edges.push_back({k, (k + 1) % ne});
    }
    in.patterns.push_back(full);
    for (Cell& c : cells) c.pattern = 0;
  } else {
    for (Cell& c : cells) {
      if (in.out.direct_evaluations < kMaxDirectEvaluations)
        in.classify(c);
      else c.fast = false;  // over budget: integrate() takes the centroid only
    }
  }
  for (Cell& c : cells) in.integrate(c);

  // Global refinement: split the cell with the largest estimate until the sum meets the
  // tolerance (or the rounding floor), or the budget is spent.
  auto by_est = [&](int x, int y) { return cells[x].est < cells[y].est; };
  std::priority_queue<int, std::vector<int>, decltype(by_est)> queue(by_est);
  std::vector<char> leaf(cells.size(), 1);
  double total_est = 0.0, total = 0.0, total_diff = 0.0;
  for (size_t k = 0; k < cells.size(); ++k) {
    queue.push(static_cast<int>(k));
    total_est += cells[k].est;
    total += cells[k].low;
    total_diff += cells[k].high - cells[k].low;
  }
  while (!queue.empty()) {
    const double tol = std::max(tol_G, kRoundingFloor * std::abs(total));
    if (!(std::max(total_est, pair_error(total_diff, total_est)) > tol)) break;
    if (in.out.evaluations >= max_evaluations ||
        in.out.direct_evaluations >= kMaxDirectEvaluations) {
      in.out.converged = false;
      break;
    }
    const int k = queue.top();
    queue.pop();
    const Cell parent = cells[k];
    leaf[k] = 0;
    total_est -= parent.est;
    total -= parent.low;
    total_diff -= parent.high - parent.low;
    const Eigen::Vector3d m01 = 0.5 * (parent.p[0] + parent.p[1]), m12 = 0.5 * (parent.p[1] + parent.p[2]),
                          m20 = 0.5 * (parent.p[2] + parent.p[0]);
    const std::array<std::array<Eigen::Vector3d, 3>, 4> children = {
        {{parent.p[0], m01, m20}, {m01, parent.p[1], m12}, {m20, m12, parent.p[2]}, {m12, m20, m01}}};
    for (const auto& corners : children) {
      Cell child;
      child.p = corners;
      child.fast = parent.fast;
      child.pattern = parent.pattern;
      if (!parent.fast) in.classify(child);
      in.integrate(child);
      cells.push_back(child);
      leaf.push_back(1);
      total_est += child.est;
      total += child.low;
      total_diff += child.high - child.low;
      queue.push(static_cast<int>(cells.size()) - 1);
    }
  }
  AnalyticEstimate out = in.out;
  out.G = 0.0;
  double diff = 0.0, abs_diff = 0.0, crude = 0.0;
  for (size_t k = 0; k < cells.size(); ++k) {
    if (!leaf[k]) continue;
    out.G += cells[k].low;
    if (cells[k].crude) {
      crude += cells[k].est;
    } else {
      diff += cells[k].high - cells[k].low;
      abs_diff += cells[k].est;
    }
    ++out.cells;
  }
  out.G = std::max(0.0, out.G);
  // plain_sum: no cancellation between cells trusted (the sum of their estimates, which the
  // refinement above keeps within tol_G as well).
  const double error =
      plain_sum ? std::max(pair_error(diff, abs_diff), abs_diff) : pair_error(diff, abs_diff);
  out.error = std::max(error + crude, kRoundingFloor * out.G);
  return out;
}

// The hidden part of the pair, H = ∫_a (F_{dx->b} - F_{dx->b, visible}) dA_x, by adaptive
// quadrature of the point factors from the blockers themselves (Integrator::direct, hidden):
// no event partition. analytic_pair_G adds the unoccluded integral (cheap: one pattern).
// A cell whose shaft to the emitter holds no blocker piece hides nothing: exactly 0, no point
// evaluated. Elsewhere the integrand is continuous, C1 across the EV events (a receiver free
// of contacts, which estimate_analytic integrates over) but not analytic, and its features
// (a shadow's band) are about as wide as the cell's distance to the nearest blocker: a cell
// wider than kResolve times that distance is split before any rule is trusted (two rules
// that both miss a band agree), and a resolved cell's estimate is |Q_high - Q_low| with the
// value Q_high. Without event lines a cell may hold a kink where both rules err alike, so the
// pair's estimate is the plain sum of the cells' estimates (no cancellation trusted), times
// kDirectSafety. The cell with the largest is split into four until that meets tol_G, or
// max_direct point factors are spent (then `converged` is false and the caller integrates
// along the events instead). kDirectSafety 2: at 1 the bench's 4-box room at --tol 1e-4 and
// 1e-5 had entries up to 1.7x their estimate against the 1e-8 reference (small box faces,
// 4-7 cells); at 2 none above 0.85 (AnalyticRoomSlow.FourBoxRoomEntriesLieWithinTheirStatedErrors).
constexpr double kDirectSafety = 2.0;
constexpr double kResolve = 1.0;
// Splits of a fan triangle towards resolution at most (cells 4^-k of it in area).
constexpr int kMaxResolveDepth = 8;

struct DirectCell {
  Cell c;
  std::vector<int> units;  // the blockers in its shaft (visible_pieces' units)
  bool empty = false;      // no blocker in its shaft: exactly 0
  bool resolved = true;    // narrower than kResolve x its distance to the blockers
  int depth = 0;
};

// `candidates`: the units of a cell containing this one (its shaft contains this one's).
DirectCell direct_cell(const Features& f, const std::array<Eigen::Vector3d, 3>& p, int depth,
                       double eps, const std::vector<int>& candidates) {
  DirectCell d;
  d.c.p = p;
  d.c.fast = false;
  d.depth = depth;
  const Polygon3 tri(p.begin(), p.end());
  const std::vector<Eigen::Vector4d> shaft = shaft_planes(tri, f.emitter, eps);
  const Eigen::Vector3d centre = (p[0] + p[1] + p[2]) / 3.0;
  double size = 0.0;
  for (int k = 0; k < 3; ++k) size = std::max(size, (p[(k + 1) % 3] - p[k]).norm());
  double dist = INFINITY;
  for (const int u : candidates) {
    // A solid counts when any of its faces is in the shaft (a segment through it crosses one).
    const int s = f.solid[u];
    const std::vector<int> lone{u};
    bool in = false;
    for (const int q : s >= 0 ? f.solids[s] : lone) {
      if (outside_shaft(f.pieces[q], shaft, eps)) continue;
      in = true;
      Eigen::AlignedBox3d box;
      for (const auto& c : f.pieces[q]) box.extend(c);
      dist = std::min(dist, box.exteriorDistance(centre));
    }
    if (in) d.units.push_back(u);
  }
  d.empty = d.units.empty();
  d.resolved = d.empty || size <= kResolve * dist;
  return d;
}

AnalyticEstimate direct_G(const Features& f, const Polygon3& receiver, double tol_G,
                          std::int64_t max_direct) {
  Integrator in{f, f.fa.w, {}, {}, {}, {}, {}, {}, true};
  const double eps = 1e-12 * std::max(polygon_diameter(receiver), f.scale);
  std::vector<DirectCell> cells;
  auto split = [](const std::array<Eigen::Vector3d, 3>& p) {
    const Eigen::Vector3d m01 = 0.5 * (p[0] + p[1]), m12 = 0.5 * (p[1] + p[2]),
                          m20 = 0.5 * (p[2] + p[0]);
    return std::array<std::array<Eigen::Vector3d, 3>, 4>{
        {{p[0], m01, m20}, {m01, p[1], m12}, {m20, m12, p[2]}, {m12, m20, m01}}};
  };
  // The initial cells: the fan, split until every cell is resolved.
  std::vector<int> all;  // every unit: the lone pieces and each solid's first
  for (size_t p = 0; p < f.pieces.size(); ++p)
    if (f.solid[p] < 0 || f.solids[f.solid[p]][0] == static_cast<int>(p))
      all.push_back(static_cast<int>(p));
  std::vector<DirectCell> todo;
  for (size_t k = 1; k + 1 < receiver.size(); ++k)
    todo.push_back(direct_cell(f, {receiver[0], receiver[k], receiver[k + 1]}, 0, eps, all));
  while (!todo.empty()) {
    DirectCell d = todo.back();
    todo.pop_back();
    if (d.resolved) {
      cells.push_back(d);
      continue;
    }
    if (d.depth >= kMaxResolveDepth) {
      in.out.converged = false;
      return in.out;
    }
    const auto children = split(d.c.p);
    for (int k = 3; k >= 0; --k)
      todo.push_back(direct_cell(f, children[k], d.depth + 1, eps, d.units));
  }
  auto evaluate = [&](DirectCell& d) {
    if (d.empty) return;  // low = high = est = 0
    in.units = &d.units;
    in.integrate(d.c);
    in.units = nullptr;
  };
  for (DirectCell& d : cells) evaluate(d);
  auto by_est = [&](int x, int y) { return cells[x].c.est < cells[y].c.est; };
  std::priority_queue<int, std::vector<int>, decltype(by_est)> queue(by_est);
  std::vector<char> leaf(cells.size(), 1);
  double total_est = 0.0, total = 0.0;
  for (size_t k = 0; k < cells.size(); ++k) {
    queue.push(static_cast<int>(k));
    total_est += cells[k].c.est;
    total += cells[k].c.high;
  }
  while (!queue.empty()) {
    const double tol = std::max(tol_G, kRoundingFloor * std::abs(total));
    if (!(kDirectSafety * total_est > tol)) break;
    if (in.out.direct_evaluations >= max_direct) {
      in.out.converged = false;
      break;
    }
    const int k = queue.top();
    queue.pop();
    const DirectCell parent = cells[k];
    leaf[k] = 0;
    total_est -= parent.c.est;
    total -= parent.c.high;
    for (const auto& corners : split(parent.c.p)) {
      DirectCell child = direct_cell(f, corners, parent.depth + 1, eps, parent.units);
      evaluate(child);
      cells.push_back(child);
      leaf.push_back(1);
      total_est += child.c.est;
      total += child.c.high;
      queue.push(static_cast<int>(cells.size()) - 1);
    }
  }
  AnalyticEstimate out = in.out;
  out.G = 0.0;
  double est = 0.0;
  for (size_t k = 0; k < cells.size(); ++k) {
    if (!leaf[k]) continue;
    out.G += cells[k].c.high;
    est += cells[k].c.est;
    ++out.cells;
  }
  out.G = std::max(0.0, out.G);
  out.error = std::max(kDirectSafety * est, kRoundingFloor * out.G);
  return out;
}

}  // namespace

AnalyticEstimate analytic_pair_G(const Polygon3& a, const Polygon3& b,
                                 const std::vector<Polygon3>& blockers, double tol_G,
                                 std::int64_t max_evaluations) {
  // Loose tolerances: the unoccluded integral (one pattern, ~1 us per point) minus the hidden
  // part by direct quadrature (direct_G), where that converges within its budget.
  AnalyticEstimate spent;  // a direct attempt that did not converge: its point factors
  if (tol_G >= kDirectMinRelTol * polygon_area(a)) {
    bool applies = false;
    const AnalyticEstimate h = pair_G(a, b, blockers, kHiddenShare * tol_G, max_evaluations,
                                      Mode::kDirect, kMaxDirect, &applies);
    if (applies && h.converged) {
      AnalyticEstimate u = pair_G(a, b, {}, kUnoccludedShare * tol_G, max_evaluations,
                                  Mode::kRoundedCdt, 0, nullptr, true);
      u.evaluations += h.evaluations;
      u.direct_evaluations += h.direct_evaluations;
      if (u.converged) {
        u.G = std::max(0.0, u.G - h.G);
        u.error += h.error;
        u.cells += h.cells;
        return u;
      }
      spent = u;
    } else {
      spent = h;
    }
  }
  AnalyticEstimate e = pair_G(a, b, blockers, tol_G, max_evaluations, Mode::kRoundedCdt);
  e.evaluations += spent.evaluations;
  e.direct_evaluations += spent.direct_evaluations;
  if (e.converged || e.events == 0) return e;
  // Unconverged with the rounded partition: again with the exact one (see RoundedCDT); the
  // better of the two, with the point factors both spent.
  AnalyticEstimate exact = pair_G(a, b, blockers, tol_G, max_evaluations, Mode::kExactCdt);
  exact.evaluations += e.evaluations;
  exact.direct_evaluations += e.direct_evaluations;
  if (exact.converged || exact.error <= e.error) return exact;
  AnalyticEstimate out = e;
  out.evaluations = exact.evaluations;
  out.direct_evaluations = exact.direct_evaluations;
  return out;
}

}  // namespace lambert::ff

namespace lambert::ff {

namespace {

Polygon3 polygon_of(const PatchGeom& g) { return Polygon3(g.p.begin(), g.p.begin() + g.n); }

// A pair's patch as the planar polygon the pair integral takes it for. A quad the loader kept
// within 1e-4 of its plane (PatchGeom::warp > 0) is put on its mean plane (through the corners'
// mean, along the patch normal): taken as it was, it was integrated on the plane of its first
// corner, a shift of up to its warp that moved F by O(warp) in a direction set by which
// corners are high (two unit squares 1 apart warped by 5e-5: 0.1998294 and 0.1998212 for the
// two congruent signs, against the planar 0.1998249, with a stated error of 5.6e-7); on the
// mean plane the shifts average out (O(warp^2)). hybrid and mc agree with this to their errors.
Polygon3 on_mean_plane(const PatchGeom& g) {
  Polygon3 p = polygon_of(g);
  if (!(g.warp > 0.0)) return p;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& c : p) mean += c / static_cast<double>(p.size());
  for (auto& c : p) c -= g.normal.dot(c - mean) * g.normal;
  return p;
}

// The patches other than `skip` in the ball around `box` whose boxes meet it (every segment
// between two points of the box lies in both): the candidate blockers.
std::vector<Polygon3> blockers_in(const Bvh& bvh, const std::vector<PatchGeom>& geom,
                                  const Eigen::AlignedBox3d& box, std::int32_t skip1,
                                  std::int32_t skip2) {
  std::vector<std::int32_t> near;
  bvh.patches_near(box.center(), 0.5 * box.diagonal().norm(), near);
  std::sort(near.begin(), near.end());
  near.erase(std::unique(near.begin(), near.end()), near.end());
  std::vector<Polygon3> blockers;
  for (const std::int32_t k : near) {
    if (k == skip1 || k == skip2) continue;
    const PatchGeom& g = geom[k];
    Eigen::AlignedBox3d gb;
    for (int c = 0; c < g.n; ++c) gb.extend(g.p[c]);
    if (gb.intersects(box)) blockers.push_back(polygon_of(g));
  }
  return blockers;
}

// Whether a blocker corner lies on p's plane strictly inside p (a blocker standing on it),
// within kMatchTol of p's size; corners on p's boundary (walls meeting a floor's edge)
// do not count.
bool blocker_stands_on(const Polygon3& p, const std::vector<Polygon3>& blockers) {
  const Frame f = frame_of(p);
  const double scale = polygon_extent(p), eps = kMatchTol * scale;
  std::vector<Eigen::Vector2d> q;
  for (const auto& c : p) q.push_back(f.to2d(c));
  for (const auto& b : blockers) {
    for (const auto& c : b) {
      if (std::abs(f.height(c)) > eps) continue;
      const Eigen::Vector2d x = f.to2d(c);
      bool inside = true;
      for (size_t k = 0; k < q.size() && inside; ++k) {
        const Eigen::Vector2d e = q[(k + 1) % q.size()] - q[k];
        inside = (e.x() * (x - q[k]).y() - e.y() * (x - q[k]).x()) / e.norm() > eps;
      }
      if (inside) return true;
    }
  }
  return false;
}

}  // namespace

PairEstimate estimate_analytic(const PairContext& ctx, std::int32_t i, std::int32_t j) {
  const PatchGeom& gi = ctx.geom[i];
  const PatchGeom& gj = ctx.geom[j];
  Eigen::AlignedBox3d box;
  for (int k = 0; k < gi.n; ++k) box.extend(gi.p[k]);
  for (int k = 0; k < gj.n; ++k) box.extend(gj.p[k]);
  const std::vector<Polygon3> blockers = blockers_in(ctx.bvh, ctx.geom, box, i, j);
  // Integrate over the side no blocker stands on: next to a contact inside the integrated
  // patch (a box on a floor) blockers project arbitrarily large and the visible polygon
  // changes without end, so refinement converges slowly there; seen from the other side the
  // same blockers are far and the integrand smooth. Else over the smaller patch (fewer
  // cells for the same accuracy per unit area).
  const Polygon3 pi = on_mean_plane(gi), pj = on_mean_plane(gj);
  const bool contact_i = blocker_stands_on(pi, blockers),
             contact_j = blocker_stands_on(pj, blockers);
  const bool over_i = contact_i != contact_j ? contact_j : gi.area <= gj.area;
  const double area = std::min(gi.area, gj.area);
  const AnalyticEstimate e =
      analytic_pair_G(over_i ? pi : pj, over_i ? pj : pi, blockers, ctx.tol * area,
                      ctx.analytic_budget > 0 ? ctx.analytic_budget : kAnalyticMaxEvaluations);
  PairEstimate out;
  out.G = e.G;
  out.var = e.error * e.error;
  out.unverified = !e.converged;
  if (e.converged) return out;
  // The budget ran out (many blockers per pair, blockers standing on both patches): hybrid's
  // rays until their standard error meets the same tolerance (issue 36), if that does better.
  const PairEstimate h = estimate_to_target(ctx, estimate_hybrid, i, j, ctx.tol);
  if (!h.short_of_target || h.var < out.var) {
    out = h;
    out.unverified = h.short_of_target;  // counted and warned about as analytic's
    out.short_of_target = false;         // (no --target-stderr was given)
  }
  out.rays = h.rays;  // traced either way
  return out;
}

double exact_point_factor(const Bvh& bvh, const std::vector<PatchGeom>& geom, std::int32_t j,
                          const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
  Eigen::AlignedBox3d box(x, x);
  for (int k = 0; k < geom[j].n; ++k) box.extend(geom[j].p[k]);
  return shadowed_point_factor(x, n, polygon_of(geom[j]), blockers_in(bvh, geom, box, j, j));
}

}  // namespace lambert::ff
