#include "io/obj_loader.hpp"

#include <gtest/gtest.h>

#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

const char* kMtl =
    "newmtl white\nKd 0.5 0.5 0.5\nKe 0 0 0\n"
    "newmtl lamp\nKd 0.2 0.2 0.2\nKe 1 2 3\n";

// A unit square floor (+y up) and a lamp triangle facing down.
const char* kObj =
    "mtllib s.mtl\n"
    "g floor\nusemtl white\n"
    "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nf 1 2 3 4\n"
    "g lamp\nusemtl lamp\n"
    "v 0 1 0\nv 1 1 0\nv 0 1 1\nf 5 6 7\n";

// Writes the MTL and an OBJ into a temp dir and returns the load error message.
std::string load_error(const testing::TempDir& dir, const std::string& obj,
                       const std::string& mtl = kMtl, const LoadOptions& options = {}) {
  dir.write("s.mtl", mtl);
  const std::string path = dir.write("s.obj", obj);
  try {
    load_obj(path, nullptr, options);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ObjLoader, LoadsSurfacesMaterialsAndWinding) {
  testing::TempDir dir;
  dir.write("s.mtl", kMtl);
  LoadReport report;
  const Scene s = load_obj(dir.write("s.obj", kObj), &report);
  ASSERT_EQ(s.surfaces.size(), 2u);
  EXPECT_EQ(s.surfaces[0].name, "floor");
  EXPECT_EQ(s.surfaces[1].name, "lamp");
  EXPECT_EQ(s.material_of(1).emission, Eigen::Vector3d(1, 2, 3));
  EXPECT_DOUBLE_EQ(s.total_area(), 1.5);
  EXPECT_TRUE(report.has_emitter);
  const PatchMesh m = mesh_scene(s, {});
  EXPECT_GT(m.patches[0].normal.y(), 0.99);  // floor wound counter-clockwise seen from +y
  EXPECT_LT(m.patches[1].normal.y(), -0.99);
}

TEST(ObjLoader, CornellBoxHasFourMaterialsOneEmitterAndItsArea) {
  LoadReport report;
  const Scene s = load_obj(std::string(LAMBERT_TEST_DATA_DIR) + "/cornell_box/cornell_box.obj", &report);
  EXPECT_EQ(s.materials.size(), 4u);
  int emitters = 0;
  for (size_t k = 0; k < s.surfaces.size(); ++k) emitters += s.material_of(k).emits();
  EXPECT_EQ(emitters, 1);
  EXPECT_EQ(s.surfaces.size(), 8u);
  EXPECT_EQ(report.nonplanar_faces_split, 0);
  EXPECT_TRUE(s.camera.defined);
  EXPECT_NEAR(s.camera.vfov_degrees, 39.3077, 1e-4);
  // Areas of the axis-aligned surfaces in closed form from the published coordinates:
  // floor trapezoid 0.5 (552.8 + 549.6) 559.2 = 308,231.04 mm^2; light 130 x 105 = 13,650;
  // ceiling 556 x 559.2 - 13,650 = 297,265.2 (the light is cut out of it). Tolerance 1e-6
  // mm^2 is ~1e4 double-precision ulps of these sums.
  double floor = 0, light = 0, ceiling = 0;
  std::vector<Eigen::Vector3d> poly;
  for (const auto& f : s.faces) {
    poly.clear();
    for (auto v : f.vertices) poly.push_back(s.vertices[v]);
    const double a = polygon_area(poly);
    const std::string& name = s.surfaces[f.surface].name;
    if (name == "floor") floor += a;
    if (name == "light") light += a;
    if (name == "ceiling") ceiling += a;
  }
  EXPECT_NEAR(floor, 308231.04, 1e-6);
  EXPECT_NEAR(light, 13650.0, 1e-6);
  EXPECT_NEAR(ceiling, 297265.2, 1e-6);
}

TEST(ObjLoader, MissingFileIsAnIoErrorNamingIt) {
  try {
    load_obj("/nonexistent/scene.obj");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.obj"), std::string::npos);
  }
}

TEST(ObjLoader, MalformedLinesNameFileAndLine) {
  testing::TempDir dir;
  EXPECT_NE(load_error(dir, "mtllib s.mtl\nusemtl white\nv 0 0\n").find("s.obj:3: malformed vertex"),
            std::string::npos);
  EXPECT_NE(load_error(dir, "mtllib s.mtl\nusemtl white\nv 0 0 0\nf 1 2 9\n").find("s.obj:4: face index 2 out of range"),
            std::string::npos);
  EXPECT_NE(load_error(dir, "bogus 1 2\n").find("s.obj:1: malformed OBJ"), std::string::npos);
  EXPECT_NE(load_error(dir, "v 0 0 0\nv 1 0 0\nf 1 2\n").find("s.obj:3: face has 2 vertices"),
            std::string::npos);
}

TEST(ObjLoader, NonFiniteCoordinateIsRejected) {
  testing::TempDir dir;
  EXPECT_NE(load_error(dir, "v 0 nan 0\n").find("s.obj:1: vertex coordinate 'nan' is not finite"),
            std::string::npos);
  EXPECT_NE(load_error(dir, "v 0 0 inf\n").find("not finite"), std::string::npos);
}

// Issue 20 made these defaults with warnings; --strict keeps the refusals.
TEST(ObjLoader, MissingMtlAndUndefinedMaterialAreErrorsWhenStrict) {
  testing::TempDir dir;
  LoadOptions strict;
  strict.strict = true;
  const std::string obj = std::string(kObj);
  std::string missing = obj;
  missing.replace(0, 12, "mtllib x.mtl");
  EXPECT_NE(load_error(dir, missing, kMtl, strict).find("s.obj:1: material library 'x.mtl' not found"),
            std::string::npos);
  std::string undefined = obj;
  undefined.replace(undefined.find("usemtl lamp"), 11, "usemtl glow");
  EXPECT_NE(load_error(dir, undefined, kMtl, strict).find("s.obj:10: material 'glow' is not defined"),
            std::string::npos);
  EXPECT_NE(load_error(dir, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", kMtl, strict).find("s.obj:4: face has no material"),
            std::string::npos);
}

// Issue 20: Kd = 1 is accepted with a warning; --strict refuses it as before, and Kd > 1 is
// always refused.
TEST(ObjLoader, ReflectanceOutsideUnitIntervalIsRejectedWithItsLine) {
  testing::TempDir dir;
  LoadOptions strict;
  strict.strict = true;
  const std::string bad_kd = "newmtl white\nKd 0.5 1.0 0.5\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n";
  const std::string err = load_error(dir, kObj, bad_kd, strict);
  EXPECT_NE(err.find("s.mtl:2: material 'white'"), std::string::npos) << err;
  EXPECT_NE(err.find("singular"), std::string::npos) << err;
  EXPECT_EQ(load_error(dir, kObj, bad_kd), "");
  const std::string above = "newmtl white\nKd 0.5 1.2 0.5\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n";
  EXPECT_NE(load_error(dir, kObj, above).find("s.mtl:2: material 'white': reflectance Kd 0.5 1.2 0.5 must lie in [0, 1]"),
            std::string::npos);
  const std::string neg_kd = "newmtl white\nKd -0.1 0 0\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n";
  EXPECT_NE(load_error(dir, kObj, neg_kd).find("s.mtl:2"), std::string::npos);
}

TEST(ObjLoader, NegativeOrNonFiniteEmissionIsRejected) {
  testing::TempDir dir;
  const std::string neg = "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 1 -1 1\n";
  EXPECT_NE(load_error(dir, kObj, neg).find("s.mtl:5: material 'lamp': emission Ke"),
            std::string::npos);
  const std::string inf = "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 1 inf 1\n";
  EXPECT_NE(load_error(dir, kObj, inf).find("must be finite"), std::string::npos);
}

TEST(ObjLoader, DegenerateFacesAreDroppedAndCounted) {
  testing::TempDir dir;
  dir.write("s.mtl", kMtl);
  const std::string obj = std::string(kObj) + "g sliver\nusemtl white\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 8 9 10\nf 8 8 9\n";
  LoadReport report;
  const Scene s = load_obj(dir.write("s.obj", obj), &report);
  EXPECT_EQ(report.degenerate_faces_dropped, 2);
  EXPECT_EQ(s.faces.size(), 2u);
}

TEST(ObjLoader, NonPlanarPolygonIsSplitPreservingItsTriangles) {
  testing::TempDir dir;
  dir.write("s.mtl", kMtl);
  // A quad with one corner lifted by 0.1 (10 % of its size, far beyond the tolerance).
  const std::string obj =
      "mtllib s.mtl\ng w\nusemtl white\nv 0 0 0\nv 1 0 0\nv 1 1 0.1\nv 0 1 0\nf 1 2 3 4\n";
  LoadReport report;
  const Scene s = load_obj(dir.write("s.obj", obj), &report);
  EXPECT_EQ(report.nonplanar_faces_split, 1);
  ASSERT_EQ(s.faces.size(), 2u);
  for (const auto& f : s.faces) EXPECT_EQ(f.vertices.size(), 3u);
}

TEST(ObjLoader, ManyNonPlanarPolygonsAreOneWarningWithCountFirstAndWorst) {
  // Issue 35: 3,028 lines on Sponza, one per polygon. Now one line: how many, where the
  // first is, and the worst one's deviation (absolute and relative to its size).
  testing::TempDir dir;
  dir.write("s.mtl", kMtl);
  std::string obj = "mtllib s.mtl\ng w\nusemtl white\n";
  // 200 unit quads side by side, corner 3 lifted by 0.01 + k * 1e-4 (quad 199 the worst:
  // 0.0299, lines 4.. are the vertices, faces from line 804).
  for (int k = 0; k < 200; ++k)
    obj += "v " + std::to_string(k) + " 0 0\nv " + std::to_string(k + 1) + " 0 0\nv " +
           std::to_string(k + 1) + " 1 " + std::to_string(0.01 + k * 1e-4) + "\nv " +
           std::to_string(k) + " 1 0\n";
  for (int k = 0; k < 200; ++k)
    obj += "f " + std::to_string(4 * k + 1) + " " + std::to_string(4 * k + 2) + " " +
           std::to_string(4 * k + 3) + " " + std::to_string(4 * k + 4) + "\n";
  LoadReport report;
  const Scene s = load_obj(dir.write("s.obj", obj), &report);
  EXPECT_EQ(report.nonplanar_faces_split, 200);
  EXPECT_EQ(s.faces.size(), 400u);
  int lines = 0;
  for (const std::string& w : report.warnings)
    if (w.find("non-planar") != std::string::npos) {
      ++lines;
      EXPECT_NE(w.find("s.obj:804: 200 non-planar polygons (the first here) split into "
                       "triangles; the worst (line 1003)"),
                std::string::npos)
          << w;
    }
  EXPECT_EQ(lines, 1);
}

TEST(ObjLoader, EmptySceneIsAnErrorAndNoEmitterOnlyAWarning) {
  testing::TempDir dir;
  EXPECT_NE(load_error(dir, "mtllib s.mtl\n# nothing\n").find("empty scene"), std::string::npos);
  dir.write("s.mtl", kMtl);
  LoadReport report;
  load_obj(dir.write("dark.obj", "mtllib s.mtl\nusemtl white\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
           &report);
  EXPECT_FALSE(report.has_emitter);
}

}  // namespace lambert

namespace lambert {

TEST(ObjLoader, RepeatedCornersAreCollapsedAndNeverMakeZeroAreaPatches) {
  testing::TempDir dir;
  dir.write("s.mtl", kMtl);
  // f 1 2 3 3 and a fourth vertex at the third one's position: both are the unit triangle.
  const std::string obj =
      "mtllib s.mtl\ng t\nusemtl white\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 1 1 0\n"
      "f 1 2 3 3\nf 1 2 3 4\nf 1 1 2 3\n";
  const Scene s = load_obj(dir.write("s.obj", obj));
  ASSERT_EQ(s.faces.size(), 3u);
  for (const auto& f : s.faces) EXPECT_EQ(f.vertices.size(), 3u);
  const PatchMesh m = mesh_scene(s, {0.3, 0});
  for (const auto& p : m.patches) EXPECT_GT(p.area, 0.0);
}

}  // namespace lambert
