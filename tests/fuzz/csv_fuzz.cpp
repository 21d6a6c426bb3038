// libFuzzer target: the radiosity CSV (`render --radiosity`) from memory, read onto a fixed
// 3-patch mesh (areas 1, 0.5, 0.25). A lambert::Error is a clean refusal; anything else is
// a bug.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/radiosity_csv.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const lambert::PatchMesh mesh = [] {
    lambert::PatchMesh m;
    m.patches.resize(3);
    for (int i = 0; i < 3; ++i) m.patches[i].area = 1.0 / (1 << i);
    return m;
  }();
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    lambert::read_radiosity_csv_stream(in, "fuzz.csv", mesh);
  } catch (const lambert::Error&) {
  }
  return 0;
}
