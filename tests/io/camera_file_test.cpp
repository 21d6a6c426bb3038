#include "io/camera_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace lambert {
namespace {

std::string refusal(const std::string& text) {
  std::istringstream in(text);
  try {
    read_camera_stream(in, "s.camera");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(accepted)";
}

}  // namespace

TEST(CameraFile, PublishedCornellCameraReads) {
  std::istringstream in(
      "# comment\neye 278 273 -800\r\nlook_at 278 273 0\nup 0 1 0  # y up\nfocal_mm 35\nfilm_mm 25");
  const Camera c = read_camera_stream(in, "s.camera");
  EXPECT_TRUE(c.defined);
  EXPECT_EQ(c.eye, Eigen::Vector3d(278, 273, -800));
  // 2 atan(12.5 / 35) in degrees; both are computed by the same expression, so 1e-12
  // (a few ulps of 39.3) is only rounding.
  EXPECT_NEAR(c.vfov_degrees, 2.0 * std::atan(12.5 / 35.0) * 180.0 / M_PI, 1e-12);
}

TEST(CameraFile, MalformedSidecarsAreRefusedNamingFileAndLine) {
  const std::string ok = "eye 0 0 -5\nlook_at 0 0 0\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {ok + "vfov 40 degrees\n", "s.camera:3: 'vfov' needs 1 number(s), found 2"},
      {"eye 0 0 -5 1\nlook_at 0 0 0\n", "s.camera:1: 'eye' needs 3 number(s), found 4"},
      {"eye 0 0\nlook_at 0 0 0\n", "s.camera:1: 'eye' needs 3"},
      {ok + "eye 0 0 -6\n", "s.camera:3: 'eye' repeated (first on line 1)"},
      {ok + "focal_mm 35\n", "s.camera:3: 'focal_mm' needs 'film_mm' too"},
      {ok + "film_mm 25\n", "s.camera:3: 'film_mm' needs 'focal_mm' too"},
      {ok + "focal_mm 35\nfilm_mm 25\nvfov 40\n", "s.camera:5: 'vfov' and 'focal_mm'"},
      {ok + "vfov 180\n", "s.camera:3: field of view 180"},
      {ok + "vfov -1\n", "s.camera:3: field of view"},
      {ok + "focal_mm 0\nfilm_mm 25\n", "s.camera:3: focal length and film width must be positive"},
      {ok + "vfov 0x1p3\n", "s.camera:3: 'vfov': '0x1p3' not a number"},
      {ok + "up nan 1 0\n", "s.camera:3: 'up': 'nan' not finite"},
      {ok + "fov 40\n", "s.camera:3: unknown camera key 'fov'"},
      {"eye 0 0 0\nlook_at 0 0 0\n", "s.camera:2: look_at must differ from eye"},
      {ok + "up 0 0 1\n", "s.camera:3: up must not be zero or parallel"},
      {"eye 0 -5 0\nlook_at 0 0 0\n", "s.camera:2: up must not be zero or parallel"},
      {"eye 0 0 -5\n", "s.camera: camera needs 'eye' and 'look_at'"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string message = refusal(text);
    EXPECT_EQ(message.rfind(expected, 0), 0u) << text << "-> " << message;
  }
}

}  // namespace lambert
