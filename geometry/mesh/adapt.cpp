#include "geometry/mesh/adapt.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "core/error.hpp"
#include "geometry/render/vertex_field.hpp"
#include "geometry/visibility/direct_light.hpp"

namespace lambert {
namespace {

Patch child_of(const PatchMesh& mesh, const Patch& parent, std::array<std::int32_t, 4> v) {
  Patch p = make_patch(mesh, v, 3);
  p.rho = parent.rho;
  p.emission = parent.emission;
  p.surface = parent.surface;
  return p;
}

}  // namespace

RefinedMesh triangulate_quads(const PatchMesh& mesh) {
  RefinedMesh out;
  out.mesh = mesh;
  out.mesh.patches.clear();
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    if (p.vertex_count == 3) {
      out.mesh.patches.push_back(p);
      out.origin.push_back(i);
      out.changed.push_back(0);
      continue;
    }
    const auto& v = p.vertices;
    const auto& x = mesh.vertices;
    // The shorter diagonal (a convex quad: both halves have positive area).
    const bool d02 = (x[v[0]] - x[v[2]]).squaredNorm() <= (x[v[1]] - x[v[3]]).squaredNorm();
    const std::array<std::array<std::int32_t, 4>, 2> halves =
        d02 ? std::array<std::array<std::int32_t, 4>, 2>{{{v[0], v[1], v[2], 0},
                                                          {v[0], v[2], v[3], 0}}}
            : std::array<std::array<std::int32_t, 4>, 2>{
                  {{v[0], v[1], v[3], 0}, {v[1], v[2], v[3], 0}}};
    for (const auto& h : halves) {
      out.mesh.patches.push_back(child_of(out.mesh, p, h));
      out.origin.push_back(i);
      out.changed.push_back(1);
    }
  }
  return out;
}

std::vector<double> patch_errors(const PatchMesh& mesh, const Eigen::MatrixX3d& B) {
  LAMBERT_CHECK(B.rows() == mesh.size(), "patch_errors: B does not match the mesh");
  std::unordered_map<std::uint64_t, std::vector<std::int32_t>> edges;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    for (int k = 0; k < p.vertex_count; ++k)
      edges[edge_key(p.vertices[k], p.vertices[(k + 1) % p.vertex_count])].push_back(i);
  }
  std::vector<double> jump(mesh.size(), 0.0);
  for (const auto& [key, ps] : edges) {
    for (size_t a = 0; a < ps.size(); ++a)
      for (size_t b = a + 1; b < ps.size(); ++b) {
        const double d = std::abs(B.row(ps[a]).mean() - B.row(ps[b]).mean());
        jump[ps[a]] = std::max(jump[ps[a]], d);
        jump[ps[b]] = std::max(jump[ps[b]], d);
      }
  }
  std::vector<double> e(mesh.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) e[i] = 0.5 * mesh.patches[i].area * jump[i];
  return e;
}

std::vector<double> field_patch_errors(const PatchMesh& mesh, const Eigen::MatrixX3d& B) {
  LAMBERT_CHECK(B.rows() == mesh.size(), "field_patch_errors: B does not match the mesh");
  const VertexField f = interpolate_to_vertices(mesh, B, VertexInterpolation::LinearFit);
  std::vector<double> e(mesh.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    double mean = 0.0;  // the field's mean over the patch (exact on a triangle)
    for (int k = 0; k < p.vertex_count; ++k) mean += f.values.row(f.patch_corners[i][k]).mean();
    mean /= p.vertex_count;
    e[i] = p.area * std::abs(B.row(i).mean() - mean);
  }
  return e;
}

std::vector<double> exact_direct_patch_errors(const Scene& scene, const PatchMesh& mesh,
                                              const Eigen::MatrixX3d& indirect, int threads) {
  LAMBERT_CHECK(indirect.rows() == mesh.size(),
                "exact_direct_patch_errors: I does not match the mesh");
  // Per patch: its corners, then its edge midpoints, at its own normal.
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<std::int64_t> first(mesh.size() + 1, 0);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    first[i] = static_cast<std::int64_t>(points.size());
    for (int k = 0; k < p.vertex_count; ++k) points.push_back(mesh.vertices[p.vertices[k]]);
    for (int k = 0; k < p.vertex_count; ++k)
      points.push_back(0.5 * (mesh.vertices[p.vertices[k]] +
                              mesh.vertices[p.vertices[(k + 1) % p.vertex_count]]));
    normals.resize(points.size(), p.normal);
  }
  const Eigen::MatrixX3d H = exact_direct_irradiance(scene, points, normals, threads);
  Eigen::MatrixX3d reflected = indirect;
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    reflected.row(i).array() *= mesh.patches[i].rho.transpose().array();
  std::vector<double> e = patch_errors(mesh, reflected);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    const std::int64_t c = first[i], m = c + p.vertex_count;
    double worst = 0.0;
    for (int k = 0; k < p.vertex_count; ++k) {
      const double mid = H.row(m + k).mean();
      const double lin = 0.5 * (H.row(c + k).mean() + H.row(c + (k + 1) % p.vertex_count).mean());
      worst = std::max(worst, std::abs(mid - lin));
    }
    e[i] += p.area * p.rho.mean() * worst;
  }
  return e;
}

