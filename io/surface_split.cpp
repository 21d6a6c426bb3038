#include "io/surface_split.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

// Union-find over faces, path halving.
std::int32_t piece_root(std::vector<std::int32_t>& parent, std::int32_t f) {
  while (parent[f] != f) f = parent[f] = parent[parent[f]];
  return f;
}

// The angle between two normals in degrees, in [0, 180] (atan2 keeps small angles exact,
// unlike acos of the dot product).
double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * (180.0 / M_PI);
}

// One face edge: its corner indices ordered (a < b), the face.
struct EdgeUse {
  std::int32_t a, b, face;
  bool operator<(const EdgeUse& o) const {
    return a != o.a ? a < o.a : b != o.b ? b < o.b : face < o.face;
  }
};

// Each vertex's lowest-numbered twin at exactly its position (-0 and +0 one position): an OBJ
// may repeat a corner under several indices; STL and PLY corners are shared already.
// O(V log V).
std::vector<std::int32_t> position_ids(const std::vector<Eigen::Vector3d>& vertices) {
  const auto n = static_cast<std::int32_t>(vertices.size());
  std::vector<std::int32_t> order(n), id(n);
  for (std::int32_t i = 0; i < n; ++i) order[i] = i;
  const auto key = [&](std::int32_t i) {
    const Eigen::Vector3d p = vertices[i] + Eigen::Vector3d::Zero();
    return std::make_tuple(p.x(), p.y(), p.z());
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::int32_t a, std::int32_t b) { return key(a) < key(b); });
  for (std::int32_t k = 0; k < n; ++k)
    id[order[k]] = k > 0 && key(order[k]) == key(order[k - 1]) ? id[order[k - 1]] : order[k];
  return id;
}

}  // namespace

void split_surfaces_at_feature_edges(Scene& scene, double max_angle_deg, const std::string& name) {
  const auto n = static_cast<std::int32_t>(scene.faces.size());
  std::vector<Eigen::Vector3d> normal(n);
  const std::vector<std::int32_t> at = position_ids(scene.vertices);
  std::vector<EdgeUse> edges;
  for (std::int32_t f = 0; f < n; ++f) {
    const auto& v = scene.faces[f].vertices;
    std::vector<Eigen::Vector3d> poly;
    for (std::int32_t i : v) poly.push_back(scene.vertices[i]);
    normal[f] = newell_normal(poly);
    for (size_t k = 0; k < v.size(); ++k) {
      const std::int32_t p = at[v[k]], q = at[v[(k + 1) % v.size()]];
      if (p != q) edges.push_back({std::min(p, q), std::max(p, q), f});
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::int32_t> parent(n);
  for (std::int32_t f = 0; f < n; ++f) parent[f] = f;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) ++j;
    // Exactly two faces on the edge (manifold), of one surface, bent by at most DEG.
    if (j - i == 2) {
      const std::int32_t f = edges[i].face, g = edges[i + 1].face;
      if (f != g && scene.faces[f].surface == scene.faces[g].surface &&
          angle_deg(normal[f], normal[g]) <= max_angle_deg + kSplitAngleSlackDeg)
        parent[piece_root(parent, f)] = piece_root(parent, g);
    }
    i = j;
  }
  // The pieces of each surface, in order of their first face.
  const auto surfaces = static_cast<std::int32_t>(scene.surfaces.size());
  std::vector<std::vector<std::int32_t>> roots_of(surfaces);  // per surface, first-face order
  std::vector<std::int32_t> rank(n, -1);  // root -> its number within its surface
  for (std::int32_t f = 0; f < n; ++f) {
    const std::int32_t r = piece_root(parent, f);
    if (rank[r] >= 0) continue;
    auto& list = roots_of[scene.faces[f].surface];
    rank[r] = static_cast<std::int32_t>(list.size());
    list.push_back(r);
  }
  std::vector<Surface> out;
  std::vector<std::int32_t> first(surfaces);  // surface -> index of its first piece in `out`
  std::set<std::string> old_names, new_names;
  for (const Surface& s : scene.surfaces) old_names.insert(s.name);
  for (std::int32_t s = 0; s < surfaces; ++s) {
    first[s] = static_cast<std::int32_t>(out.size());
    const size_t pieces = roots_of[s].size();
    if (pieces <= 1) {  // whole (or without faces): unchanged
      out.push_back(scene.surfaces[s]);
      continue;
    }
    for (size_t k = 0; k < pieces; ++k) {
      Surface piece = scene.surfaces[s];
      piece.name += "/face_" + std::to_string(k + 1);
      if (old_names.count(piece.name) || !new_names.insert(piece.name).second)
        throw SceneError(name + ": --split-angle names a piece '" + piece.name +
                         "', which is already a surface's name: rename that surface");
      out.push_back(std::move(piece));
    }
  }
  for (std::int32_t f = 0; f < n; ++f) {
    Face& face = scene.faces[f];
    face.surface = first[face.surface] + rank[piece_root(parent, f)];
  }
  scene.surfaces = std::move(out);
}

}  // namespace lambert
