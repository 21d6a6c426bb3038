#include "geometry/visibility/direct_light.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/polygon.hpp"
#include "geometry/visibility/shadow.hpp"

namespace lambert {
// Named (not anonymous) because DirectLight::Faces holds it: a class with external linkage may
// not hold a type of an anonymous namespace once this file is compiled inside a unity batch.
namespace direct_light_detail {

// A face as a blocker or source: its corners, bounding box and plane.
struct FaceGeometry {
  Polygon3 corners;
  Eigen::Vector3d lo, hi;
  Eigen::Vector3d normal;  // unit (Newell)
  double offset = 0.0;     // normal . p on the plane (through the corners' mean)
  double slack = 0.0;      // how far a point on the face may be from that plane
  bool degenerate = false;
};

}  // namespace direct_light_detail
using direct_light_detail::FaceGeometry;

namespace {

std::vector<FaceGeometry> face_geometry(const Scene& scene) {
  const auto [blo, bhi] = scene.bounds();
  const double diagonal = (bhi - blo).norm();
  std::vector<FaceGeometry> out(scene.faces.size());
  for (size_t k = 0; k < scene.faces.size(); ++k) {
    FaceGeometry& g = out[k];
    for (auto v : scene.faces[k].vertices) g.corners.push_back(scene.vertices[v]);
    g.lo = g.hi = g.corners[0];
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : g.corners) {
      g.lo = g.lo.cwiseMin(p);
      g.hi = g.hi.cwiseMax(p);
      mean += p / static_cast<double>(g.corners.size());
    }
    const Eigen::Vector3d n = newell_normal(g.corners);
    g.degenerate = !(n.norm() > 0.0);
    g.normal = g.degenerate ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(n.normalized());
    g.offset = g.normal.dot(mean);
    // Mesh vertices on a warped face lie within its planarity deviation of the mean plane;
    // kPlaneEps of the diagonal covers rounding on planar ones.
    g.slack = 2.0 * planarity_deviation(g.corners) + ff::kPlaneEps * diagonal;
  }
  return out;
}

bool boxes_meet(const Eigen::Vector3d& alo, const Eigen::Vector3d& ahi, const Eigen::Vector3d& blo,
                const Eigen::Vector3d& bhi) {
  return (alo.array() <= bhi.array()).all() && (blo.array() <= ahi.array()).all();
}

}  // namespace

bool scene_has_emitters(const Scene& scene) {
  for (const auto& f : scene.faces)
    if (scene.material_of(f.surface).emits()) return true;
  return false;
}

struct DirectLight::Faces {
  std::vector<FaceGeometry> faces;
  std::vector<size_t> emitters;  // emitting, non-degenerate faces
};

DirectLight::DirectLight(const Scene& scene) : scene_(scene) {
  auto f = std::make_shared<Faces>();
  f->faces = face_geometry(scene);
  for (size_t k = 0; k < scene.faces.size(); ++k)
    if (scene.material_of(scene.faces[k].surface).emits() && !f->faces[k].degenerate)
      f->emitters.push_back(k);
  faces_ = std::move(f);
}

bool DirectLight::empty() const { return faces_->emitters.empty(); }

Eigen::Vector3d DirectLight::irradiance(const Eigen::Vector3d& x, const Eigen::Vector3d& normal,
                                        std::vector<Polygon3>& blockers) const {
  Eigen::Vector3d H = Eigen::Vector3d::Zero();
  const std::vector<FaceGeometry>& faces = faces_->faces;
  for (size_t e : faces_->emitters) {
    const FaceGeometry& src = faces[e];
    if (!(src.normal.dot(x) - src.offset > src.slack)) continue;  // behind or in its plane
    const Eigen::Vector3d lo = src.lo.cwiseMin(x), hi = src.hi.cwiseMax(x);
    blockers.clear();
    for (size_t k = 0; k < faces.size(); ++k) {
      const FaceGeometry& b = faces[k];
      if (k == e || b.degenerate || !boxes_meet(lo, hi, b.lo, b.hi)) continue;
      if (std::abs(b.normal.dot(x) - b.offset) <= b.slack) continue;  // x on its plane
      blockers.push_back(b.corners);
    }
    const double F = shadowed_point_factor(x, normal, src.corners, blockers);
    H += F * scene_.material_of(scene_.faces[e].surface).emission;
  }
  return H;
}

Eigen::Vector3d DirectLight::irradiance(const Eigen::Vector3d& x,
                                        const Eigen::Vector3d& normal) const {
  std::vector<Polygon3> blockers;
  return irradiance(x, normal, blockers);
}

Eigen::MatrixX3d exact_direct_irradiance(const Scene& scene,
                                         const std::vector<Eigen::Vector3d>& points,
                                         const std::vector<Eigen::Vector3d>& normals, int threads) {
  Eigen::MatrixX3d H = Eigen::MatrixX3d::Zero(static_cast<Eigen::Index>(points.size()), 3);
  LAMBERT_CHECK(points.size() == normals.size(), "exact_direct_irradiance: one normal per point");
  const DirectLight light(scene);
  if (light.empty()) return H;
  parallel_for(static_cast<std::int64_t>(points.size()), 16, threads,
               [&](std::int64_t begin, std::int64_t end) {
                 std::vector<Polygon3> blockers;
                 for (std::int64_t i = begin; i < end; ++i)
                   H.row(i) = light.irradiance(points[i], normals[i], blockers).transpose();
               });
  return H;
}

}  // namespace lambert
