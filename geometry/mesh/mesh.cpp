#include "geometry/mesh/mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <unordered_map>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/sampling.hpp"
#include "geometry/mesh/discontinuity.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

// A triangle or quad of one surface, by surface-local vertex ids.
struct Element {
  std::array<std::int32_t, 4> v{};
  int n = 3;
  Eigen::Vector3d rho = Eigen::Vector3d::Zero();  ///< its face's (or else its material's)
};

// The elements of one surface before subdivision, with welded vertices.
struct SurfaceElements {
  std::vector<Eigen::Vector3d> points;
  std::vector<Element> elements;
};

// `faces`: the indices of the surface's faces, in scene order.
SurfaceElements collect(const Scene& scene, std::int32_t surface,
                        const std::vector<std::int32_t>& faces) {
  SurfaceElements out;
  std::map<std::array<double, 3>, std::int32_t> weld;  // exact-position welding
  auto local = [&](const Eigen::Vector3d& p) {
    const std::array<double, 3> key{p.x(), p.y(), p.z()};
    auto it = weld.find(key);
    if (it != weld.end()) return it->second;
    const auto id = static_cast<std::int32_t>(out.points.size());
    out.points.push_back(p);
    weld.emplace(key, id);
    return id;
  };
  std::vector<Eigen::Vector3d> poly;
  const Eigen::Vector3d& material_rho = scene.material_of(surface).rho;
  for (const std::int32_t fi : faces) {
    const auto& f = scene.faces[fi];
    const Eigen::Vector3d rho = f.rho ? *f.rho : material_rho;
    poly.clear();
    for (auto v : f.vertices) poly.push_back(scene.vertices[v]);
    if (polygon_area(poly) <= 0.0) continue;
    if (poly.size() == 3 || (poly.size() == 4 && is_convex(poly))) {
      Element e;
      e.n = static_cast<int>(poly.size());
      e.rho = rho;
      for (int k = 0; k < e.n; ++k) e.v[k] = local(poly[k]);
      out.elements.push_back(e);
      continue;
    }
    // The polygon's scale: its bounding box's diagonal (the exact diameter was an O(n²) pair
    // scan: seconds for a 20,000-gon).
    const double diam = polygon_extent(poly);
    for (const auto& t : triangulate(poly)) {
      // Skip the slivers of collinear corners: zero area up to rounding, no normal. The cross
      // product of two edges shorter than diam errs by a few eps diam² (eps = 2.2e-16), so
      // 1e-13 diam² keeps every real triangle above 500x rounding: the ears of a fine convex
      // polygon (consecutive corners 3e-4 rad apart on a circle: area 1.5e-11) are real
      // area, and a relative 1e-10 (the loader's whole-face test) dropped them.
      const double area = 0.5 * (poly[t[1]] - poly[t[0]]).cross(poly[t[2]] - poly[t[0]]).norm();
      if (area <= 1e-13 * diam * diam) continue;
      Element e;
      e.rho = rho;
      for (int k = 0; k < 3; ++k) e.v[k] = local(poly[t[k]]);
      out.elements.push_back(e);
    }
  }
  return out;
}

// The conformity constraints of mesh_scene as classes of edges: a triangle's three edges get
// one segment count (a uniform n x n split), a quad's opposite edges one each, and an edge
// shared by two elements has one count. The classes are the connected components of that
// "same count" relation (union-find, near O(E)), so that the count of a class is the largest
// ceil(length / max_edge) among its edges: what a fixpoint of pairwise maxima converges to,
// without its passes (a chain of n elements, such as the fan of a convex n-gon, took O(n²)).
struct EdgeClasses {
  std::unordered_map<std::uint64_t, std::int32_t> edge;  ///< edge key -> class
  std::vector<double> longest;                           ///< per class: its longest edge
};

