// Scenes read through assimp (io/model_loader.hpp): glTF and GLB written here byte by byte
// (an independent reading of the format), node transforms and mirroring, materials, and
// malformed files refused with one line naming the file.
#include "io/model_loader.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/gltf_cube.hpp"
#include "core/error.hpp"
#include "geometry/polygon.hpp"
#include "io/stl_loader.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;
using testing::glb;
using testing::gltf_with_data_uri;
using testing::kScaleAndMove;

class ModelLoader : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("lambert_model_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& bytes) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  fs::path dir_;
};

Eigen::Vector3d face_normal(const Scene& s, const Face& f) {
  const Eigen::Vector3d& a = s.vertices[f.vertices[0]];
  return (s.vertices[f.vertices[1]] - a).cross(s.vertices[f.vertices[2]] - a);
}

// Every face's front faces the cube's centre `c` (its normal points from the face inward).
void expect_fronts_inward(const Scene& s, const Eigen::Vector3d& c) {
  for (const Face& f : s.faces)
    EXPECT_GT(face_normal(s, f).dot(c - s.vertices[f.vertices[0]]), 0.0);
}

TEST_F(ModelLoader, AGltfCubeComesWithItsNodeTransformMaterialAndArea) {
  const std::string path = write("cube.gltf", gltf_with_data_uri(kScaleAndMove));
  LoadReport report;
  const Scene s = load_scene_path(path, &report);
  ASSERT_EQ(s.surfaces.size(), 1u);
  EXPECT_EQ(s.surfaces[0].name, "box");
  // Only the material in use (assimp appends a default one of its own).
  ASSERT_EQ(s.materials.size(), 1u);
  const Material& m = s.materials[s.surfaces[0].material];
  EXPECT_EQ(m.name, "glow");
  // float32 factors 0.25, 0.5, 0.75, 1, 0 are exact in binary.
  EXPECT_EQ(m.rho, Eigen::Vector3d(0.25, 0.5, 0.75));
  EXPECT_EQ(m.emission, Eigen::Vector3d(1.0, 0.5, 0.0));
  EXPECT_TRUE(report.has_emitter);
  EXPECT_FALSE(report.default_material_used);
  // 12 triangles of the scaled cube: six sides of 2 x 2, exact in floating point.
  EXPECT_EQ(s.faces.size(), 12u);
  double area = 0.0;
  for (const Face& f : s.faces) area += 0.5 * face_normal(s, f).norm();
  EXPECT_EQ(area, 24.0);
  const auto [lo, hi] = s.bounds();
  EXPECT_EQ(lo, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(hi, Eigen::Vector3d(3, 2, 2));
  expect_fronts_inward(s, {2, 1, 1});
}

// A mirroring transform (x -> -x) reverses the winding the file gives; the loader reverses
// the corners back, so the walls still face into the (mirrored) cube.
TEST_F(ModelLoader, AMirroringNodeKeepsEveryFrontFacingTheSameWay) {
  const Scene s =
      load_model(write("mirror.gltf", gltf_with_data_uri("-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1")));
  const auto [lo, hi] = s.bounds();
  EXPECT_EQ(lo, Eigen::Vector3d(-1, 0, 0));
  EXPECT_EQ(hi, Eigen::Vector3d(0, 1, 1));
  expect_fronts_inward(s, {-0.5, 0.5, 0.5});
}

// The same scene as a GLB (binary container) is the same scene, told apart by its first bytes
// even under a name assimp would not know.
TEST_F(ModelLoader, AGlbIsTheSameSceneAsItsGltfWhateverItsName) {
  const Scene a = load_scene_path(write("cube.gltf", gltf_with_data_uri(kScaleAndMove)));
  const Scene b = load_scene_path(write("cube.bin3d", glb(kScaleAndMove)));
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t v = 0; v < a.vertices.size(); ++v) EXPECT_EQ(a.vertices[v], b.vertices[v]);
  ASSERT_EQ(a.faces.size(), b.faces.size());
  for (size_t f = 0; f < a.faces.size(); ++f) EXPECT_EQ(a.faces[f].vertices, b.faces[f].vertices);
  EXPECT_EQ(b.materials[0].rho, a.materials[0].rho);
}

// COLLADA (another of assimp's formats): a unit quad at z = 1 in a Z_UP file comes y up (as
// every scene lambert frames), kept as one planar quad, with its lambert material's diffuse
// colour as rho.
TEST_F(ModelLoader, AColladaQuadComesYUpWithItsDiffuseColour) {
  const std::string dae = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
 <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
 <library_effects><effect id="fx"><profile_COMMON><technique sid="common"><lambert>
  <diffuse><color>0.5 0.25 0.125 1</color></diffuse></lambert></technique></profile_COMMON>
 </effect></library_effects>
 <library_materials><material id="red" name="red"><instance_effect url="#fx"/></material>
 </library_materials>
 <library_geometries><geometry id="quad" name="quad"><mesh>
  <source id="pos"><float_array id="pos-array" count="12">0 0 1 1 0 1 1 1 1 0 1 1</float_array>
   <technique_common><accessor source="#pos-array" count="4" stride="3"><param name="X"
    type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor>
   </technique_common></source>
  <vertices id="vtx"><input semantic="POSITION" source="#pos"/></vertices>
  <polylist material="mat" count="1"><input semantic="VERTEX" source="#vtx" offset="0"/>
   <vcount>4</vcount><p>0 1 2 3</p></polylist>
 </mesh></geometry></library_geometries>
 <library_visual_scenes><visual_scene id="scene"><node id="plate" name="plate">
  <instance_geometry url="#quad"><bind_material><technique_common><instance_material
   symbol="mat" target="#red"/></technique_common></bind_material></instance_geometry>
 </node></visual_scene></library_visual_scenes>
 <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>)";
  LoadReport report;
  const Scene s = load_scene_path(write("plate.dae", dae), &report);
  ASSERT_EQ(s.surfaces.size(), 1u);
  EXPECT_EQ(s.surfaces[0].name, "plate");
  ASSERT_EQ(s.faces.size(), 1u);
  EXPECT_EQ(s.faces[0].vertices.size(), 4u);
  for (const auto& v : s.vertices) EXPECT_NEAR(v.y(), 1.0, 1e-15);  // z up -> y up
  const Eigen::Vector3d n = face_normal(s, s.faces[0]);
  EXPECT_NEAR(n.normalized().y(), 1.0, 1e-15);  // the front (+z in the file) is +y now
  EXPECT_EQ(s.materials[s.surfaces[0].material].rho, Eigen::Vector3d(0.5, 0.25, 0.125));
  EXPECT_FALSE(report.has_emitter);
}

