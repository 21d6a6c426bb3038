// --sky and --sun (issue 35): daylight as first-bounce sources of the solve, checked against
// closed forms; the sun's shadow drawn per pixel; the refusals.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "geometry/analytic.hpp"
#include "io/exr.hpp"

namespace lambert {
namespace {

using testing::read_json;
using testing::run_capturing;

// OBJ text of unit-reflectance-0.5 quads, one group per entry.
struct LitQuad {
  std::string name;
  std::vector<Eigen::Vector3d> corners;  // counter-clockwise about the front normal
};
std::string lit_obj_text(const std::vector<LitQuad>& quads, double rho = 0.5) {
  std::string mtl = "newmtl grey\nKd " + std::to_string(rho) + ' ' + std::to_string(rho) + ' ' +
                    std::to_string(rho) + "\n";
  std::string obj = "mtllib scene.mtl\n";
  int v = 0;
  for (const LitQuad& q : quads) {
    for (const auto& c : q.corners)
      obj += "v " + std::to_string(c.x()) + ' ' + std::to_string(c.y()) + ' ' +
             std::to_string(c.z()) + '\n';
    obj += "g " + q.name + "\nusemtl grey\nf";
    for (size_t k = 0; k < q.corners.size(); ++k) obj += ' ' + std::to_string(++v);
    obj += '\n';
  }
  return obj + "#mtl\n" + mtl;
}

std::string write_lit_scene(const testing::TempDir& dir, const std::vector<LitQuad>& quads,
                            double rho = 0.5) {
  const std::string text = lit_obj_text(quads, rho);
  const size_t split = text.find("#mtl\n");
  dir.write("scene.mtl", text.substr(split + 5));
  return dir.write("scene.obj", text.substr(0, split));
}

double lit_surface_B(const nlohmann::json& summary, const std::string& name, int c) {
  for (const auto& s : summary["surfaces"])
    if (s["name"] == name) return s["average_radiosity"][c].get<double>();
  ADD_FAILURE() << "no surface " << name;
  return 0.0;
}

}  // namespace

TEST(Daylight, AWhitePlaneUnderTheSkyIsAsBrightAsTheSky) {
  // Nothing else in view: the plane's escape fraction is 1, its irradiance π L and its
  // radiosity ρ π L (radiance ρ L). The solver stops at a relative residual of 1e-8.
  testing::TempDir dir;
  const std::string obj =
      write_lit_scene(dir, {{"ground", {{0, 0, 0}, {0, 0, 2}, {3, 0, 2}, {3, 0, 0}}}}, 0.8);
  const auto [code, err] = run_capturing(
      {"solve", obj, "--sky", "10,20,30", "--max-edge", "1", "-o", dir.file("B.csv")});
  ASSERT_EQ(code, kExitOk) << err;
  const nlohmann::json j = read_json(dir.file("B.json"));
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(lit_surface_B(j, "ground", c), 0.8 * M_PI * 10 * (c + 1), 1e-7 * 80 * M_PI);
  // The report's power: area 6 m² × π L.
  EXPECT_NEAR(j["daylight"]["sky_power"][0].get<double>(), 6 * M_PI * 10, 1e-9 * 60 * M_PI);
}

TEST(Daylight, TwoFacingPlatesUnderTheSkyMatchTheClosedForm) {
  // Unit squares 1 apart, facing each other: each sees the other with F = 0.19982 (Howell
  // C-11) and the sky with 1 − F. By symmetry B = ρ π L (1 − F) / (1 − ρ F). One patch per
  // face and the analytic estimator to 1e-9: F's error is far below the 1e-6 asked here.
  testing::TempDir dir;
  const std::string obj =
      write_lit_scene(dir, {{"lower", {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}},
                            {"upper", {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}}}});
  const auto [code, err] =
      run_capturing({"solve", obj, "--sky", "1,1,1", "--estimator", "analytic", "--ff-tol", "1e-9",
                     "--max-edge", "2", "-o", dir.file("B.csv")});
  ASSERT_EQ(code, kExitOk) << err;
  const double F = parallel_rectangles_factor(1, 1, 1), rho = 0.5;
  const double expected = rho * M_PI * (1 - F) / (1 - rho * F);
  const nlohmann::json j = read_json(dir.file("B.json"));
  EXPECT_NEAR(lit_surface_B(j, "lower", 1), expected, 1e-6 * expected);
  EXPECT_NEAR(lit_surface_B(j, "upper", 1), expected, 1e-6 * expected);
  // Energy: what the patches reflect of the sky, Σ A ρ H_sky, is the solve's emission.
  const double sky = j["daylight"]["sky_power"][1].get<double>();
  EXPECT_NEAR(sky, 2 * M_PI * (1 - F), 1e-6 * sky);
}