EdgeClasses edge_classes(const SurfaceElements& s) {
  std::unordered_map<std::uint64_t, std::int32_t> id;  // edge key -> edge index
  std::vector<double> length;
  auto edge_of = [&](const Element& e, int k) {
    const auto a = e.v[k % e.n], b = e.v[(k + 1) % e.n];
    const auto [it, added] = id.emplace(edge_key(a, b), static_cast<std::int32_t>(length.size()));
    if (added) length.push_back((s.points[a] - s.points[b]).norm());
    return it->second;
  };
  std::vector<std::int32_t> parent;
  auto find = [&](std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];  // path halving
    return x;
  };
  auto unite = [&](std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  std::vector<std::array<std::int32_t, 4>> element_edges;
  element_edges.reserve(s.elements.size());
  for (const auto& e : s.elements) {
    std::array<std::int32_t, 4> ids{};
    for (int k = 0; k < e.n; ++k) ids[k] = edge_of(e, k);
    element_edges.push_back(ids);
  }
  parent.resize(length.size());
  for (std::size_t k = 0; k < parent.size(); ++k) parent[k] = static_cast<std::int32_t>(k);
  for (std::size_t i = 0; i < s.elements.size(); ++i) {
    const auto& ids = element_edges[i];
    if (s.elements[i].n == 3) {
      unite(ids[0], ids[1]);
      unite(ids[1], ids[2]);
    } else {
      unite(ids[0], ids[2]);
      unite(ids[1], ids[3]);
    }
  }
  EdgeClasses c;
  std::vector<std::int32_t> class_of_root(parent.size(), -1);
  for (std::size_t k = 0; k < parent.size(); ++k) {
    const auto r = find(static_cast<std::int32_t>(k));
    if (class_of_root[r] < 0) {
      class_of_root[r] = static_cast<std::int32_t>(c.longest.size());
      c.longest.push_back(0.0);
    }
  }
  c.edge.reserve(id.size());
  for (const auto& [key, k] : id) {
    const auto cls = class_of_root[find(k)];
    c.edge.emplace(key, cls);
    c.longest[cls] = std::max(c.longest[cls], length[k]);
  }
  return c;
}

// Segments on an edge class whose longest edge is `longest`, for `max_edge` (1 when max_edge
// <= 0: one element per face). Capped at 1e9 segments so that counts and their products stay
// inside int64; any such mesh is refused by mesh_scene's patch limit anyway.
std::int64_t segments(double longest, double max_edge) {
  if (max_edge <= 0) return 1;
  return static_cast<std::int64_t>(std::clamp(std::ceil(longest / max_edge), 1.0, 1e9));
}

// Segments per class for `max_edge`.
std::vector<std::int64_t> class_counts(const EdgeClasses& c, double max_edge) {
  std::vector<std::int64_t> n(c.longest.size());
  for (std::size_t k = 0; k < n.size(); ++k) n[k] = segments(c.longest[k], max_edge);
  return n;
}

// Segment counts per edge satisfying the conformity constraints (see mesh_scene).
std::unordered_map<std::uint64_t, std::int64_t> edge_counts(const EdgeClasses& c, double max_edge) {
  const std::vector<std::int64_t> n = class_counts(c, max_edge);
  std::unordered_map<std::uint64_t, std::int64_t> count;
  count.reserve(c.edge.size());
  for (const auto& [key, cls] : c.edge) count.emplace(key, n[cls]);
  return count;
}

// total + w a b, saturating at INT64_MAX (a plan for an absurd edge bound must still be
// refused by the patch limit, not wrap around).
std::int64_t add_product(std::int64_t total, std::int64_t w, std::int64_t a, std::int64_t b) {
  std::int64_t p = 0;
  if (__builtin_mul_overflow(w, a, &p) || __builtin_mul_overflow(p, b, &p) ||
      __builtin_add_overflow(total, p, &p))
    return INT64_MAX;
  return p;
}

