#include "geometry/hierarchical/hierarchy.hpp"

#include <algorithm>
#include <numeric>
#include <utility>

#include "core/error.hpp"
#include "geometry/polygon.hpp"

namespace lambert::hr {
namespace {

Eigen::AlignedBox3d box_of(const ff::PatchGeom& g) {
  Eigen::AlignedBox3d b;
  for (int k = 0; k < g.n; ++k) b.extend(g.p[k]);
  return b;
}

// Frame of a sub-element: area and centroid from its corners (the normal is its face's).
void finish_geom(ff::PatchGeom& g) {
  std::vector<Eigen::Vector3d> poly(g.p.begin(), g.p.begin() + g.n);
  g.area = polygon_area(poly);
  if (g.n == 3) {
    g.p[3] = g.p[2];
    g.centroid = (g.p[0] + g.p[1] + g.p[2]) / 3.0;
  } else {
    // Area centroid of a planar quad: area-weighted centroids of the triangles (0,1,2), (0,2,3).
    const double a1 = 0.5 * (g.p[1] - g.p[0]).cross(g.p[2] - g.p[0]).norm();
    const double a2 = 0.5 * (g.p[2] - g.p[0]).cross(g.p[3] - g.p[0]).norm();
    const Eigen::Vector3d c1 = (g.p[0] + g.p[1] + g.p[2]) / 3.0;
    const Eigen::Vector3d c2 = (g.p[0] + g.p[2] + g.p[3]) / 3.0;
    g.centroid = a1 + a2 > 0 ? Eigen::Vector3d((a1 * c1 + a2 * c2) / (a1 + a2))
                             : Eigen::Vector3d(0.25 * (g.p[0] + g.p[1] + g.p[2] + g.p[3]));
  }
  g.diameter = 0.0;
  for (int a = 0; a < g.n; ++a)
    for (int b = a + 1; b < g.n; ++b) g.diameter = std::max(g.diameter, (g.p[a] - g.p[b]).norm());
}

Eigen::Vector3d mid(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return 0.5 * (a + b); }

}  // namespace

std::array<double, 4> corner_masses(const ff::PatchGeom& g) {
  if (g.n == 3) return {1.0 / 3, 1.0 / 3, 1.0 / 3, 0.0};
  std::array<double, 4> mu{0, 0, 0, 0};
  const ff::GaussRule rule = ff::gauss_legendre(2);
  double total = 0.0;
  for (int a = 0; a < rule.n; ++a)
    for (int b = 0; b < rule.n; ++b) {
      double jacobian = 0.0;
      ff::quadrature_point(g, rule.x[a], rule.x[b], jacobian);
      const auto w = corner_weights(g, rule.x[a], rule.x[b]);
      const double dw = rule.w[a] * rule.w[b] * jacobian;
      for (int k = 0; k < 4; ++k) mu[k] += dw * w[k];
      total += dw;
    }
  for (double& m : mu) m /= total;
  return mu;
}

std::array<double, 4> corner_weights(const ff::PatchGeom& g, double u, double v) {
  if (g.n == 3) return {1.0 - u, u * (1.0 - v), u * v, 0.0};
  return {(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v};
}

std::array<double, 6> facing(const Eigen::Vector3d& normal, double area) {
  std::array<double, 6> f{};
  for (int a = 0; a < 3; ++a) {
    f[2 * a] = area * std::max(0.0, normal[a]);
    f[2 * a + 1] = area * std::max(0.0, -normal[a]);
  }
  return f;
}

double box_distance_squared(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b) {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max({0.0, a.min()[k] - b.max()[k], b.min()[k] - a.max()[k]});
    d2 += gap * gap;
  }
  return d2;
}

Hierarchy::Hierarchy(PatchMesh faces) : faces_(std::move(faces)) {
  const std::int32_t n = faces_.size();
  if (n == 0) throw SceneError("the scene has no faces");
  geom_ = ff::patch_geometry(faces_);
  nodes_.resize(n);
  for (std::int32_t i = 0; i < n; ++i) {
    Node& node = nodes_[i];
    node.face = i;
    node.area = geom_[i].area;
    node.box = box_of(geom_[i]);
    node.facing = facing(geom_[i].normal, node.area);
  }
  std::vector<std::int32_t> elements(n);
  std::iota(elements.begin(), elements.end(), 0);
  root_ = build_clusters(elements, 0, elements.size());
  // The clusters are nodes [n, n + clusters_): their descent steps side by side.
  steps_.reserve(static_cast<std::size_t>(clusters_));
  for (std::int64_t c = 0; c < clusters_; ++c) {
    const Node& node = nodes_[static_cast<std::size_t>(n + c)];
    steps_.push_back(
        {node.first_child, node.second_child, nodes_[node.first_child].area / node.area});
  }
}

std::int32_t Hierarchy::build_clusters(std::vector<std::int32_t>& elements, std::size_t begin,
                                       std::size_t end) {
  if (end - begin == 1) return elements[begin];
  Eigen::AlignedBox3d centres;
  for (std::size_t k = begin; k < end; ++k) centres.extend(geom_[elements[k]].centroid);
  int axis = 0;
  centres.diagonal().maxCoeff(&axis);
  const std::size_t half = begin + (end - begin) / 2;
  // Median split; ties broken by face index so the tree is a function of the scene alone.
  std::nth_element(elements.begin() + begin, elements.begin() + half, elements.begin() + end,
                   [&](std::int32_t a, std::int32_t b) {
                     const double ca = geom_[a].centroid[axis], cb = geom_[b].centroid[axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const std::int32_t left = build_clusters(elements, begin, half);
  const std::int32_t right = build_clusters(elements, half, end);
  const std::int32_t id = static_cast<std::int32_t>(nodes_.size());
  Node c;
  c.cluster = true;
  c.first_child = left;
  c.second_child = right;
  c.child_count = 2;
  c.area = nodes_[left].area + nodes_[right].area;
  c.box = nodes_[left].box.merged(nodes_[right].box);
  for (int b = 0; b < 6; ++b) c.facing[b] = nodes_[left].facing[b] + nodes_[right].facing[b];
  nodes_.push_back(c);
  geom_.emplace_back();
  nodes_[left].parent = id;
  nodes_[right].parent = id;
  ++clusters_;
  return id;
}

void Hierarchy::split_element(std::int32_t i) {
  LAMBERT_CHECK(!nodes_[i].cluster, "split_element on a cluster");
  if (nodes_[i].child_count > 0) return;
  const ff::PatchGeom g = geom_[i];
  std::array<ff::PatchGeom, 4> kids;
  if (g.n == 3) {
    const Eigen::Vector3d m01 = mid(g.p[0], g.p[1]), m12 = mid(g.p[1], g.p[2]),
                          m20 = mid(g.p[2], g.p[0]);
    const Eigen::Vector3d corners[4][3] = {
        {g.p[0], m01, m20}, {m01, g.p[1], m12}, {m20, m12, g.p[2]}, {m12, m20, m01}};
    for (int k = 0; k < 4; ++k) {
      kids[k].n = 3;
      for (int c = 0; c < 3; ++c) kids[k].p[c] = corners[k][c];
    }
  } else {
    const Eigen::Vector3d m01 = mid(g.p[0], g.p[1]), m12 = mid(g.p[1], g.p[2]),
                          m23 = mid(g.p[2], g.p[3]), m30 = mid(g.p[3], g.p[0]);
    const Eigen::Vector3d c = 0.25 * (g.p[0] + g.p[1] + g.p[2] + g.p[3]);
    const Eigen::Vector3d corners[4][4] = {{g.p[0], m01, c, m30},
                                           {m01, g.p[1], m12, c},
                                           {c, m12, g.p[2], m23},
                                           {m30, c, m23, g.p[3]}};
    for (int k = 0; k < 4; ++k) {
      kids[k].n = 4;
      for (int v = 0; v < 4; ++v) kids[k].p[v] = corners[k][v];
    }
  }
  const std::int32_t first = static_cast<std::int32_t>(nodes_.size());
  const Node parent = nodes_[i];
  for (auto& kid : kids) {
    kid.normal = g.normal;
    kid.warp = g.warp;  // its corners lie on the face's bilinear surface: inside its tetrahedron
    finish_geom(kid);
    Node n;
    n.parent = i;
    n.face = parent.face;
    n.depth = static_cast<std::int8_t>(parent.depth + 1);
    n.area = kid.area;
    n.box = box_of(kid);
    n.facing = facing(kid.normal, kid.area);
    nodes_.push_back(n);
    geom_.push_back(kid);
  }
  nodes_[i].first_child = first;
  nodes_[i].child_count = 4;
}

void Hierarchy::descend(std::int32_t i, int n, std::int32_t* element, double* u) const {
  // Descend by area: u in [0,1) picks a child with probability A_child / A_node and is
  // rescaled to [0,1) within that child's share, so one number serves every level (its
  // precision, 53 bits, covers any depth lambert builds). Both outcomes are computed and
  // one selected (no branch to mispredict), all n descents a level at a time (their chains
  // of divisions overlap).
  const std::int32_t first_cluster = faces_.size();
  const auto is_cluster = [&](std::int32_t k) {
    return k >= first_cluster && k - first_cluster < clusters_;
  };
  for (int k = 0; k < n; ++k) element[k] = i;
  for (bool active = is_cluster(i); active;) {
    active = false;
    for (int k = 0; k < n; ++k) {
      if (!is_cluster(element[k])) continue;
      const ClusterStep& step = steps_[static_cast<std::size_t>(element[k] - first_cluster)];
      const double pa = step.first_share;
      const bool first = u[k] < pa;
      const double in_first = u[k] / pa;
      const double in_second = pa < 1.0 ? (u[k] - pa) / (1.0 - pa) : 0.0;
      u[k] = std::min(first ? in_first : in_second, 1.0 - 0x1.0p-53);
      element[k] = first ? step.first : step.second;
      active = active || is_cluster(element[k]);
    }
  }
  // The elements' geometry is what element_point reads next: ask for it now, all at once.
  for (int k = 0; k < n; ++k) {
    const char* g = reinterpret_cast<const char*>(&geom_[static_cast<std::size_t>(element[k])]);
    for (std::size_t line = 0; line < sizeof(ff::PatchGeom); line += 64)
      __builtin_prefetch(g + line);
    __builtin_prefetch(g + sizeof(ff::PatchGeom) - 1);
  }
}

Eigen::Vector3d Hierarchy::element_point(std::int32_t e, double u, double v, double w,
                                         Eigen::Vector3d& normal, double& warp) const {
  // Uniform in area. A quad is two triangles (0,1,2), (0,2,3) chosen by area with u; a
  // triangle is sampled by the folded parallelogram (exact).
  const ff::PatchGeom& g = geom_[e];
  normal = g.normal;
  warp = g.warp;
  Eigen::Vector3d a = g.p[0], b = g.p[1], c = g.p[2];
  if (g.n == 4) {
    const double a1 = (g.p[1] - g.p[0]).cross(g.p[2] - g.p[0]).norm();
    const double a2 = (g.p[2] - g.p[0]).cross(g.p[3] - g.p[0]).norm();
    if (u * (a1 + a2) >= a1) {
      b = g.p[2];
      c = g.p[3];
    }
  }
  if (v + w > 1.0) {
    v = 1.0 - v;
    w = 1.0 - w;
  }
  return a + v * (b - a) + w * (c - a);
}

Eigen::Vector3d Hierarchy::sample_point(std::int32_t i, double u, double v, double w,
                                        Eigen::Vector3d& normal, double& warp) const {
  std::int32_t e = i;
  descend(i, 1, &e, &u);
  return element_point(e, u, v, w, normal, warp);
}

void Hierarchy::reserve(std::size_t n) {
  nodes_.reserve(n);
  geom_.reserve(n);
}

double Hierarchy::bytes() const {
  return static_cast<double>(nodes_.capacity()) * sizeof(Node) +
         static_cast<double>(geom_.capacity()) * sizeof(ff::PatchGeom) +
         static_cast<double>(steps_.capacity()) * sizeof(ClusterStep);
}

}  // namespace lambert::hr
