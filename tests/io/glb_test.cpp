// The glTF binary writer (io/glb.hpp), read back by an independent reader (tinygltf,
// tests/common/glb_reader.hpp). The values, the camera's orientation and the extras must survive.
#include "io/glb.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "common/glb_reader.hpp"
#include "common/temp_dir.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

// A unit square in z = 0 (two triangles, facing +z) with two attributes, its four edges and a
// camera at (0.5, 0.5, 3) looking at its centre.
GlbContent square() {
  GlbContent c;
  c.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  c.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  c.triangles = {0, 1, 2, 0, 2, 3};
  c.edges = {0, 1, 1, 2, 2, 3, 3, 0};
  c.attributes = {{"COLOR_0", 3, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}},
                  {"_TEMPERATURE", 1, {300, 310, 320, 330}}};
  GlbCamera cam;
  cam.eye = {0.5, 0.5, 3};
  cam.look_at = {0.5, 0.5, 0};
  cam.up = {0, 1, 0};
  cam.yfov_degrees = 30;
  cam.aspect = 1.5;
  c.camera = cam;
  c.asset_extras = {{"units", "W/m^2"}, {"exposure_ev", -1.5}};
  c.primitive_extras = {{"emitters", {"light"}}};
  return c;
}

tinygltf::Model read_back(const std::string& bytes) { return testing::parse_glb(bytes); }
std::vector<float> floats(const tinygltf::Model& m, int i) { return testing::glb_floats(m, i); }
std::vector<std::uint32_t> indices(const tinygltf::Model& m, int i) {
  return testing::glb_indices(m, i);
}

TEST(Glb, AnIndependentReaderGetsBackEveryValueIndexAndExtra) {
  const GlbContent c = square();
  const std::string bytes = glb_bytes(c);
  // GLB container: magic, version 2, the total length; chunks 4-byte aligned.
  ASSERT_GE(bytes.size(), 20u);
  EXPECT_EQ(bytes.substr(0, 4), "glTF");
  std::uint32_t version = 0, length = 0;
  std::memcpy(&version, bytes.data() + 4, 4);
  std::memcpy(&length, bytes.data() + 8, 4);
  EXPECT_EQ(version, 2u);
  EXPECT_EQ(length, bytes.size());
  EXPECT_EQ(bytes.size() % 4, 0u);

  const tinygltf::Model m = read_back(bytes);
  ASSERT_EQ(m.meshes.size(), 2u);
  const tinygltf::Primitive& tri = m.meshes[0].primitives.at(0);
  EXPECT_EQ(tri.mode, TINYGLTF_MODE_TRIANGLES);
  EXPECT_EQ(floats(m, tri.attributes.at("POSITION")), c.positions);
  EXPECT_EQ(floats(m, tri.attributes.at("NORMAL")), c.normals);
  EXPECT_EQ(floats(m, tri.attributes.at("COLOR_0")), c.attributes[0].values);
  EXPECT_EQ(floats(m, tri.attributes.at("_TEMPERATURE")), c.attributes[1].values);
  EXPECT_EQ(indices(m, tri.indices), c.triangles);
  // POSITION carries the bounds the specification requires.
  const tinygltf::Accessor& pos = m.accessors[tri.attributes.at("POSITION")];
  EXPECT_EQ(pos.minValues, (std::vector<double>{0, 0, 0}));
  EXPECT_EQ(pos.maxValues, (std::vector<double>{1, 1, 0}));
  // The edges: lines over the same positions.
  const tinygltf::Primitive& lines = m.meshes[1].primitives.at(0);
  EXPECT_EQ(lines.mode, TINYGLTF_MODE_LINE);
  EXPECT_EQ(lines.attributes.at("POSITION"), tri.attributes.at("POSITION"));
  EXPECT_EQ(indices(m, lines.indices), c.edges);
  // Unlit, double-sided material; extras kept.
  EXPECT_TRUE(m.materials.at(0).extensions.count("KHR_materials_unlit"));
  EXPECT_TRUE(m.materials.at(0).doubleSided);
  EXPECT_EQ(m.asset.extras.Get("units").Get<std::string>(), "W/m^2");
  EXPECT_DOUBLE_EQ(m.asset.extras.Get("exposure_ev").GetNumberAsDouble(), -1.5);
  EXPECT_EQ(tri.extras.Get("emitters").Get(0).Get<std::string>(), "light");
}

TEST(Glb, TheCameraNodeLooksFromTheEyeAtTheTarget) {
  // An oblique view: the node's rotation must take glTF's camera axes (-Z forward, +Y up) to
  // the view direction and the up vector projected off it; checked to 1e-12 (double
  // quaternion, exact math up to rounding).
  GlbContent c = square();
  c.camera->eye = {3, 2, 1};
  c.camera->look_at = {0, 0.5, 0};
  c.camera->up = {0, 1, 0};
  const tinygltf::Model m = read_back(glb_bytes(c));
  ASSERT_EQ(m.cameras.size(), 1u);
  EXPECT_EQ(m.cameras[0].type, "perspective");
  EXPECT_NEAR(m.cameras[0].perspective.yfov, 30 * M_PI / 180, 1e-15);
  EXPECT_DOUBLE_EQ(m.cameras[0].perspective.aspectRatio, 1.5);
  const tinygltf::Node& node = m.nodes.back();
  ASSERT_EQ(node.camera, 0);
  const Eigen::Quaterniond q(node.rotation[3], node.rotation[0], node.rotation[1],
                             node.rotation[2]);
  const Eigen::Vector3d forward = (c.camera->look_at - c.camera->eye).normalized();
  EXPECT_NEAR((q * Eigen::Vector3d(0, 0, -1) - forward).norm(), 0.0, 1e-12);
  const Eigen::Vector3d up = q * Eigen::Vector3d::UnitY();
  EXPECT_NEAR(up.dot(forward), 0.0, 1e-12);
  EXPECT_GT(up.y(), 0.0);
  EXPECT_EQ(node.translation, (std::vector<double>{3, 2, 1}));
  // The scene lists every node.
  EXPECT_EQ(m.scenes.at(0).nodes.size(), m.nodes.size());
}

TEST(Glb, InconsistentContentIsABugNotAFile) {
  testing::TempDir dir;
  GlbContent c = square();
  c.triangles[4] = 4;  // out of range
  EXPECT_THROW(write_glb(dir.file("x.glb"), c), InternalError);
  c = square();
  c.attributes[0].values[5] = std::nanf("");
  EXPECT_THROW(glb_bytes(c), InternalError);
  c = square();
  c.attributes[1].name = "TEMPERATURE";  // glTF needs a leading '_' for our own names
  EXPECT_THROW(glb_bytes(c), InternalError);
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.glb")));
}

}  // namespace
}  // namespace lambert
