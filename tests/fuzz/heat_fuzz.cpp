// libFuzzer target: the heat command's surface conditions (`--surfaces`, JSON) from memory,
// resolved against a fixed list of surface names. A lambert::Error is a clean refusal;
// anything else is a bug. An accepted file must give every surface a condition whose
// numbers the thermal solver accepts (emissivity in [0, 1], finite values, T >= 0).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/heat_surfaces.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::vector<std::string> kSurfaces = {"floor", "ceiling", "wall", "*x", ""};
  try {
    const lambert::SurfaceConditions c = lambert::parse_surface_conditions(
        std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
    for (const lambert::SurfaceCondition& s : lambert::resolve_surface_conditions(c, kSurfaces)) {
      if (!(s.emissivity >= 0.0 && s.emissivity <= 1.0) || !std::isfinite(s.value)) std::abort();
      if (s.known_temperature && s.value < 0.0) std::abort();
    }
  } catch (const lambert::Error&) {
  }
  return 0;
}
