#pragma once
// The element and cluster hierarchy of the hierarchical method (internal to geometry/).
//
// Nodes live in one vector. Root elements are the faces of the scene (one PatchMesh patch
// each, from mesh_scene without an edge bound); a binary cluster tree sits above them,
// built bottom-up by median splits of the face centroids along the longest axis of their
// bounding box (deterministic: the order of faces decides ties). Elements get 4 children on
// demand (split_element): triangles 4 similar triangles through the edge midpoints 0.5 (a + b),
// quads 4 quads through the edge midpoints and the bilinear centre. Children tile their
// parent exactly, so areas add up and neighbours that split to the same depth share their
// vertices bit for bit.
//
// Not thread-safe for mutation (split_element); reads are.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/sampling.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/mesh/mesh.hpp"

namespace lambert::hr {

/// One node: a cluster (children are nodes of either kind) or an element (a planar
/// triangle or quad on one face; children are its 4 sub-elements).
struct Node {
  std::int32_t parent = -1;
  std::int32_t first_child = -1;  ///< children are first_child .. first_child + child_count - 1
  std::int32_t second_child = -1; ///< clusters: the second child (children are not contiguous)
  std::int8_t child_count = 0;
  bool cluster = false;
  std::int8_t depth = 0;          ///< element depth below its face (0 = the face)
  std::int32_t face = -1;         ///< elements: the face (patch of the face mesh) it lies on
  double area = 0.0;              ///< total surface area below the node
  Eigen::AlignedBox3d box;        ///< bounding box of the surfaces below
  /// Projected front area below the node towards the six axis directions +x, -x, +y, -y,
  /// +z, -z: sum over its faces of A max(0, ±n_a). A cluster receiving light from direction
  /// e_b hands it on in proportion to these (oriented push, hierarchical.cpp).
  std::array<double, 6> facing{};
};

/// The hierarchy over one scene's faces.
class Hierarchy {
 public:
  /// Root elements from the patches of `faces` (one per face), clusters above them.
  explicit Hierarchy(PatchMesh faces);

  const PatchMesh& faces() const { return faces_; }
  const std::vector<Node>& nodes() const { return nodes_; }
  const Node& node(std::int32_t i) const { return nodes_[i]; }
  /// Geometry of an element node (unused for clusters).
  const ff::PatchGeom& geom(std::int32_t i) const { return geom_[i]; }
  std::int32_t root() const { return root_; }
  std::int32_t size() const { return static_cast<std::int32_t>(nodes_.size()); }
  std::int64_t clusters() const { return clusters_; }

  /// Child k of node i.
  std::int32_t child(std::int32_t i, int k) const {
    const Node& n = nodes_[i];
    return n.cluster ? (k == 0 ? n.first_child : n.second_child) : n.first_child + k;
  }
  /// True when i is an element that has not been split.
  bool is_leaf(std::int32_t i) const { return nodes_[i].child_count == 0; }

  /// Gives element i its 4 children (no-op if it has them). Invalidates references.
  void split_element(std::int32_t i);

  /// A point of the surfaces below node i, uniform in area, with its element's normal;
  /// descends the tree choosing children by area (u picks the child, its remainder is
  /// reused), then samples the element with (v, w); `warp` is the element's (ff::quad_warp of
  /// the face it lies on: the surface the BVH traces).
  Eigen::Vector3d sample_point(std::int32_t i, double u, double v, double w,
                               Eigen::Vector3d& normal, double& warp) const;
  /// sample_point's descent for n numbers u at once: element[k] is where u[k] leads below
  /// node i, and u[k] becomes its remainder (what sample_point passes to element_point).
  void descend(std::int32_t i, int n, std::int32_t* element, double* u) const;
  /// The point of element e at (u, v, w) (sample_point below the descent).
  Eigen::Vector3d element_point(std::int32_t e, double u, double v, double w,
                                Eigen::Vector3d& normal, double& warp) const;

  /// Bytes held by nodes and element geometry.
  double bytes() const;
  /// Makes room for `n` nodes in all (no reallocation while splitting up to there).
  void reserve(std::size_t n);

 private:
  std::int32_t build_clusters(std::vector<std::int32_t>& elements, std::size_t begin,
                              std::size_t end);

  /// A cluster's children and the first one's share of its area: what sample_point's
  /// descent reads, 16 bytes per cluster instead of two Nodes.
  struct ClusterStep {
    std::int32_t first, second;
    double first_share;
  };

  PatchMesh faces_;
  std::vector<Node> nodes_;
  std::vector<ClusterStep> steps_;  ///< cluster n + k (n faces) is steps_[k]
  std::vector<ff::PatchGeom> geom_;
  std::int32_t root_ = -1;
  std::int64_t clusters_ = 0;
};

/// Corner weights mu_k (sum 1) of the mean over element g of the field interpolated from
/// corner values (linear on triangles: 1/3 each; bilinear on quads: the integral of each
/// bilinear hat times the Jacobian over the area, exact with the 2 x 2 Gauss rule).
std::array<double, 4> corner_masses(const ff::PatchGeom& g);

/// Interpolation weights of the corners at parameter (u, v) of ff::quadrature_point
/// (triangles: the collapsed map, (1-u, u(1-v), uv); quads: bilinear).
std::array<double, 4> corner_weights(const ff::PatchGeom& g, double u, double v);

/// A max(0, ±n_a) for the six axis directions (Node::facing) of a planar element.
std::array<double, 6> facing(const Eigen::Vector3d& normal, double area);

/// Squared distance between two boxes (0 when they overlap or touch).
double box_distance_squared(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b);

}  // namespace lambert::hr
