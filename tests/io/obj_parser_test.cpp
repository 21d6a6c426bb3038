// OBJ/MTL parsing of hostile and unusual input (issue 10): line endings, line length,
// numbers, indices and corner counts, from memory.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "geometry/polygon.hpp"
#include "io/line_reader.hpp"
#include "io/obj_loader.hpp"

namespace lambert {
namespace {

// Loads OBJ text (and MTL text served for any mtllib) from memory.
Scene load_text(const std::string& obj, LoadReport* report = nullptr,
                const std::string& mtl = "newmtl white\nKd 0.5 0.5 0.5\n") {
  std::istringstream in(obj);
  const MtlOpener open = [&](const std::string&) {
    return MtlFile{std::make_unique<std::istringstream>(mtl), "m.mtl"};
  };
  return load_obj_stream(in, "t.obj", open, report);
}

std::string error_of(const std::string& obj, const std::string& mtl = "newmtl white\nKd 0.5 0.5 0.5\n") {
  try {
    load_text(obj, nullptr, mtl);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// A regular n-gon of circumradius 1 in the z = 0 plane as one face.
std::string ngon(int n) {
  std::ostringstream s;
  s.precision(17);
  s << "mtllib m.mtl\nusemtl white\n";
  for (int k = 0; k < n; ++k)
    s << "v " << std::cos(2 * M_PI * k / n) << " " << std::sin(2 * M_PI * k / n) << " 0\n";
  s << "f";
  for (int k = 1; k <= n; ++k) s << " " << k;
  s << "\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf -3 -2 -1\n";  // a triangle after it, by relative index
  return s.str();
}

double face_area(const Scene& s, size_t f) {
  std::vector<Eigen::Vector3d> poly;
  for (auto v : s.faces[f].vertices) poly.push_back(s.vertices[v]);
  return polygon_area(poly);
}

}  // namespace

TEST(ObjParser, PolygonsOfAnyCornerCountKeepEveryCornerAndTheirArea) {
  for (int n : {255, 256, 300, 100000}) {
    const Scene s = load_text(ngon(n));
    ASSERT_EQ(s.faces.size(), 2u) << n;
    EXPECT_EQ(s.faces[0].vertices.size(), static_cast<size_t>(n)) << n;
    // Area n/2 sin(2 pi/n) <= pi. The corners are printed to 17 digits (exact round trip);
    // each of the n - 2 fan cross products is ~2 pi/n and rounded to 1e-16 of itself, so
    // the sum errs by at most ~n * 1e-16 * 2 pi / n = 6e-16 (worst case, no cancellation of
    // errors): a tolerance of 1e-12 pi is 5000 times that. (The corner count is checked
    // exactly above; the area catches corners taken from the wrong vertices.)
    EXPECT_NEAR(face_area(s, 0), 0.5 * n * std::sin(2 * M_PI / n), 1e-12 * M_PI) << n;
    // The face after the polygon is built from its own vertices.
    EXPECT_EQ(s.faces[1].vertices, (std::vector<std::int32_t>{n, n + 1, n + 2})) << n;
    EXPECT_DOUBLE_EQ(face_area(s, 1), 0.5) << n;
  }
}

TEST(ObjParser, LoneCarriageReturnEndsALineSoTheIndexIsCheckedNotUsed) {
  EXPECT_EQ(error_of("v 0 0 0 \rf 1 9000 2"), "t.obj:2: face index 9000 out of range (1 vertices defined so far)");
  EXPECT_EQ(error_of("v 0 0 0\r\nv 1 0 0\rv 0 1 0\nf 1 2 4\r"), "t.obj:4: face index 4 out of range (3 vertices defined so far)");
}

TEST(ObjParser, FormFeedAndVerticalTabAreWhitespaceEverywhere) {
  const Scene s = load_text("mtllib m.mtl\nusemtl white\nv\f0 0 0\nv\v1 0 0\nv 0\f1\v0\nf\v1 2\f3\n");
  EXPECT_DOUBLE_EQ(face_area(s, 0), 0.5);
}

TEST(ObjParser, IndexFormsAndRelativeIndicesAreResolvedAndChecked) {
  const std::string v = "mtllib m.mtl\nusemtl white\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
  EXPECT_EQ(load_text(v + "f 1/1 2/1/1 3//1\n").faces[0].vertices, (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_EQ(load_text(v + "f -3 -2/-1 -1//-1\n").faces[0].vertices, (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_EQ(error_of(v + "f 1/2 2 3\n"), "t.obj:8: face texture-coordinate index 2 out of range (1 defined so far)");
  EXPECT_EQ(error_of(v + "f 1//2 2 3\n"), "t.obj:8: face normal index 2 out of range (1 defined so far)");
  EXPECT_EQ(error_of(v + "f 0 1 2\n"), "t.obj:8: face index 0 out of range (3 vertices defined so far)");
  EXPECT_EQ(error_of(v + "f -4 1 2\n"), "t.obj:8: face index -4 out of range (3 vertices defined so far)");
  EXPECT_EQ(error_of(v + "f -9223372036854775808 1 2\n"),
            "t.obj:8: face index -9223372036854775808 out of range (3 vertices defined so far)");
  EXPECT_EQ(error_of(v + "f 99999999999999999999 1 2\n"),
            "t.obj:8: malformed face index '99999999999999999999': '99999999999999999999' is out of range");
  EXPECT_EQ(error_of(v + "f 1x 2 3\n"), "t.obj:8: malformed face index '1x': '1x' is not an integer");
  EXPECT_EQ(error_of(v + "f 1/1/1/1 2 3\n"), "t.obj:8: malformed face index '1/1/1/1'");
  EXPECT_EQ(error_of(v + "f 1 2\n"), "t.obj:8: face has 2 vertices, needs at least 3");
}

TEST(ObjParser, NumbersAreReadByOneStrictRoutine) {
  EXPECT_EQ(error_of("v 0 0 1e400\n"), "t.obj:1: malformed vertex: '1e400' is out of the range of a double");
  EXPECT_EQ(error_of("v 0 0 1e-400\n"), "t.obj:1: malformed vertex: '1e-400' is out of the range of a double");
  EXPECT_EQ(error_of("v 0 inf 0\n"), "t.obj:1: vertex coordinate 'inf' is not finite");
  EXPECT_EQ(error_of("v 0 -nan 0\n"), "t.obj:1: vertex coordinate '-nan' is not finite");
  EXPECT_EQ(error_of("v 0 1e 0\n"), "t.obj:1: malformed vertex: '1e' is not a number");
  EXPECT_EQ(error_of("v 0 0\n"), "t.obj:1: malformed vertex: expected 3 coordinates (then a weight or r g b), got 2 numbers");
  // 400 digits then e-100: 1.0 to the last digit (strtod and from_chars agree).
  const std::string longnum = "1" + std::string(399, '0') + "e-399";
  const Scene s = load_text("mtllib m.mtl\nusemtl white\nv 0 0 0\nv " + longnum + " 0 0\nv 0 +1 0\nf 1 2 3\n");
  EXPECT_EQ(s.vertices[1].x(), 1.0);
  EXPECT_EQ(s.vertices[2].y(), 1.0);
  EXPECT_EQ(error_of("mtllib m.mtl\n", "newmtl a\nKd 0.5 0.5 0x1p-1\n"), "m.mtl:2: malformed Kd: '0x1p-1' is not a number");
  EXPECT_EQ(error_of("mtllib m.mtl\n", "newmtl a\nKe 1 nan 1\n"), "m.mtl:2: material 'a': Ke value 'nan' must be finite");
}

TEST(ObjParser, LinesAreBoundedAndBinaryInputIsRefused) {
  EXPECT_EQ(error_of("v 0 0 0\n# " + std::string(kMaxLineBytes, 'x') + "\n"),
            "t.obj:2: line longer than 1 MiB (not a text file?)");
  EXPECT_EQ(error_of(std::string("v 0 0 0\nv 1\0 0 0\n", 16)),
            "t.obj:2: NUL byte: a binary or UTF-16 file (convert to UTF-8 text)");
  EXPECT_EQ(error_of("mtllib m.mtl\n", std::string(kMaxLineBytes + 1, 'K')), "m.mtl:1: line longer than 1 MiB (not a text file?)");
}

TEST(ObjParser, DevZeroIsRefusedWithoutReadingItIntoMemory) {
  try {
    load_obj("/dev/zero");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()), "/dev/zero:1: NUL byte: a binary or UTF-16 file (convert to UTF-8 text)");
  }
}

TEST(ObjParser, HugeButAcceptedCoordinatesGiveFiniteAreas) {
  // 1e50 is the largest accepted magnitude: areas 1e100 are finite and exact in ratio.
  const Scene s = load_text("mtllib m.mtl\nusemtl white\nv 0 0 0\nv 1e50 0 0\nv 0 1e50 0\nf 1 2 3\n");
  EXPECT_DOUBLE_EQ(s.total_area(), 0.5e100);
}

TEST(ObjParser, NonPlanarPolygonsTooLargeToSplitAreRefused) {
  std::ostringstream o;
  o << "mtllib m.mtl\nusemtl white\n";
  for (int k = 0; k < 2000; ++k)
    o << "v " << std::cos(2 * M_PI * k / 2000) << " " << std::sin(2 * M_PI * k / 2000) << " " << (k % 2) * 0.1 << "\n";
  o << "f";
  for (int k = 1; k <= 2000; ++k) o << " " << k;
  o << "\n";
  EXPECT_EQ(error_of(o.str()), "t.obj:2003: non-planar polygon with 2000 corners (more than 1000 cannot be split into triangles)");
}

}  // namespace lambert
