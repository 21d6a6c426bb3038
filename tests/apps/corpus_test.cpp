// The real-scene corpus (data/: the atrium, a Sponza stand-in in centimetres with 1,292
// warped quads, slivers, T-junctions and coincident faces; the heat sink, a CAD STL in metres
// with 2,000:1 slivers) through every estimator and the hierarchical method: the runs finish,
// conserve energy, and agree with each other where physics says they must.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"

namespace lambert {
namespace {

const std::string kData = LAMBERT_TEST_DATA_DIR;

// The hemicube's energy imbalance on these scenes (its non-reciprocity part: aliasing of
// slivers and of patches 342 times larger than their neighbours, which averaging cannot
// repair), measured 3.4e-4 .. 1.1e-2 on the atrium and 2.0e-2 on the heat sink: bounded
// here so that it cannot grow unseen (a known limitation, in issue 37's note).
constexpr double kHemicubeImbalance = 0.03;

// Runs `solve` and returns its summary, checking what holds for every run: exit 0, every
// channel converged with an energy balance within `imbalance` (1e-6 by default: Gauss-Seidel's
// relative residual 1e-8 times the spectral bound 1/(1 - rho_max) = 3.6 of these materials,
// with room, F reciprocal), and every surface's mean radiosity finite and >= 0.
nlohmann::json solved(std::vector<std::string> args, const testing::TempDir& dir,
                      const std::string& name, double imbalance = 1e-6) {
  args.insert(args.begin(), "solve");
  args.insert(args.end(), {"-q", "-o", dir.file(name + ".csv")});
  const auto [code, err] = testing::run_capturing(args);
  EXPECT_EQ(code, kExitOk) << name << ": " << err;
  const nlohmann::json j = testing::read_json(dir.file(name + ".json"));
  for (const auto& c : j["channels"]) {
    EXPECT_EQ(c["status"], "converged") << name;
    EXPECT_LT(std::abs(c["energy"]["relative_imbalance"].get<double>()), imbalance) << name;
  }
  for (const auto& s : j["surfaces"])
    for (int c = 0; c < 3; ++c) {
      const double B = s["average_radiosity"][c].get<double>();
      EXPECT_TRUE(std::isfinite(B) && B >= 0.0) << name << " " << s["name"];
    }
  return j;
}

std::map<std::string, double> green_means(const nlohmann::json& j) {
  std::map<std::string, double> out;
  for (const auto& s : j["surfaces"]) out[s["name"]] = s["average_radiosity"][1].get<double>();
  return out;
}

TEST(CorpusSlow, TheAtriumUnderSkyAndSunAgreesAcrossEstimators) {
  // The atrium (5,197 patches: its detailed surfaces keep a patch per face) under a sky of
  // radiance ~1 and a sun of 23 W/m². The sunlit courtyard floor's mean radiosity is the
  // sun's exact shadow rays plus the sky through F's escape fractions: mc, hybrid and
  // gather agree on it and on the large walls to 3 % (mc and hybrid at 4 samples per pair
  // carry ~1 % noise on a surface mean). The hemicube runs, within kHemicubeImbalance, and
  // is off by up to 7.5 % (measured; the back walls): it is held to 10 %.
  testing::TempDir dir;
  const std::string atrium = kData + "/atrium/atrium.obj";
  const std::vector<std::string> light = {"--sky", "1,1.1,1.3", "--sun", "0.35,-1,0.25,24,23,21"};
  std::vector<std::map<std::string, double>> means;
  for (const std::string estimator : {"mc", "hybrid", "gather", "hemicube"}) {
    std::vector<std::string> args = {atrium, "--estimator", estimator};
    args.insert(args.end(), light.begin(), light.end());
    if (estimator == "mc" || estimator == "hybrid") args.insert(args.end(), {"--samples", "4"});
    means.push_back(green_means(
        solved(args, dir, estimator, estimator == "hemicube" ? kHemicubeImbalance : 1e-6)));
  }
  for (const char* surface : {"courtyard_floor", "back_wall_north", "back_wall_south", "end_walls"})
    for (size_t k = 1; k < means.size(); ++k)
      EXPECT_NEAR(means[k][surface], means[0][surface], (k == 3 ? 0.10 : 0.03) * means[0][surface])
          << surface << ", estimator " << k;
  // The sun lights the courtyard floor: it outshines the galleries' floors in their shade.
  EXPECT_GT(means[1]["courtyard_floor"], 3 * means[1]["gallery_floor_north"]);
}

TEST(CorpusSlow, RaysReachTheAtriumsWarpedFloorTilesAsTheExactFactorSays) {
  // Looking down at the courtyard floor from 7 m: its 624 tiles kept as quads are warped by
  // up to 1e-4 of their size (5e-3 cm), more than the rays' end offset (2.9e-3 cm). The ray
  // kernel ended rays on a tile's bilinear surface, below the triangles Embree traces, and
  // counted 6.5 % of the floor as hidden (mc 0.2684 against analytic 0.2870 for the floor
  // alone); every surface's factor must now agree with the exact one within 4 of mc's
  // standard errors plus 1e-4 relative (analytic's own error on warped quads, measured
  // 2e-5 relative on two warped squares).
  testing::TempDir dir;
  const std::string atrium = kData + "/atrium/atrium.obj";
  std::vector<nlohmann::json> runs;
  for (const std::string estimator : {"analytic", "mc"}) {
    std::vector<std::string> args = {"formfactors",
                                     atrium,
                                     "-q",
                                     "--point",
                                     "1000,700,50",
                                     "--normal",
                                     "0,-1,0",
                                     "--estimator",
                                     estimator,
                                     "-o",
                                     dir.file(estimator + ".json")};
    if (estimator == "mc") args.insert(args.end(), {"--samples", "10000"});
    const auto [code, err] = testing::run_capturing(args);
    ASSERT_EQ(code, kExitOk) << err;
    runs.push_back(testing::read_json(dir.file(estimator + ".json")));
  }
  const auto& exact = runs[0]["F"];
  const auto& mc = runs[1]["F"];
  ASSERT_EQ(exact.size(), mc.size());
  ASSERT_GT(exact[0].get<double>(), 0.25);  // the floor fills most of the view
  for (size_t k = 0; k < exact.size(); ++k) {
    const double e = exact[k].get<double>(), m = mc[k].get<double>();
    const double se = runs[1]["stderr"][k].get<double>();
    EXPECT_NEAR(m, e, 4 * se + 1e-4 * e) << runs[0]["surfaces"][k];
  }
}

TEST(CorpusSlow, TheAtriumSolvesHierarchicallyWithItsCoincidentPlaquesAlight) {
  // Hierarchical radiosity (the method that crashed on Sponza) with the plaques, faces lying
  // exactly on the end walls, as the emitters: energy balances to rounding (its sweeps'
  // bookkeeping is exact), and agrees with the matrix method on the walls to 10 % (its
  // default epsilon 1e-5 against hybrid at 4 samples per pair).
  testing::TempDir dir;
  const std::string atrium = kData + "/atrium/atrium.obj";
  const std::vector<std::string> emit = {"--emit", "plaques=2000,2000,2000"};
  std::vector<std::string> h = {atrium, "--method", "hierarchical"};
  h.insert(h.end(), emit.begin(), emit.end());
  const nlohmann::json hj = solved(h, dir, "hierarchical");
  std::vector<std::string> m = {atrium, "--samples", "4"};
  m.insert(m.end(), emit.begin(), emit.end());
  const auto hier = green_means(hj), matrix = green_means(solved(m, dir, "matrix"));
  for (const char* surface : {"end_walls", "courtyard_floor", "back_wall_north"})
    EXPECT_NEAR(hier.at(surface), matrix.at(surface), 0.10 * matrix.at(surface)) << surface;
}

TEST(CorpusSlow, TheHeatSinkUnderTheSkyAgreesAcrossEstimators) {
  // The heat sink (binary STL, metres, fins of 2,000:1 slivers) under a sky of radiance 1:
  // no patch can be brighter than an open one, B <= rho pi L, and mc, hybrid and gather agree
  // on the mean B to 2 % (B = rho pi L (1 - r) + ..., r the fraction of the sky the fins hide
  // from each other: B is 0.2 of rho pi L; their noise at 4 samples is under 1 %). The hemicube
  // runs within kHemicubeImbalance but its mean B is 33 % low (measured 0.209 against 0.313:
  // its 2,000:1 slivers alias on the hemicube's pixels): held to 40 %, and named in issue 37.
  testing::TempDir dir;
  const std::string sink = kData + "/heat_sink/heat_sink.stl";
  std::vector<double> means;
  for (const std::string estimator : {"mc", "hybrid", "gather", "hemicube"}) {
    std::vector<std::string> args = {sink, "--sky", "1,1,1", "--estimator", estimator};
    if (estimator == "mc" || estimator == "hybrid") args.insert(args.end(), {"--samples", "4"});
    const nlohmann::json j =
        solved(args, dir, estimator, estimator == "hemicube" ? kHemicubeImbalance : 1e-6);
    const double B = j["surfaces"][0]["average_radiosity"][1].get<double>();
    EXPECT_LE(B, 0.5 * M_PI * (1 + 1e-12)) << estimator;  // STL's default reflectance 0.5
    means.push_back(B);
  }
  for (size_t k = 0; k < means.size(); ++k)
    EXPECT_NEAR(means[k], means[1], (k == 3 ? 0.40 : 0.02) * means[1]) << k;
}

// Discontinuity meshing on the corpus (issue 35: every method on the real scenes). Their
// shadow lines meet at angles and distances too small to resolve (the heat sink's fins touch
// its base along 2,000:1 slivers; the atrium's warped quads and coincident plaques): the heat
// sink made 2.5 million patches for a target of 2,000 in 10 minutes (and warned 917 times),
// the atrium passed 16 times its plan by its tenth surface. Now each is refused as soon as
// the mesh passes 16 times its plan: exit 2, one line naming the surface and what to do, in
// seconds, and no output written.
TEST(CorpusSlow, DiscontinuityMeshingRefusesSliverScenesAtOnce) {
  testing::TempDir dir;
  for (const std::string scene : {"/heat_sink/heat_sink.stl", "/atrium/atrium.obj"}) {
    const auto [code, err] = testing::run_capturing(
        {"solve", kData + scene, "--discontinuity", "--sky", "1,1,1", "-o", dir.file("B.csv")});
    EXPECT_EQ(code, kExitUsage) << scene << ": " << err;
    EXPECT_NE(err.find("discontinuity meshing passed"), std::string::npos) << err;
    EXPECT_NE(err.find("mesh it without --discontinuity"), std::string::npos) << err;
    EXPECT_EQ(err.find("stopped refining"), std::string::npos) << err;  // refused, not warned
    EXPECT_FALSE(std::filesystem::exists(dir.file("B.csv"))) << scene;
  }
}

}  // namespace
}  // namespace lambert
