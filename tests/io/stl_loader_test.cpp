// The STL reader: ASCII and binary forms of one mesh, content detection, surfaces, and the
// refusals (truncated binary, wrong facet count, non-finite numbers, bad keywords).
#include "io/stl_loader.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "common/temp_dir.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

using Tri = std::array<Eigen::Vector3f, 3>;

// A unit tetrahedron's four faces, wound counter-clockwise seen from outside.
std::vector<Tri> tetrahedron() {
  const Eigen::Vector3f o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  return {{o, y, x}, {o, x, z}, {o, z, y}, {x, y, z}};
}

std::string ascii(const std::vector<std::pair<std::string, std::vector<Tri>>>& solids) {
  std::string s;
  for (const auto& [name, tris] : solids) {
    s += "solid " + name + "\n";
    for (const auto& t : tris) {
      const Eigen::Vector3f n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
      s += "  facet normal " + std::to_string(n.x()) + " " + std::to_string(n.y()) + " " +
           std::to_string(n.z()) + "\n    outer loop\n";
      for (const auto& p : t)
        s += "      vertex " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " +
             std::to_string(p.z()) + "\n";
      s += "    endloop\n  endfacet\n";
    }
    s += "endsolid " + name + "\n";
  }
  return s;
}

void put_f32(std::string& s, float f) {
  char b[4];
  std::memcpy(b, &f, 4);  // the tests run on little-endian hosts, as STL is
  s.append(b, 4);
}

std::string binary(const std::vector<Tri>& tris, const std::string& header = "lambert test",
                   std::uint32_t count = 0xffffffff) {
  std::string s = header;
  s.resize(80, ' ');
  const std::uint32_t n = count == 0xffffffff ? static_cast<std::uint32_t>(tris.size()) : count;
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : tris) {
    const Eigen::Vector3f nrm = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    for (int k = 0; k < 3; ++k) put_f32(s, nrm[k]);
    for (const auto& p : t)
      for (int k = 0; k < 3; ++k) put_f32(s, p[k]);
    s.append(2, '\0');
  }
  return s;
}

std::string stl_error(const std::string& bytes, const std::string& name = "t.stl") {
  try {
    load_stl_bytes(bytes, name);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

TEST(StlLoader, AsciiAndBinaryGiveTheSameScene) {
  const Scene a = load_stl_bytes(ascii({{"", tetrahedron()}}), "tet.stl");
  const Scene b = load_stl_bytes(binary(tetrahedron()), "tet.stl");
  ASSERT_EQ(a.faces.size(), 4u);
  ASSERT_EQ(a.faces.size(), b.faces.size());
  ASSERT_EQ(a.vertices.size(), 4u);  // shared by exact position
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t v = 0; v < a.vertices.size(); ++v) EXPECT_EQ(a.vertices[v], b.vertices[v]);
  for (size_t f = 0; f < a.faces.size(); ++f) EXPECT_EQ(a.faces[f].vertices, b.faces[f].vertices);
  ASSERT_EQ(a.surfaces.size(), 1u);
  EXPECT_EQ(a.surfaces[0].name, "tet");
  EXPECT_EQ(b.surfaces[0].name, "tet");
  EXPECT_DOUBLE_EQ(a.total_area(), b.total_area());
}

TEST(StlLoader, BinaryWhoseHeaderStartsWithSolidIsBinary) {
  const std::string bytes = binary(tetrahedron(), "solid exported by CAD");
  EXPECT_EQ(stl_kind(bytes), StlKind::Binary);
  EXPECT_EQ(load_stl_bytes(bytes, "cad.stl").faces.size(), 4u);
}

TEST(StlLoader, EachAsciiSolidIsASurface) {
  std::vector<Tri> shifted = tetrahedron();
  for (auto& t : shifted)
    for (auto& p : t) p += Eigen::Vector3f(5, 0, 0);
  const Scene s =
      load_stl_bytes(ascii({{"inner wall", tetrahedron()}, {"outer", shifted}}), "x.stl");
  ASSERT_EQ(s.surfaces.size(), 2u);
  EXPECT_EQ(s.surfaces[0].name, "inner wall");
  EXPECT_EQ(s.surfaces[1].name, "outer");
  EXPECT_EQ(s.faces[4].surface, 1);
  EXPECT_EQ(s.materials.at(s.surfaces[0].material).name, "default");
}

TEST(StlLoader, BinaryIsSplitIntoConnectedComponents) {
  std::vector<Tri> tris = tetrahedron();
  for (auto t : tetrahedron()) {
    for (auto& p : t) p += Eigen::Vector3f(5, 0, 0);
    tris.push_back(t);
  }
  const Scene s = load_stl_bytes(binary(tris), "two.stl");
  ASSERT_EQ(s.surfaces.size(), 2u);
  EXPECT_EQ(s.surfaces[0].name, "two_1");
  EXPECT_EQ(s.surfaces[1].name, "two_2");
  EXPECT_EQ(s.faces[0].surface, 0);
  EXPECT_EQ(s.faces[7].surface, 1);
}

TEST(StlLoader, FlippedStoredNormalWarnsOnceAndKeepsTheWinding) {
  std::string text = ascii({{"a", tetrahedron()}});
  // The first facet (o, y, x) is wound about -z: store +z instead.
  const auto at = text.find("facet normal ");
  text.replace(at, text.find('\n', at) - at, "facet normal 0 0 1");
  LoadReport report;
  const Scene s = load_stl_bytes(text, "f.stl", &report);
  EXPECT_EQ(s.faces.size(), 4u);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("1 facet(s) store a normal opposite"), std::string::npos);
}

