#include "io/radiosity_csv.hpp"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace lambert {
namespace {

// Two patches of areas 1 and 0.5: all a CSV is checked against.
PatchMesh two_patches() {
  PatchMesh mesh;
  mesh.patches.resize(2);
  mesh.patches[0].area = 1.0;
  mesh.patches[1].area = 0.5;
  return mesh;
}

std::string csv_refusal(const std::string& text) {
  std::istringstream in(text);
  try {
    read_radiosity_csv_stream(in, "B.csv", two_patches());
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(accepted)";
}

const std::string kHeader = "patch,surface,area,R,G,B\n";

}  // namespace

TEST(RadiosityCsv, WhatSolveWritesReadsBack) {
  std::istringstream in(kHeader + "1,\"wall, left\",0.5,1,2,3\r\n0,floor,1,4,5,6\n\n# end\n");
  const Eigen::MatrixX3d B = read_radiosity_csv_stream(in, "B.csv", two_patches());
  EXPECT_EQ(B(0, 0), 4);
  EXPECT_EQ(B(1, 2), 3);
}

TEST(RadiosityCsv, MalformedFilesAreRefusedNamingFileAndLine) {
  const std::string row0 = "0,floor,1,4,5,6\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {kHeader + row0 + "1,wall,0.5,1,2,3,7\n", "B.csv:3: expected 6 columns, found 7"},
      {kHeader + row0 + "1,wall,0.5,1,2\n", "B.csv:3: expected 6 columns, found 5"},
      {kHeader + row0 + "1,wall,0.5,1,2,3x\n", "B.csv:3: '3x' (column B): not a number"},
      {kHeader + row0 + "1,wall,0.5,0x1p3,2,3\n", "B.csv:3: '0x1p3' (column R): not a number"},
      {kHeader + row0 + "1,wall,0.5,inf,2,3\n", "B.csv:3: 'inf' (column R)"},
      {kHeader + row0 + "1.5,wall,0.5,1,2,3\n", "B.csv:3: patch '1.5' is not a patch index"},
      {kHeader + row0 + "0,wall,1,1,2,3\n", "B.csv:3: patch 0 repeated (first on line 2)"},
      {kHeader + row0 + "2,wall,0.5,1,2,3\n", "B.csv:3: patch 2 does not exist"},
      {kHeader + row0 + "1,wall,0.6,1,2,3\n", "B.csv:3: patch 1 has area 0.6"},
      {kHeader + row0 + "1,wall,0.5,-1,2,3\n", "B.csv:3: negative radiosity"},
      {kHeader + row0 + "1,\"wall,0.5,1,2,3\n", "B.csv:3: unterminated quote"},
      {kHeader + row0 + "1,\"wall\"x,0.5,1,2,3\n", "B.csv:3: text after a closing quote"},
      {kHeader + row0, "B.csv: 1 patches but the meshed scene has 2"},
      {"patch,area,R,G,B,r\n", "B.csv:1: column 'r' appears twice"},
      {"patch,area,R,G\n", "B.csv:1: header has no 'b' column"},
      {"", "B.csv: empty radiosity CSV"},
      {kHeader + row0 + std::string("1,wall,0.5,1,2,3\0\n", 18), "B.csv:3: NUL byte"},
      {kHeader + row0 + std::string(std::size_t{1} << 21, '1'), "B.csv:3: line longer than 1 MiB"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string message = csv_refusal(text);
    EXPECT_EQ(message.rfind(expected, 0), 0u) << text.substr(0, 80) << "-> " << message;
  }
}

}  // namespace lambert
