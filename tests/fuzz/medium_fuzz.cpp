// libFuzzer target: the medium grid file (`--medium-grid`) from memory. A lambert::Error is a
// clean refusal; anything else is a bug. An accepted grid must pass validate_medium, and
// then the medium's geometry runs on it: the transmittance along the box's diagonals and
// through its centre must lie in [0, 1].
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "geometry/media/medium.hpp"
#include "io/medium_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const lambert::Medium m = lambert::read_medium_grid_stream(in, "fuzz.txt");
    lambert::validate_medium(m, "fuzz.txt");
    const Eigen::Vector3d c = 0.5 * (m.lo + m.hi), d = m.hi - m.lo;
    const Eigen::Vector3d ends[][2] = {
        {m.lo, m.hi},
        {m.lo + Eigen::Vector3d(d.x(), 0, 0), m.hi - Eigen::Vector3d(d.x(), 0, 0)},
        {c - 2.0 * d, c + 0.25 * d},
        {c, c}};
    for (const auto& e : ends) {
      const double t = lambert::transmittance(m, e[0], e[1]);
      if (!(t >= 0.0 && t <= 1.0)) std::abort();
    }
  } catch (const lambert::Error&) {
  }
  return 0;
}
