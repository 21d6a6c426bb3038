#pragma once
// Atomic file output: content goes to a temporary file in the same directory, which is
// renamed over the destination only when complete. An interrupted or failed write leaves
// any previous file untouched and no partial file behind.

#include <functional>
#include <ostream>
#include <string>

namespace lambert {

/// Calls write(tmp_path) to produce the file, then renames tmp_path to `path`.
/// On any exception the temporary is removed and the exception propagates.
void write_atomically(const std::string& path,
                      const std::function<void(const std::string& tmp_path)>& write);

/// Convenience: writes a text/binary stream atomically; throws IoError on failure.
void write_stream_atomically(const std::string& path,
                             const std::function<void(std::ostream& out)>& write,
                             bool binary = false);

}  // namespace lambert
