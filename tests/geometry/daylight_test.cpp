// Daylight on patches and points (geometry/visibility/daylight.hpp) against closed forms:
// the sun on an open plane, the exact area of a box's shadow on the ground, the escape
// fraction of two facing plates.
#include "geometry/visibility/daylight.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "geometry/analytic.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert {
namespace {

const Material kGrey{"grey", Eigen::Vector3d::Constant(0.5)};

// A 10 x 10 ground (y = 0, facing up) with a closed 2 x 2 x 2 box standing on its middle.
Scene yard() {
  Scene s;
  add_polygon(s, "ground", kGrey, {{-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}});
  const double a = -1, b = 1, h = 2;
  add_polygon(s, "box", kGrey, {{a, h, a}, {a, h, b}, {b, h, b}, {b, h, a}});  // top
  add_polygon(s, "box", kGrey, {{a, 0, a}, {a, h, a}, {b, h, a}, {b, 0, a}});  // -z
  add_polygon(s, "box", kGrey, {{b, 0, a}, {b, h, a}, {b, h, b}, {b, 0, b}});  // +x
  add_polygon(s, "box", kGrey, {{b, 0, b}, {b, h, b}, {a, h, b}, {a, 0, b}});  // +z
  add_polygon(s, "box", kGrey, {{a, 0, b}, {a, h, b}, {a, h, a}, {a, 0, a}});  // -x
  return s;
}

Daylight sun(const Eigen::Vector3d& direction, double irradiance) {
  Daylight d;
  d.sun_direction = direction.normalized();
  d.sun_irradiance = Eigen::Vector3d(irradiance, 0.5 * irradiance, 0.25 * irradiance);
  return d;
}

PatchMesh meshed(const Scene& scene, double max_edge) {
  MeshOptions o;
  o.max_edge = max_edge;
  return mesh_scene(scene, o);
}

}  // namespace

TEST(Daylight, TheSunOnAnOpenPlaneIsItsIrradianceTimesTheCosine) {
  Scene s;
  add_polygon(s, "ground", kGrey, {{0, 0, 0}, {0, 0, 3}, {2, 0, 3}, {2, 0, 0}});
  const PatchMesh mesh = meshed(s, 0.7);
  const Bvh bvh(mesh, 1);
  const Daylight light = sun({1, -std::sqrt(3.0), 0}, 800);  // 30° from the zenith
  const Eigen::MatrixX3d H = sun_patch_irradiance(mesh, bvh, light, 1, 1);
  // Nothing shadows: every point sees the sun and H = S cos 30° to rounding.
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(H(i, c), light.sun_irradiance[c] * std::sqrt(3.0) / 2, 1e-12 * 800);
  // From below (the sun behind the plane) nothing arrives.
  const Eigen::MatrixX3d below = sun_patch_irradiance(mesh, bvh, sun({0, 1, 0}, 800), 1, 1);
  EXPECT_EQ(below.maxCoeff(), 0.0);
}

TEST(Daylight, ABoxCastsAShadowOfItsProjectedAreaOnTheGround) {
  const Scene s = yard();
  const PatchMesh mesh = meshed(s, 0.5);
  const Bvh bvh(mesh, 2);
  // Light along (0.6, -1, 0.3): the box's top edge (height 2) lands 2 (0.6, 0.3) = (1.2, 0.6)
  // off its foot, so the shadow on the ground is the hull of the footprint and that copy,
  // minus the footprint: 2·1.2 + 2·0.6 = 3.6 m², and the lit ground 100 − 4 − 3.6 = 92.4 m².
  const Eigen::Vector3d d = Eigen::Vector3d(0.6, -1, 0.3).normalized();
  const Daylight light = sun(d, 1000);
  const double cos_ground = -d.y();
  const Eigen::MatrixX3d H = sun_patch_irradiance(mesh, bvh, light, 7, 2);
  double ground = 0.0, box = 0.0;
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    (mesh.surface_names[mesh.patches[i].surface] == "ground" ? ground : box) +=
        mesh.patches[i].area * H(i, 0);
  // Tolerance: only patches the shadow's edge crosses err. Their k² = 256 jittered points
  // err only in the ≤ 2k = 32 strata the edge crosses, each a Bernoulli of variance ≤ 1/4:
  // the lit share of such a patch has a standard deviation ≤ √(32/4)/k² = 0.011. The edge,
  // 2 (2 + 1.2) + 2 (2 + 0.6) ≈ 12 m long, crosses ≤ 12/0.5 · 2 = 48 patches of 0.25 m²:
  // σ(lit area) ≤ √48 · 0.011 · 0.25 = 0.019 m²; 4σ = 0.08 m².
  EXPECT_NEAR(ground / (1000 * cos_ground), 92.4, 0.08);
  // The box's sunlit faces are whole: the top (cos = 0.857), −x (0.514) and −z (0.257) faces,
  // 4 m² each; nothing shadows them.
  EXPECT_NEAR(box / 1000, 4 * (-d.y() + d.x() + d.z()), 1e-9);
  // At a point the shadow is exact: one ray.
  const Eigen::Vector3d up(0, 1, 0);
  EXPECT_EQ(sun_irradiance_at(bvh, light, {1.5, 0, 1.2}, up, 1e-6).x(), 0.0);  // in the shadow
  EXPECT_DOUBLE_EQ(sun_irradiance_at(bvh, light, {-1.5, 0, 1.2}, up, 1e-6).x(),
                   1000 * cos_ground);  // beside the box, on the sun's side
  // Bitwise the same on one thread.
  const Eigen::MatrixX3d one = sun_patch_irradiance(mesh, bvh, light, 7, 1);
  EXPECT_TRUE((one.array() == H.array()).all());
}

TEST(Daylight, TheEscapeFractionIsWhatTheRowDoesNotReach) {
  SparseRowMatrix F(3, 3);
  F.insert(0, 1) = 0.25;
  F.insert(0, 2) = 0.5;
  F.insert(1, 0) = 1.0;
  F.insert(2, 0) = 0.75;
  F.insert(2, 1) = 0.5;  // a noisy row summing above 1: clamped at 0
  F.makeCompressed();
  const Eigen::VectorXd s = escape_fractions(F, {}, 3);
  EXPECT_DOUBLE_EQ(s[0], 0.25);
  EXPECT_DOUBLE_EQ(s[1], 0.0);
  EXPECT_DOUBLE_EQ(s[2], 0.0);
  // Light carried on by mirrors is counted again further on: it does not reach anything yet.
  const Eigen::VectorXd continued = Eigen::Vector3d(0.25, 0, 0);
  EXPECT_DOUBLE_EQ(escape_fractions(F, continued, 3)[0], 0.5);
}

}  // namespace lambert
