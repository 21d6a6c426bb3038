// Light tracing (geometry/render/light_trace.hpp): the independent per-surface reference.
#include "geometry/render/light_trace.hpp"

#include <gtest/gtest.h>

#include "geometry/analytic.hpp"

namespace lambert {
namespace {

// Every tolerance below is 5 standard errors of the estimate itself (the spread of its 64
// independent batches; with 63 degrees of freedom a 5-sigma miss has probability ~1e-5), and
// the standard error must be small enough for the check to mean something.
void expect_within_its_error(const TracedSurface& s, double exact, double max_relative_se) {
  for (int c = 0; c < 3; ++c) {
    EXPECT_LE(s.stderr_[c], max_relative_se * exact) << s.name << " channel " << c;
    EXPECT_NEAR(s.average[c], exact, 5.0 * s.stderr_[c]) << s.name << " channel " << c;
  }
}

}  // namespace

// Two opposed unit squares at distance 1 (F = 0.19982 both ways), the lamp a emitting E = 1,
// both reflecting rho = 0.5: B_b = rho F B_a and B_a = E + rho F B_b, so
// B_b = rho F E / (1 - rho² F²) and B_a = E + rho F B_b exactly. The photons' positions,
// cosine directions, weights and the bounces between the two are all exercised.
TEST(LightTrace, ParallelSquaresMatchTheTwoSurfaceClosedForm) {
  const PatchMesh mesh = mesh_scene(parallel_squares(1.0), {});
  const Bvh bvh(mesh, 2);
  const LightTraceResult r = light_trace(mesh, bvh, 64 * 4000, 7, 2);
  const double F = parallel_rectangles_factor(1, 1, 1), rho = 0.5;
  const double b = rho * F / (1.0 - rho * rho * F * F), a = 1.0 + rho * F * b;
  ASSERT_EQ(r.surfaces.size(), 2u);
  expect_within_its_error(r.surfaces[0], a, 0.01);
  expect_within_its_error(r.surfaces[1], b, 0.02);
  // What escapes is what neither square absorbs: 1 - (1 - rho)(H_a + H_b) A, H = (B - E) / rho;
  // an escape is a Bernoulli outcome of about 0.8 per photon path: sd ~ sqrt(0.16 / 256,000)
  // = 8e-4, so 0.01 is over 10 sd.
  const double escaped = 1.0 - (1.0 - rho) * ((a - 1.0) / rho + b / rho);
  EXPECT_NEAR(r.escaped[0], escaped, 0.01);
  EXPECT_EQ(r.capped, 0);
}

// The furnace: a closed cube whose faces all emit E = 1 and reflect rho = 0.5 has B = E /
// (1 - rho) = 2 on every face and nothing escapes; the result is bitwise the same for 1 and
// 2 threads (64 batches with their own streams, summed in order).
TEST(LightTrace, ClosedCubeFurnaceIsTwoEverywhereForAnyThreadCount) {
  PatchMesh mesh = mesh_scene(unit_cube(), {});
  for (Patch& p : mesh.patches) {
    p.emission = Eigen::Vector3d::Ones();
    p.rho = Eigen::Vector3d::Constant(0.5);
  }
  const Bvh bvh(mesh, 2);
  const LightTraceResult one = light_trace(mesh, bvh, 64 * 1000, 3, 1);
  const LightTraceResult two = light_trace(mesh, bvh, 64 * 1000, 3, 2);
  for (std::size_t s = 0; s < one.surfaces.size(); ++s) {
    expect_within_its_error(two.surfaces[s], 2.0, 0.01);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(one.surfaces[s].average[c], two.surfaces[s].average[c]);
  }
  EXPECT_EQ(two.escaped.maxCoeff(), 0.0);
  EXPECT_EQ(one.rays, two.rays);
}

}  // namespace lambert
