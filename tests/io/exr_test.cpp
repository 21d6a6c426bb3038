#include "io/exr.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "io/ply.hpp"
#include "io/tonemap.hpp"

namespace lambert {
namespace {

const Material kGrey{"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};

PatchMesh two_surface_mesh(double max_edge) {
  Scene s;
  add_polygon(s, "floor", kGrey, {{0, 0, 0}, {0, 0, 3}, {4, 0, 3}, {4, 0, 0}});
  add_polygon(s, "wall", kGrey, {{0, 0, 3}, {0, 2, 3}, {4, 2, 3}, {4, 0, 3}});
  return mesh_scene(s, {max_edge, 0});
}

VertexField field_on(const PatchMesh& mesh) {
  Eigen::MatrixX3d B(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const auto& c = mesh.patches[i].centroid;
    B.row(i) << 1 + c.x(), 10 + c.y() * c.z(), 0.001 * (1 + c.z());
  }
  return interpolate_to_vertices(mesh, B);
}

// Relative rounding of a double stored as float: 2^-24.
constexpr double kFloatRel = 0x1p-24;

}  // namespace

TEST(Exr, VertexExrRoundTripsValuesPositionsNormalsAndAttributes) {
  lambert::testing::TempDir dir;
  const PatchMesh mesh = two_surface_mesh(0.5);
  const VertexField f = field_on(mesh);
  ExrInfo info;
  info.units = "radiosity W/m^2";
  info.settings = "estimator=hybrid samples=8 seed=3";
  info.surface_names = mesh.surface_names;
  const std::string path = dir.file("v.exr");
  write_vertex_exr(path, f, info);
  const VertexExr r = read_vertex_exr(path);
  ASSERT_EQ(r.vertex_count, f.size());
  EXPECT_EQ(r.width, std::min<int>(f.size(), kVertexExrWidth));
  EXPECT_EQ(r.height, (f.size() + r.width - 1) / r.width);
  EXPECT_EQ(r.info.units, info.units);
  EXPECT_EQ(r.info.settings, info.settings);
  EXPECT_EQ(r.info.surface_names, mesh.surface_names);
  EXPECT_FALSE(r.layout.empty());
  for (std::int32_t k = 0; k < f.size(); ++k) {
    // Every channel is FLOAT: each value comes back rounded to the nearest float, i.e.
    // within relative 2^-24 of the double written.
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(r.radiosity(k, c), f.values(k, c), kFloatRel * std::abs(f.values(k, c)));
      EXPECT_NEAR(r.positions[k][c], f.positions[k][c], kFloatRel * std::abs(f.positions[k][c]));
      EXPECT_NEAR(r.normals[k][c], f.normals[k][c], kFloatRel);
    }
    EXPECT_EQ(r.surface[k], f.surface[k]);  // small integers are exact in a float
  }
  // No temporary file is left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST(Exr, LargeVertexCountsWrapIntoRowsOf1024) {
  lambert::testing::TempDir dir;
  const PatchMesh mesh = two_surface_mesh(0.1);  // 40x30 + 40x20 quads: > 2000 vertices
  const VertexField f = field_on(mesh);
  ASSERT_GT(f.size(), 2 * kVertexExrWidth);
  write_vertex_exr(dir.file("v.exr"), f, {"u", "s", mesh.surface_names});
  const VertexExr r = read_vertex_exr(dir.file("v.exr"));
  EXPECT_EQ(r.width, kVertexExrWidth);
  EXPECT_EQ(r.height, (f.size() + kVertexExrWidth - 1) / kVertexExrWidth);
  EXPECT_EQ(r.surface.back(), f.surface.back());
  EXPECT_FLOAT_EQ(static_cast<float>(r.radiosity(f.size() - 1, 1)),
                  static_cast<float>(f.values(f.size() - 1, 1)));
}

TEST(Exr, ImageRoundTripsExactly) {
  lambert::testing::TempDir dir;
  Image img;
  img.width = 7;
  img.height = 5;
  for (int k = 0; k < 35; ++k) {
    img.rgb.push_back(0.5f * k);
    img.rgb.push_back(1e-3f * k);
    img.rgb.push_back(1e4f + k);
    img.alpha.push_back(k % 3 == 0 ? 0.0f : 1.0f / static_cast<float>(k % 3));
  }
  write_image_exr(dir.file("i.exr"), img, {"radiance", "camera x", {}});
  ExrInfo info;
  const Image back = read_image_exr(dir.file("i.exr"), &info);
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 5);
  EXPECT_EQ(back.rgb, img.rgb);  // FLOAT channels: bit-exact
  EXPECT_EQ(back.alpha, img.alpha);
  EXPECT_EQ(info.units, "radiance");
  EXPECT_EQ(info.settings, "camera x");
}

TEST(Exr, ReadingAMissingOrForeignFileIsAnIoError) {
  lambert::testing::TempDir dir;
  EXPECT_THROW(read_vertex_exr(dir.file("none.exr")), IoError);
  Image img{2, 1, {1, 2, 3, 4, 5, 6}, {1, 1}};
  write_image_exr(dir.file("i.exr"), img, {});
  EXPECT_THROW(read_vertex_exr(dir.file("i.exr")), IoError);  // no P/N/surface channels
  EXPECT_THROW(write_vertex_exr(dir.file("no/such/dir/v.exr"), field_on(two_surface_mesh(1)), {}),
               IoError);
}

TEST(Tonemap, SrgbOetfMatchesTheStandardAndAutoExposureHitsTheKey) {
  // IEC 61966-2-1: the two branches meet at 0.0031308 -> 0.04045; 1 -> 1; 0.5 -> 0.7354.
  EXPECT_NEAR(srgb_oetf(0.0031308), 0.04045, 1e-5);  // published constants have 5 digits
  EXPECT_DOUBLE_EQ(srgb_oetf(1.0), 1.0);
  EXPECT_NEAR(srgb_oetf(0.5), 0.735357, 1e-6);
  EXPECT_EQ(srgb_oetf(-1.0), 0.0);
  // A uniform grey image of luminance Y gets EV = log2(key / Y).
  Image img{4, 4, std::vector<float>(48, 0.25f), std::vector<float>(16, 1.0f)};
  EXPECT_NEAR(auto_exposure(img), std::log2(kKey / 0.25), 1e-6);  // float luminance weights
  const auto px = to_srgb8(Eigen::Vector3d::Constant(0.25), auto_exposure(img));
  EXPECT_EQ(px[0], std::lround(255 * srgb_oetf(kKey)));
}

TEST(Ply, WritesOneVertexPerShadingVertexAndOneFacePerPatch) {
  lambert::testing::TempDir dir;
  const PatchMesh mesh = two_surface_mesh(1.0);
  const VertexField f = field_on(mesh);
  write_ply(dir.file("m.ply"), mesh, f, 0.0, "test");
  std::ifstream in(dir.file("m.ply"));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "ply");
  int vertices = -1, faces = -1, header = 1;
  while (std::getline(in, line) && line != "end_header") {
    ++header;
    std::istringstream ls(line);
    std::string a, b;
    int n = 0;
    ls >> a >> b >> n;
    if (a == "element" && b == "vertex") vertices = n;
    if (a == "element" && b == "face") faces = n;
  }
  EXPECT_EQ(vertices, f.size());
  EXPECT_EQ(faces, mesh.size());
  int body = 0;
  while (std::getline(in, line)) ++body;
  EXPECT_EQ(body, vertices + faces);
}

}  // namespace lambert