// The loading options a model reads: --max-reflectance clamps the base colour (a warning),
// --strict refuses what would be a warning (here rho = 1: glTF's default base colour),
// --vertex-colors-as-reflectance gives each face the mean of its corners' COLOR_0.
TEST_F(ModelLoader, TheLoadingOptionsApplyToModelsToo) {
  const std::string cube = gltf_with_data_uri(kScaleAndMove, true);
  LoadOptions clamp;
  clamp.max_reflectance = 0.6;
  LoadReport report;
  const Scene clamped = load_model(write("cube.gltf", cube), &report, clamp);
  EXPECT_EQ(clamped.materials[0].rho, Eigen::Vector3d(0.25, 0.5, 0.6));
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("--max-reflectance"), std::string::npos);

  std::string white = cube;
  const std::string factor = "\"baseColorFactor\":[0.25,0.5,0.75,1],";
  white.erase(white.find(factor), factor.size());
  EXPECT_EQ(load_model(write("white.gltf", white)).materials[0].rho, Eigen::Vector3d(1, 1, 1));
  LoadOptions strict;
  strict.strict = true;
  EXPECT_THROW(load_model(write("white.gltf", white), nullptr, strict), SceneError);
  EXPECT_NO_THROW(load_model(write("cube.gltf", cube), nullptr, strict));

  LoadOptions colours;
  colours.vertex_colors_as_reflectance = true;
  const Scene s = load_model(write("cube.gltf", cube), nullptr, colours);
  for (const Face& f : s.faces) {
    ASSERT_TRUE(f.rho.has_value());
    // The corners' colours are half their positions before the node's transform (2 p + x0).
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const std::int32_t v : f.vertices) {
      const Eigen::Vector3d p = s.vertices[v], local((p.x() - 1) / 2, p.y() / 2, p.z() / 2);
      mean += 0.5 * local / 3.0;
    }
    EXPECT_NEAR((*f.rho - mean).norm(), 0.0, 1e-15);
  }
}

// KHR_materials_emissive_strength (how Blender exports a bright lamp), which assimp 5.2 does
// not apply, scales E; a negative strength is refused.
TEST_F(ModelLoader, GltfEmissiveStrengthScalesTheEmission) {
  const Scene s = load_model(write("lamp.glb", glb(kScaleAndMove, 4.0)));
  EXPECT_EQ(s.materials[0].emission, Eigen::Vector3d(4.0, 2.0, 0.0));
  std::string negative = glb(kScaleAndMove, 4.0);
  negative.replace(negative.find("4.000000"), 8, "-4.00000");
  EXPECT_THROW(load_model(write("negative.glb", negative)), SceneError);
}

TEST_F(ModelLoader, NamesThatAssimpDoesNotTakeStayWithLambertsOwnReaders) {
  EXPECT_TRUE(looks_like_model("a/b.GLTF", "{"));
  EXPECT_TRUE(looks_like_model("a/b.dae", "<?xml"));
  EXPECT_TRUE(looks_like_model("a/b.fbx", "; FBX"));
  EXPECT_TRUE(looks_like_model("a/b", "glTF\x02"));
  EXPECT_FALSE(looks_like_model("a/b.obj", "glTF"));  // an OBJ is an OBJ, whatever it holds
  EXPECT_FALSE(looks_like_model("a/b.stl", "glTF"));
  EXPECT_FALSE(looks_like_model("a/b.ply", "ply"));
  EXPECT_FALSE(looks_like_model("scene", "v 0 0 0"));
}

// Hostile and broken files: a SceneError of one line that names the file, never a crash (the
// reader runs in a child process) and never a scene.
TEST_F(ModelLoader, MalformedFilesAreOneLineErrorsNamingTheFile) {
  const std::string whole = gltf_with_data_uri(kScaleAndMove);
  std::string no_accessors = whole.substr(0, whole.find(",\"accessors\"")) + "}";
  std::string bad_index = whole;
  bad_index.replace(bad_index.find("\"indices\":1"), 11, "\"indices\":9");
  std::string short_glb = glb(kScaleAndMove);
  short_glb.resize(short_glb.size() - 40);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"truncated.gltf", whole.substr(0, whole.size() / 2)},
      {"no_accessors.gltf", no_accessors},
      {"bad_index.gltf", bad_index},
      {"short.glb", short_glb},
      {"huge_length.glb", std::string("glTF\x02\x00\x00\x00\xff\xff\xff\x7f", 12)},
      {"garbage.fbx", std::string(2000, '\x9c')},
      {"empty.dae", ""},
      {"no_geometry.dae", "<?xml version=\"1.0\"?><COLLADA></COLLADA>"},
  };
  for (const auto& [name, bytes] : cases) {
    const std::string path = write(name, bytes);
    try {
      load_scene_path(path);
      ADD_FAILURE() << name << " loaded";
    } catch (const SceneError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace lambert
