#pragma once
// The pairwise form-factor driver shared by the ray-traced estimators (internal).
//
// For every unordered pair (i, j) that can exchange energy, an estimator returns
// G_ij = ∫_{A_i} ∫_{A_j} V cosθ_i cosθ_j / (π r²) dA_j dA_i (scene units²) and the variance
// of that estimate. F_ij = G_ij / A_i and F_ji = G_ij / A_j, so A_i F_ij = A_j F_ji holds
// by construction. Each pair's random stream is a hash of (seed, i, j): results do not
// depend on the thread count or schedule.

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert::ff {

/// What an estimator sees.
struct PairContext {
  const std::vector<PatchGeom>& geom;
  const Bvh& bvh;
  int samples;
  std::uint64_t seed;
  double offset;  ///< ray ends are lifted this far off their patches (scene units)
  double tol = 0.0;  ///< estimator "analytic": absolute error target of F_ij and F_ji
  /// Estimator "analytic": point factors per pair before it falls back to sampling
  /// (estimate_analytic; 0: kAnalyticMaxEvaluations).
  std::int64_t analytic_budget = 0;
};

/// One pair's estimate.
struct PairEstimate {
  double G = 0.0;    ///< estimate of G_ij
  double var = 0.0;  ///< estimated variance of G (0 when unknown)
  std::int64_t rays = 0;
  bool unverified = false;  ///< visibility could not be sampled as designed (see stats)
  bool short_of_target = false;  ///< --target-stderr not met at kMaxPairSamples
};

/// Signature of a pair estimator.
using PairEstimator = PairEstimate (*)(const PairContext&, std::int32_t i, std::int32_t j);

/// `estimator` (mc, hybrid) on pair (i, j) with 4 x the samples at a time, from ctx.samples,
/// until the larger standard error of F_ij and F_ji is at most `target`
/// (--target-stderr; short_of_target when kMaxPairSamples did not reach it).
PairEstimate estimate_to_target(const PairContext& ctx, PairEstimator estimator, std::int32_t i,
                                std::int32_t j, double target);

/// Estimator "mc": 4-D randomly shifted Kronecker points (x on i, y on j), one occlusion
/// ray per sample with positive kernel. Unbiased; variance from replicates.
PairEstimate estimate_mc(const PairContext& ctx, std::int32_t i, std::int32_t j);

/// Estimator "hybrid": the exact unoccluded G (adaptive quadrature of the contour formula
/// over the smaller patch) times an unbiased visible fraction from rays drawn with the
/// kernel's density. Exact (to quadrature, < 1e-6) for unoccluded pairs.
PairEstimate estimate_hybrid(const PairContext& ctx, std::int32_t i, std::int32_t j);

/// Estimator "analytic" (analytic.hpp): exact point factors past the blockers the BVH
/// finds in the pair's bounding ball, integrated over the smaller patch to an error
/// estimate of ctx.tol on both factors; var is the estimate squared. Where the budget of
/// point factors runs out first, the pair is sampled instead (hybrid, estimate_to_target
/// with target ctx.tol) and the better of the two kept; unverified when neither met ctx.tol.
PairEstimate estimate_analytic(const PairContext& ctx, std::int32_t i, std::int32_t j);

/// The exact point factor F_{dx->j, visible} at x (unit normal n) past the patches in the
/// ball around x and patch j (shadow.hpp's shadowed_point_factor): `formfactors --point`
/// with the analytic estimator.
double exact_point_factor(const Bvh& bvh, const std::vector<PatchGeom>& geom, std::int32_t j,
                          const Eigen::Vector3d& x, const Eigen::Vector3d& n);

/// Runs `estimator` over all pairs in parallel, tracing against `bvh` (built over `mesh`), and assembles F (and stderr if asked).
FormFactors compute_pairwise(const PatchMesh& mesh, const FormFactorOptions& options,
                             const Bvh& bvh, PairEstimator estimator);

/// True when the segment between x (on a patch with normal nx) and y (normal ny) is free,
/// with the ends lifted by `x_lift` and `y_lift` along their normals so the end patches never
/// occlude (end_lift: the rays' offset plus the patch's warp).
/// The segment visible() traces, as Embree's origin and direction (t in [0, 1]).
inline void lifted_segment(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, double x_lift,
                           const Eigen::Vector3d& y, const Eigen::Vector3d& ny, double y_lift,
                           Eigen::Vector3f& origin, Eigen::Vector3f& direction) {
  const Eigen::Vector3d a = x + x_lift * nx;
  const Eigen::Vector3d b = y + y_lift * ny;
  origin = a.cast<float>();
  direction = (b - a).cast<float>();
}
inline bool visible(const Bvh& bvh, const Eigen::Vector3d& x, const Eigen::Vector3d& nx,
                    double x_lift, const Eigen::Vector3d& y, const Eigen::Vector3d& ny,
                    double y_lift) {
  Eigen::Vector3f origin, direction;
  lifted_segment(x, nx, x_lift, y, ny, y_lift, origin, direction);
  return !bvh.occluded(origin, direction, 0.0f, 1.0f);
}

/// One pair's segments, each with a Payload (what its estimator needs back: replicate,
/// kernel, weight), traced Bvh::kPacket at a time: a pair's rays run from one patch to
/// another, coherent enough that Embree's packets trace them ~2.5 x faster than one by one
/// (bench/formfactors_bench), with the same answers (Bvh::occluded_packet). add() segments as
/// visible() takes them; flush() traces the pending ones and hands each payload back with
/// its answer, in the order added. Callers flush when full() (memory stays bounded under
/// --target-stderr's 2^20 samples) and once at the end.
template <typename Payload>
class SegmentBatch {
 public:
  static constexpr size_t kFlush = 256;

  void add(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, double x_lift,
           const Eigen::Vector3d& y, const Eigen::Vector3d& ny, double y_lift,
           const Payload& payload) {
    origin_.emplace_back();
    direction_.emplace_back();
    lifted_segment(x, nx, x_lift, y, ny, y_lift, origin_.back(), direction_.back());
    payload_.push_back(payload);
  }
  bool full() const { return origin_.size() >= kFlush; }
  /// Drops pending segments (a thread's batch is reused: an estimate that threw mid-pair
  /// must not hand its segments to the next).
  void clear() {
    origin_.clear();
    direction_.clear();
    payload_.clear();
  }

  /// Traces the pending segments and calls each(payload, unblocked) for them in order;
  /// returns how many were traced.
  template <typename Each>
  std::int64_t flush(const Bvh& bvh, Each&& each) {
    bool hit[Bvh::kPacket];
    for (size_t k0 = 0; k0 < origin_.size(); k0 += Bvh::kPacket) {
      const int n = static_cast<int>(std::min<size_t>(Bvh::kPacket, origin_.size() - k0));
      bvh.occluded_packet(&origin_[k0], &direction_[k0], n, hit);
      for (int k = 0; k < n; ++k) each(payload_[k0 + k], !hit[k]);
    }
    const auto traced = static_cast<std::int64_t>(origin_.size());
    clear();
    return traced;
  }

 private:
  std::vector<Eigen::Vector3f> origin_, direction_;
  std::vector<Payload> payload_;
};

}  // namespace lambert::ff
