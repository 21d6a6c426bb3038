#include "geometry/media/medium.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "core/sampling.hpp"

namespace lambert {
namespace {

// A 3 x 4 x 5 grid over [-1, 2] x [0, 2] x [0.5, 3] with a different grey sigma_t per voxel.
Medium checker_medium() {
  Medium m = homogeneous_medium({-1, 0, 0.5}, {2, 2, 3}, {3, 4, 5}, Eigen::Vector3d::Zero(),
                                Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  for (std::int32_t v = 0; v < m.voxels(); ++v) {
    m.sigma_a.row(v).setConstant(0.1 + 0.37 * (v % 7));
    m.sigma_s.row(v).setConstant(0.05 * (v % 3));
  }
  return m;
}

// Independent reference: the segment clipped to every voxel's box by slabs, sum of
// sigma_t times the clipped length (no traversal order, no stepping).
double brute_force_depth(const Medium& m, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  double tau = 0.0;
  for (std::int32_t v = 0; v < m.voxels(); ++v) {
    const Eigen::Vector3d lo = m.voxel_lo(v), hi = lo + m.voxel_size();
    double t0 = 0.0, t1 = 1.0;
    bool miss = false;
    for (int k = 0; k < 3; ++k) {
      const double d = b[k] - a[k];
      if (d == 0.0) {
        miss = miss || a[k] < lo[k] || a[k] > hi[k];
        continue;
      }
      double ta = (lo[k] - a[k]) / d, tb = (hi[k] - a[k]) / d;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (!miss && t1 > t0) tau += m.sigma_t(v) * (t1 - t0) * (b - a).norm();
  }
  return tau;
}

}  // namespace

TEST(MediumDda, OpticalDepthMatchesVoxelByVoxelClipping) {
  const Medium m = checker_medium();
  Rng rng(7);
  int crossing = 0;
  for (int k = 0; k < 2000; ++k) {
    // Segments from a box larger than the medium's: some miss it, some start or end inside.
    const Eigen::Vector3d a(-2 + 5 * rng.uniform(), -1 + 4 * rng.uniform(),
                            -0.5 + 4.5 * rng.uniform());
    const Eigen::Vector3d b(-2 + 5 * rng.uniform(), -1 + 4 * rng.uniform(),
                            -0.5 + 4.5 * rng.uniform());
    const double len = (b - a).norm();
    const double tau = optical_depth(m, a, (b - a) / len, 0.0, len);
    const double ref = brute_force_depth(m, a, b);
    crossing += ref > 0.0 ? 1 : 0;
    // Both are sums of <= 12 terms of sigma_t (<= 2.4) x length (<= 5.9): rounding of the
    // plane crossings (a few ulps of coordinates ~4) is ~1e-15 per term; 1e-12 is a wide margin.
    ASSERT_NEAR(tau, ref, 1e-12) << "segment " << k;
  }
  EXPECT_GT(crossing, 1000);  // the test exercises the grid, not only misses
}

TEST(MediumDda, AxisParallelAndGridPlaneRaysAreExact) {
  const Medium m = checker_medium();
  // Along x through the voxel row y in [0, 0.5], z in [0.5, 1]: sum of the row's sigma_t x 1.
  double row = 0.0;
  for (int x = 0; x < 3; ++x) row += m.sigma_t(m.index(x, 0, 0));
  const Eigen::Vector3d d(1, 0, 0);
  EXPECT_NEAR(optical_depth(m, {-5, 0.25, 0.75}, d, 0.0, 10.0), row, 1e-14);
  // A ray lying in a voxel plane (y = 0.5 exactly) is counted once, on one side: either
  // neighbouring row's sum.
  double next = 0.0;
  for (int x = 0; x < 3; ++x) next += m.sigma_t(m.index(x, 1, 0));
  const double on_plane = optical_depth(m, {-5, 0.5, 0.75}, d, 0.0, 10.0);
  EXPECT_TRUE(std::abs(on_plane - row) < 1e-14 || std::abs(on_plane - next) < 1e-14) << on_plane;
}

TEST(MediumDda, HomogeneousTransmittanceIsExpSigmaD) {
  const Medium m =
      homogeneous_medium({0, 0, 0}, {1, 1, 1}, {7, 5, 3}, Eigen::Vector3d::Constant(0.4),
                         Eigen::Vector3d::Constant(0.9), Eigen::Vector3d::Zero());
  const Eigen::Vector3d a(0.1, 0.2, 0.3), b(0.9, 0.7, 0.95);
  // exp(-1.3 |b - a|) to rounding of ~15 voxel terms.
  EXPECT_NEAR(transmittance(m, a, b), std::exp(-1.3 * (b - a).norm()), 1e-14);
  // Outside the box nothing attenuates.
  EXPECT_EQ(transmittance(m, {2, 2, 2}, {3, 2, 2}), 1.0);
}

TEST(MediumModel, ValidationNamesTheProblem) {
  Medium m = homogeneous_medium({0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {0.1, 0.2, 0.3}, {0.2, 0.1, 0.0},
                                Eigen::Vector3d::Zero());
  EXPECT_NO_THROW(validate_medium(m, "x"));  // sigma_t 0.3 in every channel
  m.sigma_s(3, 2) = 0.5;
  EXPECT_THROW(validate_medium(m, "x"), UsageError);  // coloured extinction
  Medium e = homogeneous_medium({0, 0, 0}, {1, 1, 1}, {1, 1, 1}, Eigen::Vector3d::Zero(),
                                Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  EXPECT_THROW(validate_medium(e, "x"), UsageError);  // emission without extinction
  // A medium that extinguishes nothing anywhere would change no result: refused, not ignored
  // (--medium-box without --sigma-a/--sigma-s was accepted and did nothing).
  Medium clear = homogeneous_medium({0, 0, 0}, {1, 1, 1}, {2, 2, 2}, Eigen::Vector3d::Zero(),
                                    Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  EXPECT_THROW(validate_medium(clear, "x"), UsageError);
  clear.sigma_s.row(5).setConstant(0.5);  // one voxel that scatters: a medium
  EXPECT_NO_THROW(validate_medium(clear, "x"));
  Medium inverted = homogeneous_medium({0, 0, 0}, {1, -1, 1}, {1, 1, 1}, Eigen::Vector3d::Ones(),
                                       Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  EXPECT_THROW(validate_medium(inverted, "x"), UsageError);
  // Issue 33, item 8: sigma 1e-320 gave NaN energies, 1e300 a message naming no file; both
  // are refused by optical thickness (sigma_t x the box's diagonal), naming the source.
  for (const double sigma : {1e-320, 1e-120, 1e300}) {
    const Medium bad =
        homogeneous_medium({0, 0, 0}, {1, 1, 1}, {1, 1, 1}, Eigen::Vector3d::Zero(),
                           Eigen::Vector3d::Constant(sigma), Eigen::Vector3d::Zero());
    try {
      validate_medium(bad, "fog.txt");
      ADD_FAILURE() << sigma << " accepted";
    } catch (const UsageError& err) {
      EXPECT_EQ(std::string(err.what()).rfind("fog.txt: voxel 0:", 0), 0u) << err.what();
    }
  }
  EXPECT_NO_THROW(
      validate_medium(homogeneous_medium({0, 0, 0}, {1, 1, 1}, {1, 1, 1}, Eigen::Vector3d::Zero(),
                                         Eigen::Vector3d::Constant(1e-90), Eigen::Vector3d::Zero()),
                      "x"));
  // --voxels N: N along the longest axis, the others in proportion.
  EXPECT_EQ(medium_resolution({0, 0, 0}, {556, 548.8, 559.2}, 16, 0.0),
            Eigen::Vector3i(16, 16, 16));
  EXPECT_EQ(medium_resolution({0, 0, 0}, {4, 2, 1}, 8, 0.0), Eigen::Vector3i(8, 4, 2));
  EXPECT_EQ(medium_resolution({0, 0, 0}, {4, 2, 1}, 0, 0.5), Eigen::Vector3i(8, 4, 2));
}

}  // namespace lambert
