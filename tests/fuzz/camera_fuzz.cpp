// libFuzzer target: the camera sidecar (`<scene>.camera`) from memory. A lambert::Error is a
// clean refusal; anything else is a bug. An accepted camera must be able to form an image.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/camera_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const lambert::Camera c = lambert::read_camera_stream(in, "fuzz.camera");
    if (!lambert::camera_problem(c).empty() || !(c.vfov_degrees > 0 && c.vfov_degrees < 180))
      std::abort();
  } catch (const lambert::Error&) {
  }
  return 0;
}