// The patch count of one surface as a function of the edge bound h, in closed form over its
// edge classes. With n_c(h) = segments(L_c, h) on class c (L_c its longest edge), a triangle
// of class c makes n_c² patches and a quad whose opposite-edge pairs are classes a and b
// makes n_a n_b, so
//   count(h) = sum_c T_c n_c(h)² + sum_(a,b) Q_ab n_a(h) n_b(h),
// T_c and Q_ab the numbers of such elements: exactly the sum over elements that subdivide
// makes, in integers. Built once per surface in O(elements) (hashing); an evaluation costs
// O(terms), the distinct classes of triangles and class pairs of quads, instead of a hash
// lookup per element: a connected triangle mesh (a scan) is one class, one term.
struct SurfaceCount {
  struct Term {
    double la = 0.0, lb = 0.0;  ///< the longest edges of the term's classes (la = lb: triangles)
    std::int64_t elements = 0;  ///< T_c or Q_ab
  };
  std::vector<Term> terms;
  std::int64_t elements = 0;  ///< the surface's elements (one patch each when h is coarse)
  double area = 0.0;          ///< their area (scene units²)
};

// The closed form of the surface's count (O(elements)).
SurfaceCount surface_count(const SurfaceElements& s, const EdgeClasses& c, double area) {
  SurfaceCount out;
  out.elements = static_cast<std::int64_t>(s.elements.size());
  out.area = area;
  const auto classes = static_cast<std::uint64_t>(c.longest.size());
  std::unordered_map<std::uint64_t, std::int32_t> term;  // a * classes + b (a = b: triangles)
  for (const auto& e : s.elements) {
    const std::uint64_t a = static_cast<std::uint64_t>(c.edge.at(edge_key(e.v[0], e.v[1])));
    const std::uint64_t b =
        e.n == 3 ? a : static_cast<std::uint64_t>(c.edge.at(edge_key(e.v[1], e.v[2])));
    const auto [it, added] =
        term.emplace(a * classes + b, static_cast<std::int32_t>(out.terms.size()));
    if (added) out.terms.push_back({c.longest[a], c.longest[b], 0});
    ++out.terms[it->second].elements;
  }
  return out;
}

// Patches of one surface at `max_edge` (O(terms); counted in `stats`).
std::int64_t count_patches(const SurfaceCount& s, double max_edge, MeshPlanStats& stats) {
  std::int64_t total = 0;
  for (const auto& t : s.terms)
    total = add_product(total, t.elements, segments(t.la, max_edge), segments(t.lb, max_edge));
  stats.terms += static_cast<std::int64_t>(s.terms.size());
  return total;
}

}  // namespace

Patch make_patch(const PatchMesh& mesh, std::array<std::int32_t, 4> v, int n) {
  Patch p;
  p.vertices = v;
  p.vertex_count = n;
  const auto& a = mesh.vertices[v[0]];
  const auto& b = mesh.vertices[v[1]];
  const auto& c = mesh.vertices[v[2]];
  Eigen::Vector3d cross1 = (b - a).cross(c - a);
  const double a1 = 0.5 * cross1.norm();
  Eigen::Vector3d centroid = a1 * (a + b + c) / 3.0;
  Eigen::Vector3d nrm = cross1;
  double area = a1;
  if (n == 4) {
    const auto& d = mesh.vertices[v[3]];
    const Eigen::Vector3d cross2 = (c - a).cross(d - a);
    const double a2 = 0.5 * cross2.norm();
    centroid += a2 * (a + c + d) / 3.0;
    nrm += cross2;
    area += a2;
  }
  p.area = area;
  p.centroid = centroid / area;
  p.normal = nrm.normalized();
  return p;
}

