#pragma once
// Atomic file output: content goes to a temporary file in the same directory, which is
// renamed over the destination only when complete. An interrupted or failed write leaves
// any previous file untouched and no partial file behind.

#include <functional>
#include <optional>
#include <ostream>
#include <string>

namespace lambert {

/// The temporary for a file NAME is ".NAME.tmp.PID.EXT" in the same directory (PID: the
/// writing process, EXT: NAME's extension). An interrupted process leaves it behind; the
/// first write of a later process into that directory removes it (remove_stale_temporaries).

/// The process id in a temporary file name of ours, nullopt for any other name.
std::optional<long> stale_temporary_pid(const std::string& file_name);

/// Removes the regular files in `directory` named like our temporaries whose process is no
/// longer running (never this process's, nor a live one's). Errors are ignored.
void remove_stale_temporaries(const std::string& directory);

/// Calls write(tmp_path) to produce the file, then renames tmp_path to `path`.
/// On any exception the temporary is removed and the exception propagates.
void write_atomically(const std::string& path,
                      const std::function<void(const std::string& tmp_path)>& write);

/// Convenience: writes a text/binary stream atomically; throws IoError on failure.
void write_stream_atomically(const std::string& path,
                             const std::function<void(std::ostream& out)>& write,
                             bool binary = false);

}  // namespace lambert
