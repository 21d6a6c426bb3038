// Hierarchical radiosity (geometry/hierarchical/) against closed forms and conservation laws.
#include <gtest/gtest.h>

#include "geometry/analytic.hpp"
#include "geometry/hierarchical/hierarchical.hpp"

namespace lambert {
namespace {

Material mat(const std::string& name, double rho, double e) {
  Material m;
  m.name = name;
  m.rho = Eigen::Vector3d::Constant(rho);
  m.emission = Eigen::Vector3d::Constant(e);
  return m;
}

// Area-weighted mean of channel 0 of B over surface `s`.
double surface_mean(const HierarchicalResult& r, int s) {
  double sum = 0, area = 0;
  for (std::int32_t i = 0; i < r.mesh.size(); ++i)
    if (r.mesh.patches[i].surface == s) {
      sum += r.mesh.patches[i].area * r.B(i, 0);
      area += r.mesh.patches[i].area;
    }
  return sum / area;
}

// Emitter a x b at z = 0 facing up, receiver at z = c facing down (rho = 1/2, so its mean
// radiosity is F_receiver->emitter / 2 for E = 1).
Scene parallel_plates(double a, double b, double c) {
  Scene s;
  add_polygon(s, "emitter", mat("e", 0.0, 1.0),
              {{0, 0, 0}, {a, 0, 0}, {a, b, 0}, {0, b, 0}});
  add_polygon(s, "receiver", mat("r", 0.5, 0.0),
              {{0, 0, c}, {0, b, c}, {a, b, c}, {a, 0, c}});
  return s;
}

TEST(Hierarchical, ParallelSquaresMatchClosedForm) {
  const Scene s = parallel_plates(1, 1, 1);
  HierarchicalOptions o;
  o.epsilon = 1e-4;
  const HierarchicalResult r = solve_hierarchical(s, o);
  const double exact = 0.5 * parallel_rectangles_factor(1, 1, 1);
  EXPECT_NEAR(surface_mean(r, 1), exact, 1e-3);
}

}  // namespace
}  // namespace lambert
namespace lambert {
namespace {
// Unit cube, faces wound to face inward.
Scene closed_cube(double rho, double e) {
  Scene s;
  const Material m = mat("wall", rho, e);
  using V = Eigen::Vector3d;
  add_polygon(s, "bottom", m, {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0)});
  add_polygon(s, "top", m, {V(0, 0, 1), V(0, 1, 1), V(1, 1, 1), V(1, 0, 1)});
  add_polygon(s, "front", m, {V(0, 0, 0), V(0, 0, 1), V(1, 0, 1), V(1, 0, 0)});
  add_polygon(s, "back", m, {V(0, 1, 0), V(1, 1, 0), V(1, 1, 1), V(0, 1, 1)});
  add_polygon(s, "left", m, {V(0, 0, 0), V(0, 1, 0), V(0, 1, 1), V(0, 0, 1)});
  add_polygon(s, "right", m, {V(1, 0, 0), V(1, 0, 1), V(1, 1, 1), V(1, 1, 0)});
  return s;
}
TEST(Hierarchical, BitwiseIdenticalForAnyThreadCount) {
  HierarchicalOptions o;
  o.epsilon = 1e-3;
  o.threads = 1;
  const HierarchicalResult a = solve_hierarchical(closed_cube(0.5, 1.0), o);
  o.threads = 2;
  const HierarchicalResult b = solve_hierarchical(closed_cube(0.5, 1.0), o);
  ASSERT_EQ(a.B.rows(), b.B.rows());
  EXPECT_EQ(a.stats.links, b.stats.links);
  EXPECT_EQ(a.stats.rays, b.stats.rays);
  for (Eigen::Index i = 0; i < a.B.rows(); ++i)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(a.B(i, c), b.B(i, c)) << "leaf " << i;
}

TEST(Hierarchical, FurnaceExplore) {
  for (double eps : {1e-2, 1e-3, 1e-4}) {
    HierarchicalOptions o;
    o.epsilon = eps;
    const HierarchicalResult r = solve_hierarchical(closed_cube(0.5, 1.0), o);
    printf("eps %g mean %.6f leaves %lld links %lld esc %g/%g\n", eps, surface_mean(r, 0), (long long)r.stats.leaves, (long long)r.stats.links, r.stats.energy[0].escaped, r.stats.energy[0].emitted);
  }
}
}  // namespace
}  // namespace lambert