namespace {

// Emits the patches of one surface into `mesh`.
void subdivide(const SurfaceElements& s, const EdgeClasses& classes, double max_edge,
               std::int32_t surface, const Material& mat, PatchMesh& mesh) {
  const auto count = edge_counts(classes, max_edge);
  auto new_vertex = [&](const Eigen::Vector3d& p) {
    mesh.vertices.push_back(p);
    mesh.vertex_surface.push_back(surface);
    return static_cast<std::int32_t>(mesh.vertices.size() - 1);
  };
  std::vector<std::int32_t> corner(s.points.size());
  for (size_t k = 0; k < s.points.size(); ++k) corner[k] = new_vertex(s.points[k]);
  // Shared points along each edge, stored from the lower to the higher local id.
  std::unordered_map<std::uint64_t, std::vector<std::int32_t>> edge_points;
  auto edge_point = [&](std::int32_t a, std::int32_t b, std::int64_t t) -> std::int32_t {
    const auto n = count.at(edge_key(a, b));
    auto& pts = edge_points[edge_key(a, b)];
    if (pts.empty()) {
      const std::int32_t lo = std::min(a, b), hi = std::max(a, b);
      pts.push_back(corner[lo]);
      for (std::int64_t k = 1; k < n; ++k) {
        const double u = static_cast<double>(k) / static_cast<double>(n);
        pts.push_back(new_vertex((1.0 - u) * s.points[lo] + u * s.points[hi]));
      }
      pts.push_back(corner[hi]);
    }
    return a < b ? pts[t] : pts[n - t];
  };
  const Eigen::Vector3d* rho = nullptr;  // of the element being subdivided
  auto emit = [&](std::array<std::int32_t, 4> v, int n) {
    Patch p = make_patch(mesh, v, n);
    p.rho = *rho;
    p.emission = mat.emission;
    p.surface = surface;
    mesh.patches.push_back(p);
  };
  for (const auto& e : s.elements) {
    const auto& P = s.points;
    rho = &e.rho;
    if (e.n == 3) {
      const std::int64_t n = count.at(edge_key(e.v[0], e.v[1]));
      // Grid point (a, b), a + b <= n: v0 + a/n (v1 - v0) + b/n (v2 - v0).
      std::vector<std::int32_t> id((n + 1) * (n + 1), -1);
      auto at = [&](std::int64_t a, std::int64_t b) -> std::int32_t& {
        return id[a * (n + 1) + b];
      };
      for (std::int64_t a = 0; a <= n; ++a) {
        for (std::int64_t b = 0; a + b <= n; ++b) {
          if (b == 0)
            at(a, b) = edge_point(e.v[0], e.v[1], a);
          else if (a == 0)
            at(a, b) = edge_point(e.v[0], e.v[2], b);
          else if (a + b == n)
            at(a, b) = edge_point(e.v[1], e.v[2], b);
          else
            at(a, b) =
                new_vertex(P[e.v[0]] + (static_cast<double>(a) / n) * (P[e.v[1]] - P[e.v[0]]) +
                           (static_cast<double>(b) / n) * (P[e.v[2]] - P[e.v[0]]));
        }
      }
      for (std::int64_t a = 0; a < n; ++a) {
        for (std::int64_t b = 0; a + b < n; ++b) {
          emit({at(a, b), at(a + 1, b), at(a, b + 1), 0}, 3);
          if (a + b < n - 1) emit({at(a + 1, b), at(a + 1, b + 1), at(a, b + 1), 0}, 3);
        }
      }
    } else {
      const std::int64_t nu = count.at(edge_key(e.v[0], e.v[1]));
      const std::int64_t nv = count.at(edge_key(e.v[1], e.v[2]));
      // Grid point (a, b): bilinear in the quad; a along v0->v1, b along v0->v3.
      std::vector<std::int32_t> id((nu + 1) * (nv + 1), -1);
      auto at = [&](std::int64_t a, std::int64_t b) -> std::int32_t& {
        return id[a * (nv + 1) + b];
      };
      for (std::int64_t a = 0; a <= nu; ++a) {
        for (std::int64_t b = 0; b <= nv; ++b) {
          if (b == 0)
            at(a, b) = edge_point(e.v[0], e.v[1], a);
          else if (b == nv)
            at(a, b) = edge_point(e.v[3], e.v[2], a);
          else if (a == 0)
            at(a, b) = edge_point(e.v[0], e.v[3], b);
          else if (a == nu)
            at(a, b) = edge_point(e.v[1], e.v[2], b);
          else {
            const double u = static_cast<double>(a) / nu, w = static_cast<double>(b) / nv;
            at(a, b) = new_vertex((1 - u) * (1 - w) * P[e.v[0]] + u * (1 - w) * P[e.v[1]] +
                                  u * w * P[e.v[2]] + (1 - u) * w * P[e.v[3]]);
          }
        }
      }
      for (std::int64_t a = 0; a < nu; ++a)
        for (std::int64_t b = 0; b < nv; ++b)
          emit({at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)}, 4);
    }
  }
}

}  // namespace