TEST(Daylight, TheSunsShadowIsDrawnPerPixelNotPerPatch) {
  // A 4 × 4 ground with a 1 × 1 square held 1 above it, the sun at 45°, no sky: the ground is
  // lit (B = ρ S cos 45°) or in the square's shadow (B = 0: the square faces up and sends
  // nothing down), and the square's top is lit like the ground. Patches are 2 wide, so a
  // per-patch sun would give grey levels between; per pixel every pixel is exactly one of
  // the two levels (one centred sample per pixel).
  testing::TempDir dir;
  const std::string obj = write_lit_scene(
      dir, {{"ground", {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}}},
            {"square", {{-0.5, 1, -0.5}, {-0.5, 1, 0.5}, {0.5, 1, 0.5}, {0.5, 1, -0.5}}}});
  const auto [code, err] = run_capturing({"run",         obj, "--sun",     "1,-1,0,100,100,100",
                                          "--max-edge",  "2", "--size",    "96x96",
                                          "--antialias", "1", "--eye",     "0",
                                          "6",           "4", "--look-at", "0",
                                          "0",           "0", "-o",        dir.file("out/")});
  ASSERT_EQ(code, kExitOk) << err;
  const Image img = read_image_exr(dir.file("out/scene.exr"));
  const double lit = 0.5 * 100 * std::sqrt(0.5) / M_PI;  // radiance ρ S cos / π
  int shadow = 0, bright = 0, other = 0;
  for (size_t k = 0; k < img.alpha.size(); ++k) {
    if (img.alpha[k] < 1) continue;  // the background
    const double L = img.rgb[3 * k + 1];
    if (std::abs(L) < 1e-4 * lit)
      ++shadow;
    else if (std::abs(L - lit) < 1e-4 * lit)  // float pixels: 1e-4 is far above their rounding
      ++bright;
    else
      ++other;
  }
  EXPECT_EQ(other, 0);
  EXPECT_GT(shadow, 100);
  EXPECT_GT(bright, 1000);
  const nlohmann::json report = read_json(dir.file("out/report.json"));
  // The sun's power on the patches: the lit ground (16 − 1 m² of shadow) and the square's top.
  EXPECT_NEAR(report["daylight"]["sun_power"][0].get<double>(), 100 * std::sqrt(0.5) * 16,
              0.02 * 100 * 16);
}

