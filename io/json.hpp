#pragma once
// JSON reports and summaries through nlohmann-json: the document type every report is built
// as, its text form and the atomic file writer.

#include <nlohmann/json.hpp>
#include <string>

namespace lambert {

/// A JSON document whose object keys keep their insertion order (reports read top-down).
using Json = nlohmann::ordered_json;

/// The text of `j`: indented by 2, with a final newline. Non-finite numbers become null (JSON
/// has no NaN/Inf); invalid UTF-8 in strings (e.g. a Latin-1 file name) is replaced by U+FFFD
/// instead of throwing.
std::string json_text(const Json& j);

/// Writes json_text(j) to `path` atomically (temp name in the same folder, then rename).
void write_json_file(const std::string& path, const Json& j);

}  // namespace lambert
