#pragma once
// Exact direct light at points: the irradiance that arrives straight from the emitters,
//
//   H_d(x) = Σ_e E_e F_{dx→e, visible}        (W/m² per channel, E in the scene's units),
//
// with every emitting face e of the scene a uniform Lambertian source of radiosity E_e (its
// surface material's emission) and every other face a blocker. Each factor is exact up to
// rounding (shadow.hpp: the visible part of e from x by CGAL polygon booleans, Lambert's
// contour formula on it), so H_d is exact across penumbrae, umbrae and contact lines,
// where patch constants and Monte Carlo rays are not. Per-vertex radiosity uses it
// (vertex_field.hpp, VertexInterpolation::ExactDirect).
//
// Blockers for a point x and an emitter e: the faces whose bounding boxes meet the box of
// x and e (nothing outside it can lie on a segment from x to e), except e itself and faces
// whose plane passes through x (within kPlaneRelEps of the scene's size: from x such a
// face projects onto a line and hides nothing; it is x's own face, or a crease neighbour).
// Faces block from both sides, as the Embree rays of the estimators do.
//
// Complexity: O(emitters × faces) box tests per point plus one polygon difference per
// (point, emitter) over the k blockers in the box, O(k log k); meant for the vertices of a
// mesh (10³–10⁵ points) on scenes of up to some thousand faces. Thread safety: the points
// are split over `threads` threads, each writing only its own rows; deterministic (each
// row is a pure function of its point).

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "geometry/polygon.hpp"
#include "geometry/scene.hpp"

namespace lambert {

/// The exact direct irradiance H_d of one point at a time (the kernel of
/// exact_direct_irradiance), with the scene's faces prepared once. Keeps a reference to the
/// scene, which must outlive it. Queries are const and thread-safe.
class DirectLight {
 public:
  /// Prepares the faces (bounds, planes) and the list of emitting faces: O(faces).
  explicit DirectLight(const Scene& scene);
  /// True when nothing emits (H_d = 0 everywhere).
  bool empty() const;
  /// H_d (RGB, W/m²) at x (on its surface's plane) with unit front normal `normal`.
  Eigen::Vector3d irradiance(const Eigen::Vector3d& x, const Eigen::Vector3d& normal) const;
  /// The same with a caller-owned scratch list of blockers (no allocation once it is large).
  Eigen::Vector3d irradiance(const Eigen::Vector3d& x, const Eigen::Vector3d& normal,
                             std::vector<Polygon3>& blockers) const;

 private:
  struct Faces;
  const Scene& scene_;
  std::shared_ptr<const Faces> faces_;
};

/// Exact direct irradiance H_d (rows: per point; columns R, G, B) at `points` with unit
/// front normals `normals`, from every emitting face of `scene`. 0 where nothing emits.
Eigen::MatrixX3d exact_direct_irradiance(const Scene& scene,
                                         const std::vector<Eigen::Vector3d>& points,
                                         const std::vector<Eigen::Vector3d>& normals,
                                         int threads = 0);

/// True when some surface of `scene` emits (H_d can be non-zero).
bool scene_has_emitters(const Scene& scene);

}  // namespace lambert
