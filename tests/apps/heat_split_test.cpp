// --split-angle through the CLI: a heat sink (a base plate and two fins, one connected STL
// body) split at its feature edges, its faces listed by `info --list-surfaces` and given
// different conditions by `heat`'s surfaces file; bad angles are usage errors.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/stl_text.hpp"
#include "common/temp_dir.hpp"
#include "solvers/thermal.hpp"

namespace lambert {
namespace {

using testing::read_json;
using testing::run;
using testing::run_capturing;
using testing::TempDir;
using P = Eigen::Vector3d;

// The sink's profile in x-z, extruded along y in [0, 2]: a 4 x 0.5 base with two fins
// (x in [0.5, 1] and [3, 3.5]) up to z = 2.5. Every face is split where a neighbour's edge
// ends, so faces meet edge to edge (no T-junctions) and the body is one component.
std::string heat_sink_stl() {
  std::vector<testing::StlTriangle> t;
  const auto tri = [&](P a, P b, P c) { t.push_back({a, b, c}); };
  const auto quad = [&](P a, P b, P c, P d) {  // counter-clockwise about its front
    tri(a, b, c);
    tri(a, c, d);
  };
  const double w = 2.0;  // depth along y
  // A wall along the profile edge (x0,z0)->(x1,z1), its front on the right of the direction
  // of travel seen from +y (the profile is walked clockwise seen from +y: outward fronts).
  const auto wall = [&](double x0, double z0, double x1, double z1) {
    quad(P(x0, 0, z0), P(x1, 0, z1), P(x1, w, z1), P(x0, w, z0));
  };
  const double xs[] = {0, 0.5, 1, 3, 3.5, 4};
  // Facet order sets the names: the base's bottom (sink/face_1), then the first fin's left
  // side, top and right side (face_2, face_3, face_4), then the rest.
  for (int k = 0; k < 5; ++k) wall(xs[k + 1], 0, xs[k], 0);  // bottom, facing -z
  wall(0.5, 0.5, 0.5, 2.5);                                  // fin 1 left, -x
  wall(0.5, 2.5, 1, 2.5);                                    // fin 1 top, +z
  wall(1, 2.5, 1, 0.5);                                      // fin 1 right, +x
  wall(0, 0, 0, 0.5);                                        // base left end, -x
  wall(0, 0.5, 0.5, 0.5);                                    // base top, left of fin 1
  wall(1, 0.5, 3, 0.5);                                      // base top between the fins
  wall(3, 0.5, 3, 2.5);                                      // fin 2 left
  wall(3, 2.5, 3.5, 2.5);                                    // fin 2 top
  wall(3.5, 2.5, 3.5, 0.5);                                  // fin 2 right
  wall(3.5, 0.5, 4, 0.5);                                    // base top, right of fin 2
  wall(4, 0.5, 4, 0);                                        // base right end, +x
  // The two end caps (y = 0 facing -y, y = w facing +y): rectangles meeting the walls' edges.
  const auto caps = [&](double x0, double x1, double z0, double z1) {
    quad(P(x0, 0, z0), P(x1, 0, z0), P(x1, 0, z1), P(x0, 0, z1));
    quad(P(x0, w, z0), P(x0, w, z1), P(x1, w, z1), P(x1, w, z0));
  };
  for (int k = 0; k < 5; ++k) caps(xs[k], xs[k + 1], 0, 0.5);
  caps(0.5, 1, 0.5, 2.5);
  caps(3, 3.5, 0.5, 2.5);
  return testing::ascii_stl({{"sink", t}});
}

std::vector<std::string> listed_surfaces(const std::vector<std::string>& args) {
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  std::vector<std::string> a = {"info"};
  a.insert(a.end(), args.begin(), args.end());
  a.push_back("--list-surfaces");
  EXPECT_EQ(run(a), 0);
  const std::string out = ::testing::internal::GetCapturedStdout();
  ::testing::internal::GetCapturedStderr();
  std::vector<std::string> names;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) names.push_back(line.substr(0, line.find('\t')));
  return names;
}

TEST(SplitAngleCli, InfoListsTheHeatSinksFaces) {
  const TempDir dir;
  const std::string stl = dir.write("sink.stl", heat_sink_stl());
  EXPECT_EQ(listed_surfaces({stl}), std::vector<std::string>{"sink"});
  // 6 base walls (bottom, two ends, three top strips between the fins), 3 per fin, 2 end
  // caps: 14 faces. A cap is one face: its rectangles are coplanar and meet edge to edge.
  const auto names = listed_surfaces({stl, "--split-angle", "30"});
  ASSERT_EQ(names.size(), 14u);
  for (size_t k = 0; k < names.size(); ++k)
    EXPECT_EQ(names[k], "sink/face_" + std::to_string(k + 1));
}

TEST(SplitAngleCli, HeatGivesTheBaseAndAFinTheirOwnTemperatures) {
  const TempDir dir;
  const std::string stl = dir.write("sink.stl", heat_sink_stl());
  // The base's bottom (face_1) held at 400 K, the first fin's right side (face_4, facing the
  // second fin across the base) at 350 K, the rest adiabatic (re-radiating).
  const std::string json = dir.write("s.json", R"({
      "sink/face_1": {"emissivity": 0.9, "temperature": 400},
      "sink/face_4": {"emissivity": 0.8, "temperature": 350},
      "*": {"emissivity": 0.7, "heat_flux": 0}})");
  ASSERT_EQ(run({"heat", stl, "--split-angle", "30", "--surfaces", json, "--patches", "150",
                 "--ambient-temperature", "300", "-o", dir.file("sink"), "-q"}),
            0);
  const auto j = read_json(dir.file("sink.json"));
  std::set<std::string> names;
  for (const auto& s : j["surfaces"]) {
    const std::string name = s["name"];
    names.insert(name);
    if (name == "sink/face_1") {
      EXPECT_EQ(s["condition"], "temperature");
      EXPECT_EQ(double(s["temperature_K"]), 400.0);  // a given T is reported as given
      EXPECT_EQ(double(s["emissivity"]), 0.9);
      // It faces down and sees only the environment (F = 0: every ray escapes), so it loses
      // Q = eps A sigma (T^4 - Ta^4) exactly up to the solve (relative tolerance << 1e-6).
      const double expected =
          0.9 * 8.0 * kStefanBoltzmann * (std::pow(400.0, 4) - std::pow(300.0, 4));
      EXPECT_NEAR(double(s["area_m2"]), 8.0, 1e-12);
      EXPECT_NEAR(double(s["power_W"]), expected, 1e-6 * expected);
    } else if (name == "sink/face_4") {
      EXPECT_EQ(s["condition"], "temperature");
      EXPECT_EQ(double(s["temperature_K"]), 350.0);
      EXPECT_EQ(double(s["emissivity"]), 0.8);
    } else {
      EXPECT_EQ(s["condition"], "heat_flux") << name;
      EXPECT_EQ(double(s["given"]), 0.0) << name;
      // An adiabatic face settles between the environment and the hottest face it sees (to
      // the solve's tolerance, << 1e-6 K); one that sees only the sky (a fin's top, the end
      // caps) stays at the environment's 300 K. The second fin's inner side (face_8) and the
      // base between the fins (face_7) face the 350 K fin: warmer than the environment.
      const double t = s["temperature_K"];
      EXPECT_GE(t, 300.0 - 1e-6) << name;
      EXPECT_LE(t, 350.0 + 1e-6) << name;
      if (name == "sink/face_7" || name == "sink/face_8") {
        EXPECT_GT(t, 301.0) << name;
      }
    }
  }
  EXPECT_EQ(names.size(), 14u);
  EXPECT_TRUE(names.count("sink/face_1") && names.count("sink/face_4"));
}

TEST(SplitAngleCli, BadAnglesAreUsageErrors) {
  const TempDir dir;
  const std::string stl = dir.write("sink.stl", heat_sink_stl());
  for (const char* bad : {"-1", "180.5", "nan", "ten"}) {
    const auto [code, err] = run_capturing({"info", stl, "--split-angle", bad, "--list-surfaces"});
    EXPECT_EQ(code, 2) << bad;
    EXPECT_NE(err.find("--split-angle"), std::string::npos) << err;
    EXPECT_NE(err.find("[0, 180]"), std::string::npos) << err;
  }
}

}  // namespace
}  // namespace lambert