std::vector<Eigen::Vector3d> PatchMesh::corners(std::int32_t i) const {
  const auto& p = patches[i];
  std::vector<Eigen::Vector3d> c;
  for (int k = 0; k < p.vertex_count; ++k) c.push_back(vertices[p.vertices[k]]);
  return c;
}

namespace {

std::string shortest(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// Every surface's elements, faces bucketed by surface first: O(faces + surfaces), where a
// scan of every face for every surface was quadratic on scenes of many one-face surfaces.
std::vector<SurfaceElements> collect_all(const Scene& scene) {
  std::vector<std::vector<std::int32_t>> faces(scene.surfaces.size());
  for (std::size_t f = 0; f < scene.faces.size(); ++f) {
    const auto surface = scene.faces[f].surface;
    LAMBERT_CHECK(surface >= 0 && static_cast<std::size_t>(surface) < faces.size(),
                  "a face of no surface");
    faces[surface].push_back(static_cast<std::int32_t>(f));
  }
  std::vector<SurfaceElements> surfaces;
  surfaces.reserve(scene.surfaces.size());
  for (size_t s = 0; s < scene.surfaces.size(); ++s)
    surfaces.push_back(collect(scene, static_cast<std::int32_t>(s), faces[s]));
  return surfaces;
}

// The area of a surface's elements (scene units²).
double elements_area(const SurfaceElements& s) {
  double a = 0.0;
  for (const auto& e : s.elements) {
    const auto& P = s.points;
    a += 0.5 * (P[e.v[1]] - P[e.v[0]]).cross(P[e.v[2]] - P[e.v[0]]).norm();
    if (e.n == 4) a += 0.5 * (P[e.v[2]] - P[e.v[0]]).cross(P[e.v[3]] - P[e.v[0]]).norm();
  }
  return a;
}

// Every surface's closed-form count (SurfaceCount), from its elements and edge classes.
std::vector<SurfaceCount> surface_counts(const std::vector<SurfaceElements>& surfaces,
                                         const std::vector<EdgeClasses>& classes) {
  std::vector<SurfaceCount> counts;
  counts.reserve(surfaces.size());
  for (std::size_t k = 0; k < surfaces.size(); ++k)
    counts.push_back(surface_count(surfaces[k], classes[k], elements_area(surfaces[k])));
  return counts;
}

// The patch target is met by area: a surface that the edge h subdivides counts its patches;
// one that h leaves as its own elements (a detailed object finer than h, or a small face)
// counts its area share A_s / h², not its element count. So a 3,000-triangle bunny in a box
// takes its area's share of the budget and the walls keep theirs (it took 3,000 of 3,020 and
// left every wall one patch); the mesh then exceeds the target by the detail it cannot drop,
// and the plan says so. A surface under the floor (floor[s] > 0) counts at least the floor.
// Non-increasing in h. One evaluation, O(surfaces + terms).
double scene_budget(const std::vector<SurfaceCount>& counts, const std::vector<int>& floor,
                    double h, MeshPlanStats& stats) {
  ++stats.evaluations;
  double t = 0.0;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const SurfaceCount& s = counts[k];
    const std::int64_t c = count_patches(s, h, stats);
    const double share = c > s.elements
                             ? static_cast<double>(c)
                             : std::min(static_cast<double>(s.elements), s.area / (h * h));
    t += std::max(share, static_cast<double>(floor[k]));
  }
  return t;
}

// The floor of each surface (0: none): `floor` patches for the largest surfaces by area
// (ties by index), as many as a quarter of the target allows (a scene of thousands of small
// surfaces must not spend its budget on floors); none without a target or with a floor <= 1.
std::vector<int> surface_floors(const std::vector<SurfaceCount>& counts,
                                const MeshOptions& options) {
  std::vector<int> floor(counts.size(), 0);
  if (options.target_patches <= 0 || options.surface_floor <= 1 || options.discontinuity)
    return floor;
  const auto cap = static_cast<std::size_t>(options.target_patches / 4 / options.surface_floor);
  std::vector<std::size_t> order(counts.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  const std::size_t n = std::min(cap, order.size());
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n), order.end(),
                    [&](std::size_t a, std::size_t b) {
                      return counts[a].area != counts[b].area ? counts[a].area > counts[b].area
                                                              : a < b;
                    });
  for (std::size_t k = 0; k < n; ++k) floor[order[k]] = options.surface_floor;
  return floor;
}

