// libFuzzer target: OBJ + MTL loading from memory (parse, materials, surfaces, faces).
// Input: OBJ text, optionally followed by a line "#MTL" and MTL text, which is served for
// every mtllib statement. A lambert::Error is a clean refusal; anything else (a crash, a
// sanitizer report, another exception, an internal check) is a bug.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/obj_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool quiet = (lambert::set_log_level(lambert::LogLevel::Quiet), true);
  (void)quiet;
  const std::string all(reinterpret_cast<const char*>(data), size);
  const std::string sep = "\n#MTL\n";
  const std::size_t at = all.find(sep);
  std::istringstream obj(all.substr(0, at));
  const std::string mtl = at == std::string::npos ? std::string() : all.substr(at + sep.size());
  const lambert::MtlOpener open = [&](const std::string& lib) {
    if (at == std::string::npos || lib == "missing.mtl") return lambert::MtlFile{};
    return lambert::MtlFile{std::make_unique<std::istringstream>(mtl), "fuzz.mtl"};
  };
  lambert::LoadOptions options;
  options.strict = size % 2 == 1;  // both the defaulting and the strict paths
  try {
    lambert::load_obj_stream(obj, "fuzz.obj", open, nullptr, options);
  } catch (const lambert::Error&) {
  }
  return 0;
}
