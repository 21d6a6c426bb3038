// libFuzzer target: an STL file (ASCII or binary, told apart by content) from memory. A
// lambert::Error is a clean refusal; anything else is a bug. An accepted scene must have
// faces with positive area on valid surfaces.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/error.hpp"
#include "io/stl_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const lambert::Scene s = lambert::load_stl_bytes(bytes, "fuzz.stl");
    if (s.faces.empty()) std::abort();
    for (const auto& f : s.faces) {
      if (f.surface < 0 || static_cast<std::size_t>(f.surface) >= s.surfaces.size()) std::abort();
      for (const auto v : f.vertices)
        if (v < 0 || static_cast<std::size_t>(v) >= s.vertices.size()) std::abort();
    }
  } catch (const lambert::Error&) {
  }
  return 0;
}