TEST(StlLoader, ZeroAreaFacetsAreDroppedAndCounted) {
  std::vector<Tri> tris = tetrahedron();
  tris.push_back({Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 1, 1), Eigen::Vector3f(2, 2, 2)});
  LoadReport report;
  const Scene s = load_stl_bytes(binary(tris), "d.stl", &report);
  EXPECT_EQ(s.faces.size(), 4u);
  EXPECT_EQ(report.degenerate_faces_dropped, 1);
}

TEST(StlLoader, TruncatedBinaryNamesTheFacet) {
  std::string bytes = binary(tetrahedron());
  bytes.resize(bytes.size() - 20);  // facet 4 incomplete
  const std::string e = stl_error(bytes);
  EXPECT_NE(e.find("t.stl: facet 4: binary STL truncated"), std::string::npos) << e;
}

TEST(StlLoader, WrongFacetCountIsRefused) {
  const std::string e = stl_error(binary(tetrahedron(), "x", 3));  // 4 stored, 3 declared
  EXPECT_NE(e.find("t.stl: binary STL facet count 3 does not match the size"), std::string::npos)
      << e;
  const std::string shorter = stl_error(binary(tetrahedron(), "x", 9));
  EXPECT_NE(shorter.find("truncated"), std::string::npos) << shorter;
}

TEST(StlLoader, NonFiniteNumbersAreRefused) {
  std::string bytes = binary(tetrahedron());
  // Facet 3's second vertex, y: header 84 + 2 facets of 50 + normal 12 + vertex 12 + x 4.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&bytes[84 + 2 * 50 + 12 + 12 + 4], &nan, 4);
  const std::string e = stl_error(bytes);
  EXPECT_NE(e.find("t.stl: facet 3: vertex 2 has a non-finite coordinate"), std::string::npos) << e;
  std::string text = ascii({{"a", tetrahedron()}});
  const auto at = text.find("vertex ") + 7;
  text.replace(at, text.find(' ', at) - at, "inf");
  const std::string ea = stl_error(text);
  EXPECT_NE(ea.find("t.stl:4: 'inf'"), std::string::npos) << ea;
}

