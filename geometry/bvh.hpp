#pragma once
// Ray queries against the patches, backed by an Embree 3 BVH (private to bvh.cpp).

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>

#include "geometry/mesh.hpp"

namespace lambert {

/// The closest hit of a ray.
struct RayHit {
  std::int32_t patch = -1;  ///< -1 when nothing was hit
  double t = 0.0;           ///< ray parameter of the hit (origin + t * direction)
};

/// An acceleration structure over a PatchMesh. Every patch blocks rays from both sides.
/// Queries are const and thread-safe; construction is not.
class Bvh {
 public:
  /// Builds the BVH (robust mode, high quality). Throws Error if Embree fails.
  explicit Bvh(const PatchMesh& mesh);
  ~Bvh();
  Bvh(const Bvh&) = delete;
  Bvh& operator=(const Bvh&) = delete;

  /// True if anything is hit on origin + t * direction for t in (tnear, tfar).
  /// Callers offset the segment ends so the end patches themselves are not hit.
  bool occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float tnear,
                float tfar) const;

  /// Closest hit on origin + t * direction for t in (tnear, tfar).
  RayHit intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                   float tnear = 0.0f,
                   float tfar = std::numeric_limits<float>::infinity()) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lambert
