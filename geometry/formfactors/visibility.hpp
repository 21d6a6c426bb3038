#pragma once
// The visible fraction of a patch seen from a point, the one kernel shared by `hybrid`
// and the sensor-point factors (internal).
//
// From a point x with normal n_x, the unoccluded factor to patch b is
//   F(x -> b) = (1/π) ∫_b K dA_y,  K = cosθ_x cosθ_y / r²  (Lambert's contour formula),
// and the occluded one is F(x -> b) · vis with vis = ∫_b K V dA_y / ∫_b K dA_y. Drawing y
// with density ∝ K on b (the projected solid angle of b from x) makes every ray an
// unbiased Bernoulli sample of vis: no ratio of weights, no Jacobian, no bias for any
// patch shape, size or distance.

#include "core/sampling.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert::ff {

/// Draws points of a patch with density ∝ K(x, y) from a fixed point x. Two exact methods:
/// directions uniform in the solid angle of b's part in front of x (Arvo 1995, per triangle
/// of its fan), kept with probability cosθ_x / (bound of cosθ_x over b); or, when b subtends
/// under kSmallSolidAngle (to first order; where Arvo's formulas lose digits and K is
/// nearly uniform over b) unless K is far from uniform over it (a sliver reaching from near
/// x to far away: expected acceptance under kMinAreaAcceptance), points uniform in area,
/// kept with probability K / (bound of K over b). Both are rejection samplers of the same density.
class KernelSampler {
 public:
  /// With `with_factor` false the unoccluded factor is computed only where the choice of
  /// method needs it (a small solid angle), and factor() is NaN otherwise: a caller that
  /// weights rays by it can compute it later (clipped_factor), only where it matters.
  KernelSampler(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, const PatchGeom& b,
                bool with_factor = true);
  /// True when no part of b is in front of x (nothing to sample); with `with_factor`, also
  /// when F(x -> b) is not positive.
  bool empty() const { return triangles_ == 0; }
  /// The unoccluded factor F(x -> b) (clipped_factor, from the same clipped polygon).
  double factor() const { return factor_; }
  /// A point of b. (u0, u1, u2) uniform in [0,1)^3 drive the first try (stratification);
  /// further tries draw from rng. After kMaxTries rejections the last try is returned and
  /// `exhausted` is set (never seen in practice: acceptance is >= ~cos of b's elevation).
  Eigen::Vector3d sample(double u0, double u1, double u2, Rng& rng, bool& exhausted) const;

  /// Solid angles below this (sr) use area sampling: ~1e-16 / 1e-4 relative precision of
  /// Arvo's spherical-excess arithmetic, and a patch that small is nearly uniform in K.
  static constexpr double kSmallSolidAngle = 1e-4;
  /// Area sampling only where its expected acceptance is at least this (else solid-angle
  /// sampling): the break-even of a cheap area try against an Arvo try (trigonometry, ~5x
  /// the cost) accepted with probability >= cos of b's elevation.
  static constexpr double kMinAreaAcceptance = 0.2;
  /// Tries before giving up on the rejection.
  static constexpr int kMaxTries = 4096;

 private:
  Eigen::Vector3d try_once(double u0, double u1, double u2, double& accept) const;
  Eigen::Vector3d x_, nx_, nb_;
  double plane_ = 0.0;  // n_b · p_b
  ClippedCorners w_;    // clipped corners (unit directions, or points in area mode)
  std::array<double, kMaxClippedCorners - 2> cdf_{};  // fan triangles (0, k+1, k+2), cumulative
  int triangles_ = 0;
  bool area_mode_ = false;
  double bound_ = 1.0;  // upper bound of the acceptance numerator
  double factor_ = 0.0;
};

/// F(x -> b) for x with normal nx in front of b: b clipped to x's horizon, then the contour
/// formula; bitwise the factor KernelSampler computes. 0 where nothing of b is in front.
double clipped_factor(const Eigen::Vector3d& x, const Eigen::Vector3d& nx, const PatchGeom& b);

/// Number of `rays` visibility rays from x (normal nx, on a patch) to points of b drawn by
/// KernelSampler that reach b unblocked. `stream` seeds the lattice; `exhausted` counts
/// rejection give-ups. The rays leave x + x_lift nx and end lifted by end_lift(b, offset).
int count_visible(const Bvh& bvh, const Eigen::Vector3d& x, const Eigen::Vector3d& nx,
                  double x_lift, const PatchGeom& b, int rays, std::uint64_t stream, double offset,
                  int& exhausted);

}  // namespace lambert::ff