RefinedMesh refine_marked(const PatchMesh& mesh, const std::vector<char>& marked) {
  LAMBERT_CHECK(static_cast<std::int32_t>(marked.size()) == mesh.size(),
                "refine: marks do not match");
  RefinedMesh out;
  out.mesh = mesh;
  PatchMesh& m = out.mesh;
  std::vector<Patch>& tris = m.patches;
  std::vector<std::int32_t> origin(mesh.size());
  std::vector<char> alive(mesh.size(), 1), changed(mesh.size(), 0);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    LAMBERT_CHECK(tris[i].vertex_count == 3, "refine: every patch must be a triangle");
    origin[i] = i;
  }
  std::unordered_map<std::uint64_t, std::vector<std::int32_t>> on_edge;
  auto link = [&](std::int32_t t) {
    for (int k = 0; k < 3; ++k)
      on_edge[edge_key(tris[t].vertices[k], tris[t].vertices[(k + 1) % 3])].push_back(t);
  };
  auto unlink = [&](std::int32_t t) {
    for (int k = 0; k < 3; ++k) {
      auto& v = on_edge[edge_key(tris[t].vertices[k], tris[t].vertices[(k + 1) % 3])];
      v.erase(std::remove(v.begin(), v.end(), t), v.end());
    }
  };
  for (std::int32_t t = 0; t < mesh.size(); ++t) link(t);
  // The longest edge of t as its first corner index k (edge k -> k+1); ties by vertex ids.
  auto longest = [&](std::int32_t t) {
    int best = 0;
    auto len = [&](int k) {
      const auto a = tris[t].vertices[k], b = tris[t].vertices[(k + 1) % 3];
      return std::make_tuple((m.vertices[a] - m.vertices[b]).squaredNorm(), std::min(a, b),
                             std::max(a, b));
    };
    for (int k = 1; k < 3; ++k)
      if (len(k) > len(best)) best = k;
    return best;
  };
  auto edge_of = [&](std::int32_t t, int k) {
    return edge_key(tris[t].vertices[k], tris[t].vertices[(k + 1) % 3]);
  };
  // Bisects every triangle on edge (a, b) at its midpoint.
  auto bisect = [&](std::int32_t a, std::int32_t b) {
    const std::vector<std::int32_t> around = on_edge[edge_key(a, b)];
    const auto mid = static_cast<std::int32_t>(m.vertices.size());
    m.vertices.push_back(0.5 * (m.vertices[a] + m.vertices[b]));
    m.vertex_surface.push_back(m.vertex_surface[a]);
    for (std::int32_t t : around) {
      unlink(t);
      alive[t] = 0;
      const auto v = tris[t].vertices;
      int k = 0;
      while (edge_key(v[k], v[(k + 1) % 3]) != edge_key(a, b)) ++k;
      const auto p = v[k], q = v[(k + 1) % 3], r = v[(k + 2) % 3];
      const Patch parent = tris[t];
      for (const auto& c :
           {std::array<std::int32_t, 4>{p, mid, r, 0}, std::array<std::int32_t, 4>{mid, q, r, 0}}) {
        tris.push_back(child_of(m, parent, c));
        alive.push_back(1);
        changed.push_back(1);
        origin.push_back(origin[t]);
        link(static_cast<std::int32_t>(tris.size() - 1));
      }
    }
  };
  for (std::int32_t t0 = 0; t0 < mesh.size(); ++t0) {
    if (!marked[t0]) continue;
    while (alive[t0]) {
      // Walk the longest-edge propagation path from t0 to a terminal edge and bisect it.
      std::int32_t t = t0;
      for (int guard = 0;; ++guard) {
        LAMBERT_CHECK(guard < 1000000, "refine: longest-edge path did not terminate");
        const int k = longest(t);
        const auto e = edge_of(t, k);
        std::int32_t next = -1;
        for (std::int32_t n : on_edge[e])
          if (n != t && edge_of(n, longest(n)) != e) next = n;
        if (next < 0) {
          bisect(tris[t].vertices[k], tris[t].vertices[(k + 1) % 3]);
          break;
        }
        t = next;
      }
    }
  }
  std::vector<Patch> kept;
  for (size_t t = 0; t < tris.size(); ++t) {
    if (!alive[t]) continue;
    kept.push_back(tris[t]);
    out.origin.push_back(origin[t]);
    out.changed.push_back(changed[t]);
  }
  tris = std::move(kept);
  return out;
}

}  // namespace lambert
