// The PLY reader (io/ply_loader.hpp): ASCII, binary little- and big-endian read to the same
// scene; the Stanford bunny; every malformed input refused with its place, before any large
// allocation.
#include "io/ply_loader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/polygon.hpp"
#include "io/stl_loader.hpp"

namespace lambert {
namespace {

// A unit square (y = 0, facing +y) and a triangle above it (facing -z).
const std::vector<Eigen::Vector3d> kVertices = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1},
                                                {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
const std::vector<std::vector<int>> kFaces = {{0, 1, 2, 3}, {0, 4, 5}};

std::string ascii_ply() {
  std::string s =
      "ply\nformat ascii 1.0\ncomment test\nelement vertex 6\nproperty float x\nproperty float "
      "y\nproperty float z\nproperty float confidence\nelement face 2\nproperty list uchar int "
      "vertex_indices\nend_header\n";
  for (const auto& v : kVertices)
    s += std::to_string(v.x()) + " " + std::to_string(v.y()) + " " + std::to_string(v.z()) +
         " 0.5\n";
  for (const auto& f : kFaces) {
    s += std::to_string(f.size());
    for (int i : f) s += " " + std::to_string(i);
    s += "\n";
  }
  return s;
}

template <typename T>
void put(std::string& out, T value, bool big) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if (big)
    for (size_t k = 0; k < sizeof(T) / 2; ++k) std::swap(b[k], b[sizeof(T) - 1 - k]);
  out.append(b, sizeof(T));
}

std::string binary_ply(bool big) {
  std::string s = std::string("ply\nformat ") +
                  (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex 6\nproperty double x\nproperty double y\nproperty double "
                  "z\nproperty uchar red\nelement face 2\nproperty list ushort uint "
                  "vertex_indices\nelement edge 1\nproperty int a\nproperty int b\nend_header\n";
  for (const auto& v : kVertices) {
    for (int c = 0; c < 3; ++c) put<double>(s, v[c], big);
    put<std::uint8_t>(s, 200, big);
  }
  for (const auto& f : kFaces) {
    put<std::uint16_t>(s, static_cast<std::uint16_t>(f.size()), big);
    for (int i : f) put<std::uint32_t>(s, static_cast<std::uint32_t>(i), big);
  }
  put<std::int32_t>(s, 0, big);
  put<std::int32_t>(s, 1, big);
  return s;
}

double area(const Scene& s) {
  double a = 0;
  for (const Face& f : s.faces) {
    std::vector<Eigen::Vector3d> p;
    for (auto v : f.vertices) p.push_back(s.vertices[v]);
    a += polygon_area(p);
  }
  return a;
}

void expect_refused(const std::string& bytes, const std::string& what) {
  try {
    load_ply_bytes(bytes, "bad.ply");
    ADD_FAILURE() << "accepted; expected: " << what;
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("bad.ply: ", 0), 0u) << e.what();
  }
}

}  // namespace

TEST(PlyLoader, AsciiAndBothBinaryEncodingsGiveTheSameScene) {
  const Scene a = load_ply_bytes(ascii_ply(), "two.ply");
  for (bool big : {false, true}) {
    const Scene b = load_ply_bytes(binary_ply(big), "two.ply");
    ASSERT_EQ(b.vertices.size(), a.vertices.size());
    for (size_t k = 0; k < a.vertices.size(); ++k) EXPECT_EQ(b.vertices[k], a.vertices[k]);
    ASSERT_EQ(b.faces.size(), a.faces.size());
    for (size_t k = 0; k < a.faces.size(); ++k) EXPECT_EQ(b.faces[k].vertices, a.faces[k].vertices);
  }
  // The square (1) and the triangle (1/2), one connected component: one surface.
  EXPECT_NEAR(area(a), 1.5, 1e-15);
  ASSERT_EQ(a.surfaces.size(), 1u);
  EXPECT_EQ(a.surfaces[0].name, "two");
  // Wound counter-clockwise about the front: the square faces +y.
  std::vector<Eigen::Vector3d> sq;
  for (auto v : a.faces[0].vertices) sq.push_back(a.vertices[v]);
  EXPECT_GT(newell_normal(sq).y(), 0.0);
}

