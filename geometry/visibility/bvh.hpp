#pragma once
// Ray queries against the patches, backed by an Embree 3 BVH (private to bvh.cpp).

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "geometry/mesh/mesh.hpp"

namespace lambert {

/// The closest hit of a ray.
struct RayHit {
  std::int32_t patch = -1;  ///< -1 when nothing was hit
  double t = 0.0;           ///< ray parameter of the hit (origin + t * direction)
};

/// An acceleration structure over a PatchMesh. Every patch blocks rays from both sides.
/// Queries are const and thread-safe; construction is not. All BVHs of a process share one
/// Embree device per thread count (in practice one: the command's -j), created on first use
/// and kept for the life of the process.
class Bvh {
 public:
  /// Builds the BVH (robust mode, high quality) on the process's device for `threads`
  /// worker threads (0 = all cores). Throws Error if Embree fails.
  explicit Bvh(const PatchMesh& mesh, int threads = 0);
  ~Bvh();
  Bvh(const Bvh&) = delete;
  Bvh& operator=(const Bvh&) = delete;

  /// True if anything is hit on origin + t * direction for t in (tnear, tfar).
  /// Callers offset the segment ends so the end patches themselves are not hit.
  bool occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float tnear,
                float tfar) const;

  /// The most segments occluded_packet takes at once.
  static constexpr int kPacket = 16;

  /// occluded(origin[k], direction[k], 0, 1) for k < n <= kPacket, traced together as one
  /// Embree packet (pays for coherent rays: one pair's, from one patch to another). Each
  /// answer is the single query's (the same watertight test per lane; checked in
  /// tests/geometry/bvh_test.cpp), whatever the other lanes hold.
  void occluded_packet(const Eigen::Vector3f* origin, const Eigen::Vector3f* direction, int n,
                       bool* hit) const;

  /// intersect(origin[k], direction[k]) for k < n <= kPacket (tnear 0, tfar infinity),
  /// traced together as one Embree packet (gather's rays from one patch). Each answer is the
  /// single query's (tests/geometry/bvh_test.cpp).
  void intersect_packet(const Eigen::Vector3f* origin, const Eigen::Vector3f* direction, int n,
                        RayHit* hit) const;

  /// Closest hit on origin + t * direction for t in (tnear, tfar).
  RayHit intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                   float tnear = 0.0f, float tfar = std::numeric_limits<float>::infinity()) const;

  /// Appends to `out` every patch whose bounds may meet the ball (centre, radius), a
  /// superset of those that do (Embree's point query over the BVH's float boxes, the
  /// radius widened by 1e-6 relative to cover their rounding). Unordered: callers sort.
  void patches_near(const Eigen::Vector3d& centre, double radius,
                    std::vector<std::int32_t>& out) const;

  /// BVHs built and Embree devices created so far by this process (for tests and logs).
  static std::int64_t builds();
  static std::int64_t devices();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lambert