TEST(StlLoader, CoordinatesBeyondTheObjLimitAreRefused) {
  // Issue 33, item 8: OBJ refuses |x| > 1e50 (distances^4 overflow); ASCII STL took them.
  std::string text = ascii({{"a", tetrahedron()}});
  const auto at = text.find("vertex ") + 7;
  text.replace(at, text.find(' ', at) - at, "-2e50");
  const std::string e = stl_error(text);
  EXPECT_NE(e.find("t.stl:4: '-2e50': coordinate beyond +-1e50"), std::string::npos) << e;
  // And a scene below 1e-50 across, where form factors underflow.
  const std::string tiny = stl_error(
      "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1e-60 0 0\n"
      "vertex 0 1e-60 0\nendloop\nendfacet\nendsolid\n");
  EXPECT_NE(tiny.find("t.stl: scene extent below 1e-50"), std::string::npos) << tiny;
}

TEST(StlLoader, CoincidentFacetsAreWarnedOncePerPairOfSurfaces) {
  // Issue 33, item 8: OBJ warned of faces with the same corners (their area counts twice);
  // STL did not. Two solids holding the same tetrahedron: four coincident faces, one warning.
  LoadReport report;
  const Scene s =
      load_stl_bytes(ascii({{"a", tetrahedron()}, {"b", tetrahedron()}}), "t.stl", &report);
  EXPECT_EQ(s.faces.size(), 8u);
  EXPECT_EQ(report.coincident_faces, 4);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("surfaces 'a' and 'b', 4 coincident face(s)"),
            std::string::npos)
      << report.warnings[0];
  // Binary facets have no line: the warning names no line 0.
  std::vector<Tri> twice = tetrahedron();
  twice.push_back(twice[0]);
  LoadReport binary_report;
  load_stl_bytes(binary(twice), "t.stl", &binary_report);
  EXPECT_EQ(binary_report.coincident_faces, 1);
  ASSERT_EQ(binary_report.warnings.size(), 1u);
  EXPECT_EQ(binary_report.warnings[0].find("line 0"), std::string::npos);
}

TEST(StlLoader, BadKeywordNamesTheLine) {
  std::string text = ascii({{"a", tetrahedron()}});
  text.replace(text.find("endloop"), 7, "endlop");
  const std::string e = stl_error(text);
  EXPECT_NE(e.find("t.stl:7: expected 'endloop', got 'endlop'"), std::string::npos) << e;
  const std::string cut = stl_error("solid a\n  facet normal 0 0 1\n    outer loop\n");
  EXPECT_NE(cut.find("end of file inside a solid"), std::string::npos) << cut;
  const std::string four = stl_error(
      "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "vertex 1 1 0\nendloop\nendfacet\nendsolid\n");
  EXPECT_NE(four.find("t.stl:7: a facet has 3 vertices"), std::string::npos) << four;
}

TEST(StlLoader, EmptySolidIsAnEmptyScene) {
  const std::string e = stl_error("solid nothing\nendsolid nothing\n");
  EXPECT_NE(e.find("empty scene"), std::string::npos) << e;
}

TEST(StlLoader, SceneFilesAreToldApartByContent) {
  const testing::TempDir dir;
  std::string bytes = binary(tetrahedron());
  const std::string path = dir.file("mesh.obj");  // STL content under an OBJ name
  std::ofstream(path, std::ios::binary) << bytes;
  EXPECT_EQ(load_scene_path(path).faces.size(), 4u);
  const std::string obj = dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(load_scene_path(obj).faces.size(), 1u);
  // A truncated binary without a "solid" header is still reported as a binary STL.
  bytes.resize(100);
  const std::string broken = dir.file("broken.stl");
  std::ofstream(broken, std::ios::binary) << bytes;
  try {
    load_scene_path(broken);
    FAIL() << "accepted a truncated binary STL";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("binary STL truncated"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lambert
