#include "geometry/visibility/daylight.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

// A point of patch p for (u, v) in [0,1)²: triangles fold the unit square onto the
// triangle (2-to-1, uniform in area), quads map it bilinearly (uniform for parallelograms,
// the patches uniform meshing makes; a trapezoid's points crowd its short side slightly).
Eigen::Vector3d patch_point(const PatchMesh& mesh, const Patch& p, double u, double v) {
  const Eigen::Vector3d& a = mesh.vertices[p.vertices[0]];
  const Eigen::Vector3d& b = mesh.vertices[p.vertices[1]];
  const Eigen::Vector3d& c = mesh.vertices[p.vertices[2]];
  if (p.vertex_count == 3) {
    if (u + v > 1.0) {
      u = 1.0 - u;
      v = 1.0 - v;
    }
    return a + u * (b - a) + v * (c - a);
  }
  const Eigen::Vector3d& d = mesh.vertices[p.vertices[3]];
  return (1 - u) * (1 - v) * a + u * (1 - v) * b + u * v * c + (1 - u) * v * d;
}

}  // namespace

Eigen::VectorXd escape_fractions(const SparseRowMatrix& F, const Eigen::VectorXd& continued,
                                 std::int32_t patches) {
  LAMBERT_CHECK(patches <= F.rows() && (continued.size() == 0 || continued.size() == F.rows()),
                "escape_fractions: sizes do not match");
  Eigen::VectorXd s(patches);
  for (std::int32_t i = 0; i < patches; ++i) {
    double sum = 0.0;
    for (SparseRowMatrix::InnerIterator it(F, i); it; ++it) sum += it.value();
    if (continued.size() > 0) sum -= continued[i];
    s[i] = std::clamp(1.0 - sum, 0.0, 1.0);
  }
  return s;
}

Eigen::Vector3d sun_irradiance_at(const Bvh& bvh, const Daylight& light, const Eigen::Vector3d& x,
                                  const Eigen::Vector3d& normal, double offset) {
  if (!light.has_sun()) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d to_sun = -light.sun_direction;
  const double cosine = normal.dot(to_sun);
  if (!(cosine > 0.0)) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d origin = x + offset * normal;
  if (bvh.occluded(origin.cast<float>(), to_sun.cast<float>(), 0.0f,
                   std::numeric_limits<float>::infinity()))
    return Eigen::Vector3d::Zero();
  return cosine * light.sun_irradiance;
}

Eigen::MatrixX3d sun_patch_irradiance(const PatchMesh& mesh, const Bvh& bvh, const Daylight& light,
                                      std::uint64_t seed, int threads) {
  const auto n = static_cast<std::int64_t>(mesh.patches.size());
  Eigen::MatrixX3d H = Eigen::MatrixX3d::Zero(n, 3);
  if (!light.has_sun()) return H;
  const Eigen::Vector3d to_sun = -light.sun_direction;
  const double offset = kSunRayOffset * mesh.scale;
  constexpr int k = kSunSide;
  parallel_for(n, 64, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      const Patch& p = mesh.patches[i];
      const double cosine = p.normal.dot(to_sun);
      if (!(cosine > 0.0)) continue;
      Rng rng(hash_keys(seed, static_cast<std::uint64_t>(i), 0x73756eull));  // "sun"
      int lit = 0;
      // Points on a quad's bilinear surface can lie below the triangles Embree traces.
      const double lift =
          offset +
          (p.vertex_count == 4
               ? quad_warp(mesh.vertices[p.vertices[0]], mesh.vertices[p.vertices[1]],
                           mesh.vertices[p.vertices[2]], mesh.vertices[p.vertices[3]], p.normal)
               : 0.0);
      for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
          const Eigen::Vector3d x =
              patch_point(mesh, p, (a + rng.uniform()) / k, (b + rng.uniform()) / k);
          const Eigen::Vector3d origin = x + lift * p.normal;
          if (!bvh.occluded(origin.cast<float>(), to_sun.cast<float>(), 0.0f,
                            std::numeric_limits<float>::infinity()))
            ++lit;
        }
      H.row(i) = (cosine * lit / double(k * k)) * light.sun_irradiance.transpose();
    }
  });
  return H;
}

}  // namespace lambert
