#include "geometry/mesh/discontinuity.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "core/parallel.hpp"
#include "geometry/polygon.hpp"
#include "geometry/visibility/bvh.hpp"
#include "geometry/visibility/shadow.hpp"

namespace lambert {
namespace {

// Points closer than this (relative to the scene's size) to a plane are on it: the blocks of
// the measured Cornell box stand on the floor to the last digit, so contact is exact there.
constexpr double kOnPlane = 1e-9;
// Ends of a projected edge are kept this far (relative to the source's height) from the
// plane through the source point parallel to the receiver, where the projection diverges.
constexpr double kVanishing = 1e-6;
// Visibility half-lines stop this fraction of their length short of the grazed feature.
constexpr double kGrazeStop = 1e-3;
// Lines are kept this far (relative to the receiver's size) past its bounding box.
constexpr double kOverrun = 0.05;
// A line is kept when at least this much of it (relative to the face's size) lies inside
// the face polygon: far above the mesher's snap (1e-6), so that a line touching the face
// only at a corner, or dipping in by rounding, is dropped.
constexpr double kMinInside = 1e-3;
// Pieces per wedge line at most (a line crossing the whole scene with the default piece).
constexpr int kMaxPieces = 256;

struct WeldedFace {
  Polygon3 poly;
  std::vector<std::int32_t> ids;  // welded vertex ids of the corners
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d lo, hi;  // bounding box
  double height(const Eigen::Vector3d& p) const { return (p - poly[0]).dot(normal); }
};

std::vector<WeldedFace> welded_faces(const Scene& scene) {
  std::map<std::array<double, 3>, std::int32_t> weld;
  std::vector<WeldedFace> out;
  for (const auto& f : scene.faces) {
    WeldedFace g;
    for (auto v : f.vertices) {
      const Eigen::Vector3d& p = scene.vertices[v];
      g.poly.push_back(p);
      const auto it = weld.emplace(std::array<double, 3>{p.x(), p.y(), p.z()},
                                   static_cast<std::int32_t>(weld.size()));
      g.ids.push_back(it.first->second);
    }
    const Eigen::Vector3d n = newell_normal(g.poly);
    g.normal = n.norm() > 0 ? n.normalized() : Eigen::Vector3d::Zero();
    g.lo = g.hi = g.poly[0];
    for (const auto& p : g.poly) {
      g.lo = g.lo.cwiseMin(p);
      g.hi = g.hi.cwiseMax(p);
    }
    out.push_back(std::move(g));
  }
  return out;
}

// Clips the segment a-b to the box [lo, hi] (Liang-Barsky); false when nothing is left.
bool clip_to_box(Eigen::Vector3d& a, Eigen::Vector3d& b, const Eigen::Vector3d& lo,
                 const Eigen::Vector3d& hi) {
  double t0 = 0.0, t1 = 1.0;
  const Eigen::Vector3d d = b - a;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    double ta = (lo[k] - a[k]) / d[k], tb = (hi[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  const Eigen::Vector3d a0 = a;
  a = a0 + t0 * d;
  b = a0 + t1 * d;
  return true;
}

// The sub-interval of [0, 1] where the affine function f(t) = fa + t (fb - fa) is >= 0.
bool clip_interval(double fa, double fb, double& t0, double& t1) {
  if (fa >= 0 && fb >= 0) return t0 <= t1;
  if (fa < 0 && fb < 0) return false;
  const double t = fa / (fa - fb);
  if (fa < 0)
    t0 = std::max(t0, t);
  else
    t1 = std::min(t1, t);
  return t0 < t1;
}

// The length of the part of the segment a-b (on the plane of `poly`, unit normal n) inside
// the polygon: the crossings with its edges cut a-b into intervals, counted where their
// midpoints are inside (crossing number in the plane). Any simple polygon, O(corners).
double length_inside(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Polygon3& poly,
                     const Eigen::Vector3d& n) {
  const Eigen::Vector3d u =
      (std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY())
          .cross(n)
          .normalized();
  const Eigen::Vector3d v = n.cross(u);
  auto to2 = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d((p - poly[0]).dot(u), (p - poly[0]).dot(v));
  };
  const Eigen::Vector2d A = to2(a), D = to2(b) - A;
  std::vector<Eigen::Vector2d> P;
  for (const auto& p : poly) P.push_back(to2(p));
  std::vector<double> ts = {0.0, 1.0};
  auto cross2 = [](const Eigen::Vector2d& x, const Eigen::Vector2d& y) {
    return x.x() * y.y() - x.y() * y.x();
  };
  for (size_t k = 0; k < P.size(); ++k) {
    const Eigen::Vector2d E = P[(k + 1) % P.size()] - P[k];
    const double den = cross2(D, E);
    if (den == 0.0) continue;  // parallel: no transversal crossing
    const double t = cross2(P[k] - A, E) / den, w = cross2(P[k] - A, D) / den;
    if (t > 0.0 && t < 1.0 && w >= 0.0 && w <= 1.0) ts.push_back(t);
  }
  std::sort(ts.begin(), ts.end());
  auto inside = [&](const Eigen::Vector2d& q) {
    bool in = false;
    for (size_t k = 0, j = P.size() - 1; k < P.size(); j = k++)
      if ((P[k].y() > q.y()) != (P[j].y() > q.y()) &&
          q.x() < P[j].x() + (P[k].x() - P[j].x()) * (q.y() - P[j].y()) / (P[k].y() - P[j].y()))
        in = !in;
    return in;
  };
  double t_inside = 0.0;
  for (size_t k = 0; k + 1 < ts.size(); ++k)
    if (ts[k + 1] > ts[k] && inside(A + 0.5 * (ts[k] + ts[k + 1]) * D))
      t_inside += ts[k + 1] - ts[k];
  return t_inside * (b - a).norm();
}

// A wedge line on the receiver, parametrised by u in [0, 1]: the receiver point q(u), the
// blocker feature m(u) it grazes and the source point s(u) it comes from.
struct Wedge {
  Eigen::Vector3d s0, s1;  // source points at u = 0 and 1 (equal for VE)
  Eigen::Vector3d m0, m1;  // blocker points at u = 0 and 1 (equal for EV)
};

}  // namespace

std::vector<std::int32_t> discontinuity_sources(const Scene& scene, int secondary_sources) {
  std::vector<std::int32_t> sources;
  std::vector<char> has_face(scene.surfaces.size(), 0);
  for (const auto& f : scene.faces) has_face[f.surface] = 1;
  for (size_t s = 0; s < scene.surfaces.size(); ++s)
    if (has_face[s] && scene.material_of(static_cast<std::int32_t>(s)).emits())
      sources.push_back(static_cast<std::int32_t>(s));
  if (secondary_sources <= 0) return sources;
  // Reflected power estimate per non-emitting surface.
  std::vector<double> power(scene.surfaces.size(), 0.0);
  std::vector<Polygon3> emitters;
  std::vector<double> emitter_e;
  for (const auto& f : scene.faces) {
    const Material& m = scene.material_of(f.surface);
    if (!m.emits()) continue;
    Polygon3 poly;
    for (auto v : f.vertices) poly.push_back(scene.vertices[v]);
    emitters.push_back(poly);
    emitter_e.push_back(m.emission.mean());
  }
  for (const auto& f : scene.faces) {
    const Material& m = scene.material_of(f.surface);
    if (m.emits()) continue;
    Polygon3 poly;
    for (auto v : f.vertices) poly.push_back(scene.vertices[v]);
    const double area = polygon_area(poly);
    if (!(area > 0)) continue;
    const Eigen::Vector3d n = newell_normal(poly).normalized();
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& p : poly) c += p / static_cast<double>(poly.size());
    const double rho = f.rho ? f.rho->mean() : m.rho.mean();
    double h = 0.0;
    for (size_t e = 0; e < emitters.size(); ++e)
      h += emitter_e[e] * shadowed_point_factor(c, n, emitters[e], {});
    power[f.surface] += rho * area * h;
  }
  std::vector<std::int32_t> order;
  for (size_t s = 0; s < scene.surfaces.size(); ++s)
    if (power[s] > 0) order.push_back(static_cast<std::int32_t>(s));
  std::stable_sort(order.begin(), order.end(),
                   [&](std::int32_t a, std::int32_t b) { return power[a] > power[b]; });
  for (size_t k = 0; k < order.size() && static_cast<int>(k) < secondary_sources; ++k)
    sources.push_back(order[k]);
  return sources;
}

std::vector<DiscontinuitySegment> discontinuity_segments(const Scene& scene,
                                                         const DiscontinuityOptions& options) {
  std::vector<DiscontinuitySegment> out;
  if (scene.faces.empty()) return out;
  const std::vector<WeldedFace> faces = welded_faces(scene);
  const auto [scene_lo, scene_hi] = scene.bounds();
  const double scale = std::max((scene_hi - scene_lo).norm(), 1e-300);
  const double eps = kOnPlane * scale;
  const double piece = options.piece > 0 ? options.piece : scale / 64.0;
  const PatchMesh face_mesh = mesh_scene(scene, MeshOptions{});
  const Bvh bvh(face_mesh, options.threads);
  const double offset = 1e-6 * scale;

  const std::vector<std::int32_t> source_surfaces =
      discontinuity_sources(scene, options.secondary_sources);
  std::vector<std::int32_t> sources;
  for (size_t f = 0; f < faces.size(); ++f)
    if (std::find(source_surfaces.begin(), source_surfaces.end(), scene.faces[f].surface) !=
            source_surfaces.end() &&
        faces[f].normal.squaredNorm() > 0)
      sources.push_back(static_cast<std::int32_t>(f));

  // Unique blocker edges and vertices (welded), each with its position.
  std::map<std::pair<std::int32_t, std::int32_t>, std::pair<Eigen::Vector3d, Eigen::Vector3d>>
      edges;
  std::map<std::int32_t, Eigen::Vector3d> vertices;
  for (const auto& g : faces) {
    for (size_t k = 0; k < g.poly.size(); ++k) {
      const size_t l = (k + 1) % g.poly.size();
      vertices.emplace(g.ids[k], g.poly[k]);
      if (g.ids[k] == g.ids[l]) continue;
      if (g.ids[k] < g.ids[l])
        edges.emplace(std::make_pair(g.ids[k], g.ids[l]), std::make_pair(g.poly[k], g.poly[l]));
      else
        edges.emplace(std::make_pair(g.ids[l], g.ids[k]), std::make_pair(g.poly[l], g.poly[k]));
    }
  }

  // Silhouette culling, per source: a blocker edge between two faces that both face every
  // corner of the source the same way (both towards it or both away: the signs of their
  // planes agree at all its corners, strictly) is on no silhouette seen from any point of
  // the convex source, so its VE wedge bounds no shadow (its visibility test would reject
  // it, at the cost of the rays); a vertex all of whose edges are such is no EV vertex.
  // Boundary and non-manifold edges are kept. On tessellated curved blockers this keeps
  // the silhouettes' few edges out of all of them.
  std::map<std::pair<std::int32_t, std::int32_t>, std::vector<std::int32_t>> edge_faces;
  for (size_t f = 0; f < faces.size(); ++f) {
    const WeldedFace& g = faces[f];
    for (size_t k = 0; k < g.poly.size(); ++k) {
      const std::int32_t a = g.ids[k], b = g.ids[(k + 1) % g.poly.size()];
      if (a != b)
        edge_faces[{std::min(a, b), std::max(a, b)}].push_back(static_cast<std::int32_t>(f));
    }
  }
  auto silhouettes = [&](const WeldedFace& S,
                         std::set<std::pair<std::int32_t, std::int32_t>>& keep_edges,
                         std::set<std::int32_t>& keep_vertices) {
    auto side = [&](std::int32_t f) {  // +1 / -1 when every source corner is strictly on one side
      int sign = 0;
      for (const auto& c : S.poly) {
        const double h = faces[f].height(c);
        const int sg = h > eps ? 1 : h < -eps ? -1 : 0;
        if (sg == 0 || (sign != 0 && sg != sign)) return 0;
        sign = sg;
      }
      return sign;
    };
    for (const auto& [key, fs] : edge_faces) {
      bool keep = fs.size() != 2;
      if (!keep) {
        const int a = side(fs[0]), b = side(fs[1]);
        keep = a == 0 || b == 0 || a != b;
      }
      if (!keep) continue;
      keep_edges.insert(key);
      keep_vertices.insert(key.first);
      keep_vertices.insert(key.second);
    }
  };
  std::vector<std::set<std::pair<std::int32_t, std::int32_t>>> source_edges(faces.size());
  std::vector<std::set<std::int32_t>> source_vertices(faces.size());
  for (std::int32_t sf : sources) silhouettes(faces[sf], source_edges[sf], source_vertices[sf]);

  std::vector<std::vector<DiscontinuitySegment>> per_face(faces.size());
  parallel_for(
      static_cast<std::int64_t>(faces.size()), 1, options.threads,
      [&](std::int64_t begin, std::int64_t end) {
        for (std::int64_t r = begin; r < end; ++r) {
          const WeldedFace& R = faces[r];
          auto& segs = per_face[r];
          if (R.normal.squaredNorm() == 0) continue;
          // Lines run a margin past the face's bounding box, so that they cross its boundary
          // transversally instead of ending at rounding distance from it (a feature Delaunay
          // refinement could not resolve); the mesher keeps only what lies inside the faces.
          // A line with (almost) nothing inside the face polygon is dropped: it is no
          // discontinuity of the face, and one running just outside an edge at a small angle
          // (the wedges of a neighbour's edge on a slightly warped wall) made the refinement
          // chase the sliver between them all along the edge.
          const double pad = kOverrun * (R.hi - R.lo).norm() + eps;
          const Eigen::Vector3d lo = R.lo - Eigen::Vector3d::Constant(pad);
          const Eigen::Vector3d hi = R.hi + Eigen::Vector3d::Constant(pad);
          auto add = [&](Eigen::Vector3d a, Eigen::Vector3d b, int order) {
            if (!clip_to_box(a, b, lo, hi) || (b - a).norm() <= eps) return;
            if (length_inside(a, b, R.poly, R.normal) > kMinInside * (R.hi - R.lo).norm())
              segs.push_back({a, b, order, static_cast<std::int32_t>(r)});
          };

          // D0: blocker faces touching or piercing the receiver's plane.
          for (size_t b = 0; b < faces.size(); ++b) {
            if (static_cast<std::int64_t>(b) == r) continue;
            const WeldedFace& B = faces[b];
            std::vector<double> h;
            bool off_plane = false;
            for (const auto& p : B.poly) {
              h.push_back(R.height(p));
              off_plane = off_plane || std::abs(h.back()) > eps;
            }
            if (!off_plane) continue;  // coplanar: part of the receiver's plane, not a blocker
            std::vector<std::array<int, 3>> tris;
            if (B.poly.size() == 3)
              tris.push_back({0, 1, 2});
            else
              tris = triangulate(B.poly);
            for (const auto& t : tris) {
              std::vector<Eigen::Vector3d> on;
              for (int k = 0; k < 3; ++k) {
                const int i = t[k], j = t[(k + 1) % 3];
                if (std::abs(h[i]) <= eps) on.push_back(B.poly[i]);
                if ((h[i] > eps && h[j] < -eps) || (h[i] < -eps && h[j] > eps))
                  on.push_back(B.poly[i] + (h[i] / (h[i] - h[j])) * (B.poly[j] - B.poly[i]));
              }
              if (on.size() < 2) continue;
              size_t ia = 0, ib = 1;
              for (size_t i = 0; i < on.size(); ++i)
                for (size_t j = i + 1; j < on.size(); ++j)
                  if ((on[i] - on[j]).squaredNorm() > (on[ia] - on[ib]).squaredNorm())
                    ia = i, ib = j;
              add(on[ia] - R.height(on[ia]) * R.normal, on[ib] - R.height(on[ib]) * R.normal, 0);
            }
          }

          // D1/D2: VE and EV wedges of each source with every blocker edge and vertex.
          auto trace = [&](const Wedge& w) {
            // Receiver point of parameter u: the line s(u) -> m(u) meets the receiver's plane.
            auto at = [&](double u, Eigen::Vector3d& q, Eigen::Vector3d& s, Eigen::Vector3d& m) {
              s = (1 - u) * w.s0 + u * w.s1;
              m = (1 - u) * w.m0 + u * w.m1;
              const double hs = R.height(s), hm = R.height(m);
              q = s + (m - s) * (hs / (hs - hm));
              q -= R.height(q) * R.normal;  // on the plane to rounding
            };
            Eigen::Vector3d q0, q1, s, m;
            at(0, q0, s, m);
            at(1, q1, s, m);
            Eigen::Vector3d c0 = q0, c1 = q1;
            if (!clip_to_box(c0, c1, lo, hi)) return;
            const int n =
                std::clamp(static_cast<int>(std::ceil((q1 - q0).norm() / piece)), 1, kMaxPieces);
            auto free_line = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
              const Eigen::Vector3d d = to - from;
              return !bvh.occluded(from.cast<float>(), d.cast<float>(), 0.0f,
                                   static_cast<float>(1.0 - kGrazeStop));
            };
            int run_start = -1;
            for (int k = 0; k <= n; ++k) {
              bool visible = false;
              if (k < n) {
                Eigen::Vector3d q;
                at((k + 0.5) / n, q, s, m);
                const bool inside =
                    (q.array() >= lo.array()).all() && (q.array() <= hi.array()).all();
                visible = inside && free_line(q + offset * R.normal, m) &&
                          free_line(s + offset * (m - s).normalized(), m);
              }
              if (visible && run_start < 0) run_start = k;
              if (!visible && run_start >= 0) {
                Eigen::Vector3d a, b;
                at(static_cast<double>(run_start) / n, a, s, m);
                at(static_cast<double>(k) / n, b, s, m);
                add(a, b, 1);
                run_start = -1;
              }
            }
          };
          for (std::int32_t sf : sources) {
            if (sf == r) continue;
            const WeldedFace& S = faces[sf];
            double hs_max = -INFINITY;
            for (const auto& p : S.poly) hs_max = std::max(hs_max, R.height(p));
            if (hs_max <= eps) continue;  // the source is behind the receiver
            bool receiver_in_front = false;
            for (const auto& p : R.poly) receiver_in_front = receiver_in_front || S.height(p) > eps;
            if (!receiver_in_front) continue;
            // VE: source vertex, blocker edge (the edge's part between the receiver's plane and
            // the source vertex's height, in front of the source).
            for (const auto& sv : S.poly) {
              const double hs = R.height(sv);
              if (hs <= eps) continue;
              for (const auto& [key, e] : edges) {
                if (!source_edges[sf].count(key)) continue;
                double t0 = 0, t1 = 1;
                const double ha = R.height(e.first), hb = R.height(e.second);
                if (!clip_interval(ha - eps, hb - eps, t0, t1)) continue;
                const double top = hs * (1 - kVanishing);
                if (!clip_interval(top - ha, top - hb, t0, t1)) continue;
                if (!clip_interval(S.height(e.first) - eps, S.height(e.second) - eps, t0, t1))
                  continue;
                Wedge w;
                w.s0 = w.s1 = sv;
                w.m0 = e.first + t0 * (e.second - e.first);
                w.m1 = e.first + t1 * (e.second - e.first);
                trace(w);
              }
            }
            // EV: source edge, blocker vertex (the edge's part above the vertex's height).
            for (size_t k = 0; k < S.poly.size(); ++k) {
              const Eigen::Vector3d& a = S.poly[k];
              const Eigen::Vector3d& b = S.poly[(k + 1) % S.poly.size()];
              for (const auto& [id, p] : vertices) {
                if (!source_vertices[sf].count(id)) continue;
                const double hp = R.height(p);
                if (hp <= eps || S.height(p) <= eps) continue;
                double t0 = 0, t1 = 1;
                const double floor_h = hp + kVanishing * (hs_max - hp) + eps;
                if (!clip_interval(R.height(a) - floor_h, R.height(b) - floor_h, t0, t1)) continue;
                Wedge w;
                w.s0 = a + t0 * (b - a);
                w.s1 = a + t1 * (b - a);
                w.m0 = w.m1 = p;
                trace(w);
              }
            }
          }
        }
      });
  for (auto& segs : per_face) out.insert(out.end(), segs.begin(), segs.end());
  return out;
}

}  // namespace lambert
