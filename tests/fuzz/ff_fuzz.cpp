// libFuzzer target: saved form-factor files (binary and Matrix Market, chosen by content as
// `--ff` does) from memory, without the mesh identity check so that the fuzzer reaches the
// entries. A lambert::Error is a clean refusal; anything else is a bug.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/ff_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    lambert::read_form_factors(in, "fuzz.ff", 0, -1);
  } catch (const lambert::Error&) {
  }
  return 0;
}
