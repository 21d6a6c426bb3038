// Scenes that cannot work say so: an inside-out cube, a light facing out of its box and a
// scene without emitter each give one warning on stderr naming the cause, and the command
// still succeeds (exit 0).

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "geometry/analytic.hpp"

namespace lambert {

using testing::run;
namespace {

// Writes `scene` as <name>.obj and <name>.mtl (one group and material per surface), with
// the winding of every face reversed when `invert` is set; returns the OBJ's path.
std::string write_obj(const testing::TempDir& dir, const std::string& name, const Scene& scene,
                      bool invert = false) {
  std::ostringstream obj, mtl;
  obj << "mtllib " << name << ".mtl\n";
  for (const auto& v : scene.vertices) obj << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (size_t s = 0; s < scene.surfaces.size(); ++s) {
    const Material& m = scene.material_of(static_cast<std::int32_t>(s));
    mtl << "newmtl m" << s << "\nKd " << m.rho.x() << ' ' << m.rho.y() << ' ' << m.rho.z()
        << "\nKe " << m.emission.x() << ' ' << m.emission.y() << ' ' << m.emission.z() << '\n';
    obj << "g " << scene.surfaces[s].name << "\nusemtl m" << s << '\n';
    for (const Face& f : scene.faces) {
      if (f.surface != static_cast<std::int32_t>(s)) continue;
      std::vector<std::int32_t> idx = f.vertices;
      if (invert) std::reverse(idx.begin(), idx.end());
      obj << 'f';
      for (auto i : idx) obj << ' ' << i + 1;
      obj << '\n';
    }
  }
  dir.write(name + ".mtl", mtl.str());
  return dir.write(name + ".obj", obj.str());
}

// The unit cube with its faces renamed to words (the lamp is "top") and no emitter when
// `lit` is false.
Scene cube(bool lit = true) {
  Scene s = unit_cube();
  const char* names[] = {"left", "right", "floor", "top", "back", "front"};
  for (size_t k = 0; k < s.surfaces.size(); ++k) s.surfaces[k].name = names[k];
  if (!lit)
    for (Material& m : s.materials) m.emission.setZero();
  return s;
}

// A Cornell-like box open at the top, faces inward, with a small light in the opening
// (y = 1) wound so that it faces up, out of the box. In the plane of the walls' top edges
// it sees nothing at all; a light just below them (y = 0.999) would see 0.001-high strips of
// the walls: a tiny but nonzero row, rightly not warned about.
Scene open_box_light_facing_up() {
  const Material white{"white", Eigen::Vector3d::Constant(0.6), Eigen::Vector3d::Zero()};
  const Material red{"red", Eigen::Vector3d(0.7, 0.1, 0.1), Eigen::Vector3d::Zero()};
  const Material light{"light", Eigen::Vector3d::Constant(0.2), Eigen::Vector3d(10, 9, 8)};
  Scene s;
  add_polygon(s, "floor", white, {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}});
  add_polygon(s, "back", white, {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}});
  add_polygon(s, "left", red, {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}});
  add_polygon(s, "right", white, {{1, 0, 0}, {1, 0, 1}, {1, 1, 1}, {1, 1, 0}});
  add_polygon(s, "light", light, {{0.4, 1, 0.4}, {0.4, 1, 0.6}, {0.6, 1, 0.6}, {0.6, 1, 0.4}});
  return s;
}

// Runs a command with stderr captured; returns {exit code, stderr}.
std::pair<int, std::string> run_captured(const std::vector<std::string>& args) {
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const int code = run(args);
  std::string err = ::testing::internal::GetCapturedStderr();
  ::testing::internal::GetCapturedStdout();
  return {code, err};
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

const std::vector<std::string> kSmall = {"--max-edge", "0.5", "--samples", "4"};

std::vector<std::string> small(std::vector<std::string> args) {
  args.insert(args.end(), kSmall.begin(), kSmall.end());
  return args;
}

}  // namespace

TEST(LightingWarnings, InsideOutCubeWarnsOnceForComputedAndLoadedF) {
  testing::TempDir dir;
  const std::string obj = write_obj(dir, "inside_out", cube(), true);
  const std::string warning = "warning: no patch faces any other";
  for (const auto& args :
       {small({"solve", obj, "-o", dir.file("B.csv")}),
        small({"formfactors", obj, "-o", dir.file("F.bin")}),
        // --samples would be refused with --ff (the file's own settings are used).
        std::vector<std::string>{"solve", obj, "--ff", dir.file("F.bin"), "--max-edge", "0.5",
                                 "-o", dir.file("B2.csv")}}) {
    const auto [code, err] = run_captured(args);
    EXPECT_EQ(code, kExitOk) << args[0] << '\n' << err;
    EXPECT_EQ(count(err, warning), 1) << args[0] << '\n' << err;
    EXPECT_NE(err.find("inside out or its winding inverted"), std::string::npos) << err;
    // The lamp's blindness has the same cause: no second warning.
    EXPECT_EQ(count(err, "warning:"), 1) << args[0] << '\n' << err;
  }
}

TEST(LightingWarnings, LightFacingOutOfTheBoxIsNamedByRun) {
  testing::TempDir dir;
  const std::string obj = write_obj(dir, "box", open_box_light_facing_up());
  const auto [code, err] = run_captured(
      small({"run", obj, "-o", dir.file("out"), "--size", "16x16", "--antialias", "1"}));
  EXPECT_EQ(code, kExitOk) << err;
  EXPECT_EQ(count(err, "warning: emitter 'light' sees nothing from its front side"), 1) << err;
  EXPECT_NE(err.find("inverted winding"), std::string::npos) << err;
  EXPECT_EQ(count(err, "warning:"), 1) << err;
}

// One warning for a scene without an emitter (the loader's, naming the file and --emit),
// not a second one from the F check.
TEST(LightingWarnings, SceneWithoutEmitterIsWarnedAboutOnce) {
  testing::TempDir dir;
  const std::string obj = write_obj(dir, "dark", cube(false));
  for (const auto& args :
       {small({"render", obj, "-o", dir.file("img.exr"), "--size", "16x16", "--antialias", "1"}),
        small({"formfactors", obj, "-o", dir.file("F.bin")})}) {
    const auto [code, err] = run_captured(args);
    EXPECT_EQ(code, kExitOk) << err;
    EXPECT_EQ(count(err, "emit"), 1 + count(err, "--emit")) << err;  // one line mentions it
    EXPECT_EQ(count(err, ": no emitter (no material with Ke > 0)"), 1) << err;
    EXPECT_EQ(count(err, "no surface emits"), 0) << err;
  }
}

TEST(LightingWarnings, AWorkingSceneHasNoWarning) {
  testing::TempDir dir;
  const std::string obj = write_obj(dir, "cube", cube());
  const auto [code, err] = run_captured(small({"solve", obj, "-o", dir.file("B.csv")}));
  EXPECT_EQ(code, kExitOk) << err;
  EXPECT_EQ(count(err, "warning:"), 0) << err;
}

}  // namespace lambert