// The largest edge bound below h that gives surface s (with fewer than `floor` patches at h)
// at least `floor` patches: by 64 geometric bisection steps down to h x 1e-6 (counts are
// non-increasing in the edge; a surface that no edge in that range raises keeps h).
double floor_edge(const SurfaceCount& s, int floor, double h, MeshPlanStats& stats) {
  if (floor <= 1 || h <= 0) return h;
  double lo = h * 1e-6, hi = h;  // count(lo) >= floor > count(hi)
  if (count_patches(s, lo, stats) < floor) return h;
  for (int it = 0; it < 64; ++it) {
    const double mid = std::sqrt(lo * hi);
    (count_patches(s, mid, stats) >= floor ? lo : hi) = mid;
  }
  return lo;
}

// The edge bound whose budget is closest to `target`: 60 geometric bisection steps between
// 1e-4 and 1 scene diagonal, so 63 evaluations of scene_budget whatever the input size
// (O(63 (surfaces + terms)) in all).
double search_edge(const Scene& scene, const std::vector<SurfaceCount>& counts,
                   const std::vector<int>& floor, double target, MeshPlanStats& stats) {
  const auto [lo_corner, hi_corner] = scene.bounds();
  double hi = (hi_corner - lo_corner).norm();  // one element per edge or fewer
  double lo = hi * 1e-4;
  if (scene_budget(counts, floor, lo, stats) < target) return lo;
  for (int it = 0; it < 60; ++it) {
    const double mid = std::sqrt(lo * hi);
    (scene_budget(counts, floor, mid, stats) > target ? lo : hi) = mid;
  }
  // Pick whichever bracket is closer to the target.
  const double at_lo = scene_budget(counts, floor, lo, stats),
               at_hi = scene_budget(counts, floor, hi, stats);
  return std::abs(at_lo - target) < std::abs(at_hi - target) ? lo : hi;
}

// The log line for a mesh of `made` patches that exceeds `target` by more than 10 %: the
// detail that made it (surfaces that keep one patch per face), or the mesh's steps.
std::string detail_note(const Scene& scene, const std::vector<SurfaceCount>& counts,
                        std::int64_t target, double max_edge, std::int64_t made,
                        MeshPlanStats& stats) {
  ++stats.evaluations;  // every surface's count at max_edge
  std::size_t worst = 0, detailed = 0;
  std::int64_t worst_elements = -1, detail_faces = 0;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const std::int64_t elements = counts[k].elements;
    if (count_patches(counts[k], max_edge, stats) != elements || elements < 2) continue;
    ++detailed;
    detail_faces += elements;
    if (elements > worst_elements) {
      worst = k;
      worst_elements = elements;
    }
  }
  if (detailed == 0)  // the mesh's steps: no edge length gives closer to the target
    return "meshing: " + thousands(made) + " patches for the target of " + thousands(target) +
           ": the count near it that the uniform subdivision of these faces gives (" +
           thousands(static_cast<std::int64_t>(scene.faces.size())) +
           " faces; --max-edge or --patches to choose)";
  return "meshing: the target of " + thousands(target) + " patches grew to " + thousands(made) +
         ": " +
         (detailed == 1
              ? std::string("a detailed surface keeps")
              : thousands(static_cast<std::int64_t>(detailed)) + " detailed surfaces keep") +
         " one patch per face (" + thousands(detail_faces) + " faces; the largest, '" +
         scene.surfaces[worst].name + "', has " + thousands(worst_elements) +
         "); the others get their area's share";
}

