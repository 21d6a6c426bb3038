#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"

namespace lambert {

using testing::run;
using testing::slurp;
namespace {



// Numbers of the JSON array that follows `"key": [` (flat arrays only).
std::vector<double> json_numbers(const std::string& json, const std::string& key) {
  std::vector<double> out;
  size_t at = json.find("\"" + key + "\": [");
  if (at == std::string::npos) return out;
  at = json.find('[', at) + 1;
  const size_t end = json.find(']', at);
  std::stringstream ss(json.substr(at, end - at));
  std::string tok;
  while (std::getline(ss, tok, ',')) out.push_back(std::stod(tok));
  return out;
}

// The inside of a unit cube as an OBJ file (faces wound to point inwards).
const char* kCubeObj =
    "mtllib c.mtl\nusemtl grey\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "g bottom\nf 1 2 3 4\ng top\nf 5 8 7 6\ng left\nf 1 4 8 5\ng right\nf 2 6 7 3\n"
    "g front\nf 1 5 6 2\ng back\nf 4 3 7 8\n";

}  // namespace

TEST(FormFactorsCommand, SensorPointAtTheCubeCentreSeesEachFaceAnalytically) {
  testing::TempDir dir;
  dir.write("c.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  const std::string obj = dir.write("c.obj", kCubeObj);
  const std::string out = dir.file("p.json");
  ASSERT_EQ(run({"formfactors", obj, "-q", "--point", "0.5,0.5,0.5", "--normal", "0,0,1",
                 "--max-edge", "0.5", "-o", out}),
            kExitOk);
  const std::string json = slurp(out);
  const auto F = json_numbers(json, "F");
  ASSERT_EQ(F.size(), 6u);
  // Surfaces in file order: bottom, top, left, right, front, back. Facing +z from the
  // centre: the top face is a centred parallel square (side 1 at distance 0.5), four times
  // the corner formula with A = B = 1: (2/π)(1/√2) atan(1/√2) x 2 = 0.55397...; the sides
  // share the rest equally and the bottom is behind. No blocker: only rounding remains.
  const double top = 4.0 / M_PI * std::sqrt(0.5) * std::atan(std::sqrt(0.5));
  EXPECT_NEAR(F[1], top, 1e-12);
  EXPECT_NEAR(F[0], 0.0, 1e-15);
  for (int s = 2; s < 6; ++s) EXPECT_NEAR(F[s], (1 - top) / 4, 1e-12);
}

TEST(FormFactorsCommand, BySurfaceTableIsReciprocalAndRowsOfTheClosedCubeSumToOne) {
  testing::TempDir dir;
  dir.write("c.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  const std::string obj = dir.write("c.obj", kCubeObj);
  const std::string out = dir.file("s.json");
  ASSERT_EQ(run({"formfactors", obj, "-q", "--by-surface", "--max-edge", "0.5", "--samples", "4",
                 "-o", out}),
            kExitOk);
  const std::string json = slurp(out);
  EXPECT_NE(json.find("\"surfaces\""), std::string::npos);
  EXPECT_NE(json.find("\"stderr\""), std::string::npos);
  // Rows: F[g] arrays appear in order after "F": [[ ... ]]; parse the whole nested block.
  const size_t at = json.find("\"F\": [");
  std::string block = json.substr(at, json.find("\"stderr\"") - at);
  std::vector<double> all;
  std::string num;
  for (char c : block.substr(5)) {
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == 'e' || c == '-') {
      num += c;
    } else if (!num.empty()) {
      all.push_back(std::stod(num));
      num.clear();
    }
  }
  ASSERT_EQ(all.size(), 36u);
  for (int g = 0; g < 6; ++g) {
    double sum = 0;
    for (int h = 0; h < 6; ++h) {
      sum += all[g * 6 + h];
      // Equal areas: reciprocity makes the table symmetric to rounding.
      EXPECT_NEAR(all[g * 6 + h], all[h * 6 + g], 1e-14);
    }
    // Unoccluded enclosure, hybrid: quadrature error per entry < 1e-5 (see the engine tests).
    EXPECT_NEAR(sum, 1.0, 1e-4);
  }
}

TEST(FormFactorsCommand, SavedMatrixIsRefusedForAnotherMeshing) {
  testing::TempDir dir;
  dir.write("c.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  const std::string obj = dir.write("c.obj", kCubeObj);
  ASSERT_EQ(run({"formfactors", obj, "-q", "--max-edge", "0.5", "--samples", "2", "-o", dir.file("F.mtx")}), kExitOk);
  ASSERT_EQ(run({"formfactors", obj, "-q", "--max-edge", "0.5", "--samples", "2", "-o", dir.file("F.bin")}), kExitOk);
  EXPECT_NE(slurp(dir.file("F.report.json")).find("\"reciprocity_max\""), std::string::npos);
  EXPECT_EQ(run({"formfactors", "-q", "-o", dir.file("x.bin"), "--estimator", "nope"}), kExitUsage);
}

}  // namespace lambert

namespace lambert {

TEST(FormFactorsCommand, OutputIntoAMissingDirectoryIsRefusedBeforeAnyWork) {
  testing::TempDir dir;
  // A usage error (exit 2) from the option check, before the scene is even loaded.
  EXPECT_EQ(testing::run({"formfactors", "-q", "-o", dir.file("missing/F.bin")}), kExitUsage);
  EXPECT_EQ(testing::run({"solve", "-q", "-o", dir.file("missing/B.csv")}), kExitUsage);
  EXPECT_EQ(testing::run({"render", "-q", "--png", dir.file("missing/x.png")}), kExitUsage);
}

}  // namespace lambert