TEST(PlyLoader, TheStanfordBunnyLoadsWithItsArea) {
  // data/bunny/bun_zipper_res4.ply: 453 vertices (452 used), 946 triangles (2 removed as "comment"
  // lines in the body, read past), one surface; its area, the sum of the triangles' half cross
  // products in double from the file's decimal text (ASCII values are read as written, not
  // rounded to the declared float32; computed independently in Python), is 0.0545575302 m²: 1e-12
  // covers the order of summation (1e-16 × 946 terms).
  LoadReport report;
  const Scene s =
      load_scene_path(std::string(LAMBERT_TEST_DATA_DIR) + "/bunny/bun_zipper_res4.ply", &report);
  EXPECT_EQ(s.vertices.size(), 452u);  // the 453 less one no face uses
  EXPECT_EQ(s.faces.size() + static_cast<size_t>(report.degenerate_faces_dropped), 946u);
  EXPECT_NEAR(area(s), 0.05455753019761333, 1e-12);
  EXPECT_EQ(s.surfaces.size(), 1u);
}

TEST(PlyLoader, VertexColoursBecomeReflectanceOnlyWhenAsked) {
  std::string ply = binary_ply(false);
  LoadOptions o;
  EXPECT_FALSE(load_ply_bytes(ply, "c.ply", nullptr, o).faces[0].rho.has_value());
  o.vertex_colors_as_reflectance = true;
  // Only red is given: no colour (red, green and blue are needed).
  EXPECT_FALSE(load_ply_bytes(ply, "c.ply", nullptr, o).faces[0].rho.has_value());
  const std::string rgb =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty "
      "float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face "
      "1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 255 0 51\n1 0 0 255 0 51\n0 "
      "1 0 0 0 51\n3 0 1 2\n";
  const Scene s = load_ply_bytes(rgb, "c.ply", nullptr, o);
  ASSERT_TRUE(s.faces[0].rho.has_value());
  EXPECT_NEAR(s.faces[0].rho->x(), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(s.faces[0].rho->y(), 0.0, 0.0);
  EXPECT_NEAR(s.faces[0].rho->z(), 0.2, 1e-15);
}

TEST(PlyLoader, MalformedFilesAreRefusedWithTheirPlace) {
  const std::string good = ascii_ply();
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  expect_refused("ply\nformat ascii 1.0\nelement vertex 1\n", "'end_header'");
  expect_refused(replaced("format ascii 1.0", "format ascii 2.0"), "line 2: expected 'format");
  expect_refused(replaced("format ascii 1.0", "format binary_middle_endian 1.0"), "unknown format");
  expect_refused(replaced("property float z", "property quad z"), "unknown property type 'quad'");
  expect_refused(replaced("comment test", "colour blue"), "unknown header keyword 'colour'");
  expect_refused(replaced("property float z\n", ""), "no x, y and z");
  expect_refused(replaced("vertex_indices", "corners"), "no list property vertex_indices");
  expect_refused(replaced("3 0 4 5", "3 0 4 9"), "face 2: vertex index 9 out of range");
  expect_refused(replaced("3 0 4 5", "2 0 4"), "face 2: a face needs 3 corners");
  expect_refused(replaced("3 0 4 5", "3 0 4 x"), "face 2: not an integer");
  expect_refused(replaced("3 0 4 5", "3 0 4 5 7"), "text after the last element");
  expect_refused(good.substr(0, good.size() - 4), "face 2: the file ends inside it");
  expect_refused(replaced("element face 2", "element face 0"), "text after the last element");
  expect_refused("ply\nelement vertex 0\nend_header\n", "the header has no 'format' line");
  // A count the file cannot hold is refused before anything is allocated for it.
  expect_refused(replaced("element vertex 6", "element vertex 4000000000"),
                 "4000000000 vertex elements cannot fit");
  std::string bin = binary_ply(false);
  expect_refused(bin.substr(0, bin.size() - 3), "the file ends inside it (truncated)");
  expect_refused(bin + "xyz", "3 bytes after the last element");
  std::string nan = binary_ply(false);
  const size_t body = nan.find("end_header\n") + 11;
  const double inf = INFINITY;
  std::memcpy(&nan[body], &inf, sizeof inf);
  expect_refused(nan, "vertex 1: a coordinate is not finite");
  // Points alone (a scan before reconstruction) cannot be meshed into patches.
  expect_refused(
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty "
      "float z\nend_header\n0 0 0\n",
      "no faces: a point cloud");
}

TEST(PlyLoader, ACommandsSceneIsToldApartByContent) {
  EXPECT_TRUE(looks_like_ply("ply\nformat ascii 1.0\n"));
  EXPECT_TRUE(looks_like_ply("ply\r\nformat ascii 1.0\r\n"));
  EXPECT_FALSE(looks_like_ply("plyx\n"));
  EXPECT_FALSE(looks_like_ply("solid ply\n"));
}

}  // namespace lambert