// The plan from every surface's closed-form count: one evaluation, O(surfaces + terms), for
// an edge bound; for a patch target 63 for the search, 1 for the count (2 with the note),
// and for each surface under its floor up to 66 counts of its own (terms, not evaluations).
MeshPlan plan_counts(const Scene& scene, const std::vector<SurfaceCount>& counts,
                     const MeshOptions& options) {
  LAMBERT_CHECK(options.max_edge >= 0 && options.target_patches >= 0, "negative mesh target");
  MeshPlan plan;
  plan.max_edge = options.max_edge;
  const std::vector<int> floor = surface_floors(counts, options);
  if (plan.max_edge <= 0 && options.target_patches > 0)
    plan.max_edge =
        search_edge(scene, counts, floor, static_cast<double>(options.target_patches), plan.stats);
  // One evaluation of every surface at the edge bound; a surface under its floor gets its own
  // finer bound (floor_edge) and is counted at it.
  ++plan.stats.evaluations;
  std::vector<double> edge(counts.size(), plan.max_edge);
  std::int64_t added = 0;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    std::int64_t c = count_patches(counts[k], plan.max_edge, plan.stats);
    if (c < floor[k]) {
      edge[k] = floor_edge(counts[k], floor[k], plan.max_edge, plan.stats);
      if (edge[k] != plan.max_edge) {
        const std::int64_t raised = count_patches(counts[k], edge[k], plan.stats);
        ++plan.floored;
        added += raised - c;
        c = raised;
      }
    }
    plan.patches = add_product(plan.patches, 1, c, 1);
  }
  if (plan.floored > 0) {
    plan.surface_edge = std::move(edge);
    const auto covered = static_cast<std::int64_t>(
        std::count_if(floor.begin(), floor.end(), [](int f) { return f > 0; }));
    plan.floor_note = "meshing: " + thousands(plan.floored) + " small surface" +
                      (plan.floored == 1 ? "" : "s") + " raised to the floor of " +
                      std::to_string(options.surface_floor) + " patches (+" + thousands(added) +
                      " patches";
    if (covered < static_cast<std::int64_t>(counts.size()))
      plan.floor_note += "; the floor covers the " + thousands(covered) + " largest of " +
                         thousands(static_cast<std::int64_t>(counts.size())) +
                         " surfaces, a quarter of the target";
    plan.floor_note += "; --surface-floor to change)";
  }
  if (options.target_patches > 0 &&
      static_cast<double>(plan.patches) > 1.1 * static_cast<double>(options.target_patches) &&
      options.max_edge <= 0)
    plan.note =
        detail_note(scene, counts, options.target_patches, plan.max_edge, plan.patches, plan.stats);
  return plan;
}

// Every surface's edge classes (O(elements) hashing).
std::vector<EdgeClasses> all_edge_classes(const std::vector<SurfaceElements>& surfaces) {
  std::vector<EdgeClasses> classes;
  classes.reserve(surfaces.size());
  for (const auto& s : surfaces) classes.push_back(edge_classes(s));
  return classes;
}

}  // namespace

MeshPlan plan_mesh(const Scene& scene, const MeshOptions& options) {
  const std::vector<SurfaceElements> surfaces = collect_all(scene);
  return plan_counts(scene, surface_counts(surfaces, all_edge_classes(surfaces)), options);
}

double mesh_peak_bytes(std::int64_t patches) {
  // Per patch: the Patch itself, about one vertex (position and surface id), 2x capacity
  // while the vectors grow; and the Embree BVH over the quads (float corners and index,
  // about 4 x 16 + 16 bytes per primitive plus nodes, ~128 bytes).
  const double per_patch =
      2.0 * (sizeof(Patch) + sizeof(Eigen::Vector3d) + sizeof(std::int32_t)) + 128.0;
  return static_cast<double>(patches) * per_patch;
}

