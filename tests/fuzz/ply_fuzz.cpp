// libFuzzer target: a PLY file (ASCII, binary little- or big-endian) from memory. A
// lambert::Error is a clean refusal; anything else is a bug. An accepted scene must have
// faces with positive area on valid surfaces.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "io/ply_loader.hpp"
#include "scene_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    check_fuzzed_scene(lambert::load_ply_bytes(bytes, "fuzz.ply"));
  } catch (const lambert::Error&) {
  }
  return 0;
}
