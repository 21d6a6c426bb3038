#include "io/json.hpp"

#include "core/atomic_file.hpp"

namespace lambert {

std::string json_text(const Json& j) {
  // nlohmann's serializer writes NaN and +-Inf as null.
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + '\n';
}

void write_json_file(const std::string& path, const Json& j) {
  const std::string text = json_text(j);
  write_stream_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace lambert
