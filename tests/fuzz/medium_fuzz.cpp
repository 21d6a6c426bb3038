// libFuzzer target: the medium grid file (`--medium-grid`) from memory. A lambert::Error is a
// clean refusal; anything else is a bug. An accepted grid must pass validate_medium.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/medium_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const lambert::Medium m = lambert::read_medium_grid_stream(in, "fuzz.txt");
    lambert::validate_medium(m, "fuzz.txt");
  } catch (const lambert::Error&) {
  }
  return 0;
}
