// Scenes in assimp's formats through the commands (issue 35 item 6): a glTF enclosure solves
// to the furnace's closed form; a malformed one is exit 1 with one line and no output.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "common/gltf_cube.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"

namespace lambert {
namespace {

using testing::read_json;
using testing::run_capturing;

// The closed cube of "glow" (rho = 0.25, 0.5, 0.75; E = 1, 0.5, 0) is a furnace: every patch
// sees the walls only (row sums 1), so B = E / (1 - rho) = (4/3, 1, 0) on every patch.
// Tolerance: the solver stops at a relative residual of 1e-8 (the default --tol), so
// |B - B*| <= 1e-8 |E| / (1 - rho_max) = 4e-8 per channel; the unoccluded contour kernel's row
// sums are exact to ~1e-12 in a convex enclosure. 1e-7 leaves room for both.
TEST(ModelCli, TheFurnaceInAGltfCubeIsEmissionOverOneMinusReflectance) {
  const testing::TempDir dir;
  const std::string scene =
      dir.write("cube.gltf", testing::gltf_with_data_uri(testing::kScaleAndMove));
  const auto [code, err] =
      run_capturing({"solve", scene, "--patches", "200", "-q", "-o", dir.file("B.csv")});
  ASSERT_EQ(code, 0) << err;
  const auto summary = read_json(dir.file("B.json"));
  ASSERT_EQ(summary["surfaces"].size(), 1u);
  const auto& box = summary["surfaces"][0];
  EXPECT_EQ(box["name"], "box");
  const double expected[3] = {1.0 / 0.75, 0.5 / 0.5, 0.0};
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(box["average_radiosity"][c].get<double>(), expected[c], 1e-7) << c;
}

TEST(ModelCli, AMalformedModelIsExitOneWithOneLineAndNoOutput) {
  const testing::TempDir dir;
  const std::string whole = testing::gltf_with_data_uri(testing::kScaleAndMove);
  const std::string scene = dir.write("broken.gltf", whole.substr(0, whole.size() / 2));
  const auto [code, err] = run_capturing({"solve", scene, "-q", "-o", dir.file("B.csv")});
  EXPECT_EQ(code, 1);
  EXPECT_EQ(err.rfind("lambert: " + scene + ": ", 0), 0u) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("B.csv")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("B.json")));
}

}  // namespace
}  // namespace lambert