TEST(Daylight, ASceneLitOnlyByDaylightRunsAndBadDaylightIsRefused) {
  testing::TempDir dir;
  const std::string obj =
      write_lit_scene(dir, {{"ground", {{0, 0, 0}, {0, 0, 2}, {3, 0, 2}, {3, 0, 0}}}});
  const auto refused = [&](std::vector<std::string> args, const std::string& why) {
    if (std::find(args.begin(), args.end(), "hierarchical") == args.end())
      args.insert(args.end(), {"--max-edge", "1"});  // (--method hierarchical refuses it)
    const auto [code, err] = run_capturing(args);
    EXPECT_EQ(code, kExitUsage) << err;
    EXPECT_NE(err.find(why), std::string::npos) << err;
  };
  // Nothing emits and no daylight: the refusal names all three ways to light it.
  refused({"solve", obj, "-o", dir.file("B.csv")}, "--sky R,G,B or --sun DX,DY,DZ,R,G,B");
  refused({"solve", obj, "--sun", "0,0,0,1,1,1", "-o", dir.file("B.csv")}, "has no length");
  refused({"solve", obj, "--sun", "0,-1,0,1,-1,1", "-o", dir.file("B.csv")}, ">= 0");
  refused({"solve", obj, "--sun", "0,-1,0,1,1", "-o", dir.file("B.csv")}, "DX,DY,DZ,R,G,B");
  refused({"solve", obj, "--sky", "1,-1,1", "-o", dir.file("B.csv")}, "--sky");
  // What does not read daylight refuses it.
  refused({"solve", obj, "--sky", "1,1,1", "--method", "hierarchical", "-o", dir.file("B.csv")},
          "--sky does not apply");
  refused({"run", obj, "--sun", "0,-1,0,1,1,1", "--shading", "raytrace", "-o", dir.file("o/")},
          "--sun does not apply");
  refused({"formfactors", obj, "--sky", "1,1,1", "-o", dir.file("F.mtx")}, "--sky");
  refused({"run", obj, "--sky", "1,1,1", "--vertex-interp", "exact-direct", "-o", dir.file("o/")},
          "exact-direct");
  EXPECT_FALSE(std::filesystem::exists(dir.file("B.csv")));
  // Mirrors and glass: refused when the scene is loaded, before its form factors.
  {
    const auto [code, err] = run_capturing(
        {"solve",
         std::string(LAMBERT_TEST_DATA_DIR) + "/cornell_box_specular/cornell_box_specular.obj",
         "--sky", "1,1,1", "-o", dir.file("B.csv")});
    EXPECT_EQ(code, kExitUsage) << err;
    EXPECT_NE(err.find("mirrors and glass"), std::string::npos) << err;
    EXPECT_EQ(err.find("form factors"), std::string::npos) << err;  // no F was computed
  }
  const auto [code, err] = run_capturing(
      {"solve", obj, "--sun", "0,-1,0,1,1,1", "--max-edge", "1", "-o", dir.file("B.csv")});
  EXPECT_EQ(code, kExitOk) << err;
}

}  // namespace lambert

namespace lambert {

TEST(DaylightSlow, TheBunnyUnderTheSkyAgreesAcrossEstimators) {
  // The real-scene corpus (data/bunny, PLY): the bunny under a uniform sky of radiance 1 with
  // each estimator that fills F. Physics: no patch can be brighter than an open one, B ≤ ρ π L
  // (every radiance in the scene is at most ρ times the brightest it sees, and the sky is
  // the brightest); the sky's power is at most π L times the area. The estimators agree on the
  // mean B to 1.5 %: B̄ = ρ π L (1 − r̄) + ..., r̄ ≈ 0.06 the mean row sum, so even a 10 % bias
  // of the row sums (hemicube aliasing is a few %) moves B̄ by under 1 %.
  testing::TempDir dir;
  const std::string bunny = std::string(LAMBERT_TEST_DATA_DIR) + "/bunny/bun_zipper_res4.ply";
  std::vector<double> means;
  for (const char* estimator : {"mc", "hybrid", "gather", "hemicube"}) {
    std::vector<std::string> args = {
        "solve",       bunny,     "--sky", "1,1,1",
        "--estimator", estimator, "-o",    dir.file(std::string(estimator) + ".csv")};
    if (std::string(estimator) == "mc" || std::string(estimator) == "hybrid")
      args.insert(args.end(), {"--samples", "8"});
    const auto [code, err] = testing::run_capturing(args);
    ASSERT_EQ(code, kExitOk) << estimator << ": " << err;
    const nlohmann::json j = testing::read_json(dir.file(std::string(estimator) + ".json"));
    const double B = j["surfaces"][0]["average_radiosity"][1].get<double>();
    const double area = j["surfaces"][0]["area"].get<double>();
    EXPECT_LE(B, 0.5 * M_PI) << estimator;
    EXPECT_LE(j["daylight"]["sky_power"][1].get<double>(), M_PI * area * (1 + 1e-12)) << estimator;
    means.push_back(B);
  }
  const double mean = (means[0] + means[1] + means[2] + means[3]) / 4;
  for (double B : means) EXPECT_NEAR(B, mean, 0.015 * mean);
}

}  // namespace lambert
