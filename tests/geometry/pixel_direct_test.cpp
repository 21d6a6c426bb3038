// PixelDirectLight: the emitters' direct light at a point from shadow rays, against the exact
// shadowed point factor of the partial-shadow scene (analytic.hpp: light E = 1, floor B(x) =
// 0.5 F_visible(x)).

#include "geometry/render/pixel_direct.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/sampling.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/visibility/bvh.hpp"
#include "geometry/visibility/shadow.hpp"

namespace lambert {
namespace {

struct ShadowSetup {
  Scene scene = partial_shadow_scene();
  PatchMesh mesh = mesh_scene(scene, {});
  Bvh bvh{mesh, 1};
  PartialShadowGeometry g = partial_shadow_geometry();
  double exact(const Eigen::Vector3d& x) const {  // the exact visible factor F(x -> light)
    return shadowed_point_factor(x, Eigen::Vector3d::UnitZ(), g.light, {g.blocker});
  }
};

TEST(PixelDirectLight, IsExactWhereTheLightIsAllSeenOrAllHidden) {
  const ShadowSetup s;
  const PixelDirectLight light(s.scene, 8, ff::kRayOffset * s.mesh.scale);
  ASSERT_TRUE(light.usable()) << light.why();
  EXPECT_EQ(light.pieces(), 1);  // the light is one face: one piece, one contour sum
  const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  std::int64_t cast = 0;
  // A floor corner sees the whole light (the blocker is far off its line of sight): H = E F
  // with F exact, each ray weighing F; 8 equal terms summed and divided by 8, so 4 ulps.
  const Eigen::Vector3d lit(0.2, 3.8, 0.0);
  const double f_lit = s.exact(lit);
  ASSERT_GT(f_lit, 0.0);
  const Eigen::Vector3d H = light.irradiance(s.bvh, lit, n, 7, 0, cast);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(H[c], f_lit, 4e-16 * f_lit * 8);
  EXPECT_EQ(cast, 8);
  // Under the blocker's centre, in its umbra: every ray is blocked, H = 0 exactly.
  const Eigen::Vector3d umbra(2.1, 1.7, 0.0);
  ASSERT_EQ(s.exact(umbra), 0.0);
  EXPECT_EQ(light.irradiance(s.bvh, umbra, n, 7, 0, cast), Eigen::Vector3d::Zero());
  // A point behind the light's plane or facing away gets nothing, without a ray.
  const std::int64_t before = cast;
  EXPECT_EQ(light.irradiance(s.bvh, Eigen::Vector3d(2, 2, 3.5), n, 7, 0, cast),
            Eigen::Vector3d::Zero());
  EXPECT_EQ(light.irradiance(s.bvh, lit, -n, 7, 0, cast), Eigen::Vector3d::Zero());
  EXPECT_EQ(cast, before);
}

TEST(PixelDirectLight, IsUnbiasedInThePenumbraWithinItsOwnStandardError) {
  // Points across the penumbrae on the line y = 1.75: the mean of M independent estimates
  // (streams) of R rays each against the exact factor, within 4 standard errors of that
  // mean, the standard error measured from the M estimates themselves (a false failure
  // ~6e-5 per point). Also: the same stream gives the same bits.
  const ShadowSetup s;
  constexpr int kRays = 8, kStreams = 400;
  const PixelDirectLight light(s.scene, kRays, ff::kRayOffset * s.mesh.scale);
  const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  int penumbra = 0;
  for (double x = 0.3; x < 3.8; x += 0.25) {
    const Eigen::Vector3d p(x, 1.75, 0.0);
    const double f = s.exact(p);
    double sum = 0.0, sum2 = 0.0;
    std::int64_t cast = 0;
    for (int k = 0; k < kStreams; ++k) {
      const double h = light.irradiance(s.bvh, p, n, hash_keys(11, k), 0, cast)[1];
      sum += h;
      sum2 += h * h;
    }
    const double mean = sum / kStreams;
    const double var = std::max(0.0, sum2 / kStreams - mean * mean);
    const double se = std::sqrt(var / (kStreams - 1));
    EXPECT_NEAR(mean, f, 4.0 * se + 1e-15) << "x = " << x;
    if (se > 0.0) ++penumbra;
    std::int64_t c1 = 0, c2 = 0;
    EXPECT_EQ(light.irradiance(s.bvh, p, n, 99, 16, c1), light.irradiance(s.bvh, p, n, 99, 16, c2));
  }
  EXPECT_GE(penumbra, 4);  // the line does cross penumbrae
}

TEST(PixelDirectLight, RefusesTooManyEmittingFacesWithAReason) {
  // kMaxPieces + 1 emitting triangles: not usable, and says why.
  Scene scene;
  scene.materials.push_back(Material{});
  scene.materials[0].emission = Eigen::Vector3d::Ones();
  scene.surfaces.push_back({"lights", 0});
  for (int k = 0; k <= PixelDirectLight::kMaxPieces; ++k) {
    const auto v = static_cast<std::int32_t>(scene.vertices.size());
    scene.vertices.push_back(Eigen::Vector3d(k, 0, 0));
    scene.vertices.push_back(Eigen::Vector3d(k + 1, 0, 0));
    scene.vertices.push_back(Eigen::Vector3d(k, 1, 0));
    Face f;
    f.vertices = {v, v + 1, v + 2};
    scene.faces.push_back(f);
  }
  const PixelDirectLight light(scene, 4, 1e-6);
  EXPECT_FALSE(light.usable());
  EXPECT_NE(light.why().find("more than 64 emitting faces"), std::string::npos) << light.why();
}

}  // namespace
}  // namespace lambert