PatchMesh mesh_scene(const Scene& scene, const MeshOptions& options) {
  const std::vector<SurfaceElements> surfaces = collect_all(scene);
  const std::vector<EdgeClasses> classes = all_edge_classes(surfaces);
  const MeshPlan plan = plan_counts(scene, surface_counts(surfaces, classes), options);
  const double max_edge = plan.max_edge;
  if (plan.patches > kMaxPatches)
    throw UsageError("meshing with max edge " + shortest(max_edge) + " would make " +
                     std::to_string(plan.patches) + " patches (limit " +
                     std::to_string(kMaxPatches) + "): choose a larger --max-edge");

  if (options.discontinuity) {
    DiscontinuityOptions d;
    d.secondary_sources = options.discontinuity_sources;
    d.piece = max_edge / 2.0;  // 0 (one element per face): discontinuity.hpp's default
    d.threads = options.threads;
    const std::vector<DiscontinuitySegment> lines = discontinuity_segments(scene, d);
    // Lines add patches beyond the uniform plan (a few times it on the Cornell box); the
    // final mesh passing 16 times the plan means lines at the rounding scale: refused at once,
    // not after minutes (kMaxPatches at the most). A first pass that the correction step
    // meshes again may pass it legitimately (a tessellated sphere's lines: 40 times a target
    // of 2,000, corrected to under 5 times), so it gets up to 200,000 patches.
    const bool corrected = options.max_edge <= 0 && options.target_patches > 0 && max_edge > 0;
    ConstrainedLimits limits;
    limits.planned = std::max<std::int64_t>(plan.patches, options.target_patches);
    const std::int64_t final_cap =
        std::min<std::int64_t>(kMaxPatches, 16 * std::max<std::int64_t>(limits.planned, 1000));
    limits.max_patches = corrected ? std::max<std::int64_t>(final_cap, 200000) : final_cap;
    limits.warn = !corrected;  // the correction's pass says what went short
    PatchMesh mesh = mesh_scene_constrained(scene, max_edge, lines, limits);
    if (corrected && mesh.size() > 0) {
      // Patches scale as 1 / max_edge^2 away from the constraints: one correction step.
      const double h = max_edge * std::sqrt(static_cast<double>(mesh.size()) /
                                            static_cast<double>(options.target_patches));
      limits.warn = true;
      limits.max_patches = final_cap;
      mesh = mesh_scene_constrained(scene, h, lines, limits);
    }
    return mesh;
  }

  PatchMesh mesh;
  copy_surfaces(scene, mesh);
  const auto [lo, hi] = scene.bounds();
  mesh.max_edge = max_edge;
  mesh.scale = scene.faces.empty() ? 1.0 : std::max((hi - lo).norm(), 1e-300);
  for (size_t s = 0; s < surfaces.size(); ++s) {
    const double edge = plan.surface_edge.empty() ? max_edge : plan.surface_edge[s];
    subdivide(surfaces[s], classes[s], edge, static_cast<std::int32_t>(s),
              scene.material_of(static_cast<std::int32_t>(s)), mesh);
  }
  LAMBERT_CHECK(mesh.patches.size() < static_cast<size_t>(INT32_MAX), "too many patches");
  return mesh;
}

void copy_surfaces(const Scene& scene, PatchMesh& mesh) {
  bool specular = false;
  for (const auto& s : scene.surfaces) {
    mesh.surface_names.push_back(s.name);
    specular = specular || scene.materials[s.material].specular.any();
  }
  if (!specular) return;
  for (const auto& s : scene.surfaces)
    mesh.surface_specular.push_back(scene.materials[s.material].specular);
}

std::uint64_t mesh_hash(const PatchMesh& mesh) {
  std::uint64_t h = mix64(mesh.patches.size());
  auto add = [&](double x) {
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    h = mix64(h ^ bits);
  };
  for (const auto& p : mesh.patches) {
    for (int k = 0; k < p.vertex_count; ++k)
      for (int d = 0; d < 3; ++d) add(mesh.vertices[p.vertices[k]][d]);
    add(static_cast<double>(p.surface));
  }
  // Specular surfaces change where rays go, so they are part of what F was computed for
  // (purely diffuse meshes hash as before).
  for (const Specular& sp : mesh.surface_specular) {
    for (int c = 0; c < 3; ++c) add(sp.reflectance[c]), add(sp.transmission[c]);
    add(sp.dielectric ? sp.ior : -1.0);
  }
  return h;
}

}  // namespace lambert
