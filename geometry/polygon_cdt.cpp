// Triangulation of a large simple polygon in O(n log n): the constrained Delaunay
// triangulation of its boundary (CGAL), keeping the faces inside it (odd nesting depth from
// the infinite face). Ear clipping (polygon.cpp) is O(n^2) or worse for a non-convex polygon:
// a 10^5-corner floor outline would take hours.

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_face_base_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <deque>
#include <utility>

#include "geometry/polygon.hpp"

namespace lambert {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using Fbi = CGAL::Triangulation_face_base_with_info_2<int, K>;  // nesting depth, -1 = unset
using Fb = CGAL::Constrained_triangulation_face_base_2<K, Fbi>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt =
    CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::No_constraint_intersection_tag>;
}  // namespace

std::optional<std::vector<std::array<int, 3>>> triangulate_simple(
    const std::vector<Eigen::Vector2d>& p) {
  const int m = static_cast<int>(p.size());
  if (m < 3) return std::nullopt;
  Cdt cdt;
  std::vector<Cdt::Vertex_handle> v(m);
  try {
    for (int k = 0; k < m; ++k) {
      v[k] =
          cdt.insert(K::Point_2(p[k].x(), p[k].y()), k > 0 ? v[k - 1]->face() : Cdt::Face_handle());
      if (cdt.number_of_vertices() != static_cast<std::size_t>(k) + 1)
        return std::nullopt;  // a corner repeated: not simple
      v[k]->info() = k;
    }
    for (int k = 0; k < m; ++k) cdt.insert_constraint(v[k], v[(k + 1) % m]);
  } catch (const std::exception&) {
    return std::nullopt;  // crossing edges (No_constraint_intersection_tag): not simple
  }
  if (cdt.number_of_vertices() != static_cast<std::size_t>(m)) return std::nullopt;
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
  // Flood fill: depth 0 from the infinite face, +1 across each constrained edge.
  std::deque<std::pair<Cdt::Face_handle, int>> seeds{{cdt.infinite_face(), 0}};
  while (!seeds.empty()) {
    auto [start, depth] = seeds.front();
    seeds.pop_front();
    if (start->info() != -1) continue;
    std::deque<Cdt::Face_handle> queue{start};
    start->info() = depth;
    while (!queue.empty()) {
      const Cdt::Face_handle f = queue.front();
      queue.pop_front();
      for (int e = 0; e < 3; ++e) {
        const Cdt::Face_handle n = f->neighbor(e);
        if (n->info() != -1) continue;
        if (cdt.is_constrained({f, e})) {
          seeds.push_back({n, depth + 1});
        } else {
          n->info() = depth;
          queue.push_back(n);
        }
      }
    }
  }
  std::vector<std::array<int, 3>> tris;
  tris.reserve(m - 2);
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
    if (f->info() % 2 == 1)
      tris.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  // A simple polygon of m corners has exactly m - 2 triangles inside.
  if (static_cast<int>(tris.size()) != m - 2) return std::nullopt;
  return tris;
}

}  // namespace lambert
