#include "io/medium_file.hpp"

#include <gtest/gtest.h>

#include <sstream>

#include "core/error.hpp"

namespace lambert {
namespace {

Medium parse(const std::string& text) {
  std::istringstream in(text);
  return read_medium_grid_stream(in, "grid.txt");
}

// The message of the SceneError `text` raises ("" when it parses).
std::string grid_refusal(const std::string& text) {
  try {
    parse(text);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MediumGridFile, ReadsBoundsResolutionAndVoxelsXFastest) {
  const Medium m = parse(
      "# comment\n\nbounds -1 0 0 1 2 3\r\nresolution 2 1 1\n"
      "0.1 0.2 0.3  0.4 0.3 0.2  0 0 0\n"
      "1 1 1 0 0 0 5 6 7 # hot\n");
  EXPECT_EQ(m.lo, Eigen::Vector3d(-1, 0, 0));
  EXPECT_EQ(m.hi, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(m.resolution, Eigen::Vector3i(2, 1, 1));
  EXPECT_EQ(m.sigma_a(0, 2), 0.3);
  EXPECT_EQ(m.sigma_s(0, 0), 0.4);
  EXPECT_EQ(m.emission(1, 1), 6.0);
  EXPECT_EQ(m.source, "grid.txt");
}

TEST(MediumGridFile, RefusalsNameTheLine) {
  const std::string head = "bounds 0 0 0 1 1 1\nresolution 1 1 2\n";
  const std::string ok = "1 1 1 0 0 0 0 0 0\n";
  EXPECT_EQ(grid_refusal(head + ok + ok), "");
  EXPECT_NE(grid_refusal(head + ok + "1 1 1 0 0 0 0 0 -1\n").find("grid.txt:4"), std::string::npos);
  EXPECT_NE(grid_refusal(head + ok + "1 1 1 0 0 0 0 0 nan\n").find("grid.txt:4"),
            std::string::npos);
  EXPECT_NE(grid_refusal(head + ok + "1 1\n").find("grid.txt:4"), std::string::npos);
  EXPECT_NE(grid_refusal(head + "1 2 1 0 0 0 0 0 0\n").find("grid.txt:3"),
            std::string::npos);  // colour
  EXPECT_NE(grid_refusal(head + "0 0 0 0 0 0 1 0 0\n").find("grid.txt:3"),
            std::string::npos);                                                        // no σt
  EXPECT_NE(grid_refusal(head + ok).find("1 voxel lines"), std::string::npos);         // too few
  EXPECT_NE(grid_refusal(head + ok + ok + ok).find("grid.txt:5"), std::string::npos);  // too many
  EXPECT_NE(grid_refusal(ok).find("grid.txt:1"), std::string::npos);  // before the header
  EXPECT_NE(grid_refusal("bounds 0 0 0 1 -1 1\n").find("grid.txt:1"), std::string::npos);
  EXPECT_NE(grid_refusal("bounds 0 0 0 1 1 1\nresolution 1 0 1\n").find("grid.txt:2"),
            std::string::npos);
  EXPECT_NE(grid_refusal("").find("missing"), std::string::npos);
  EXPECT_NE(grid_refusal(head + "resolution 1 1 1\n").find("grid.txt:3"), std::string::npos);
}

}  // namespace lambert
