#pragma once
// Atomic file output: content goes to a temporary file in the same directory, which is
// renamed over the destination only when complete. An interrupted or failed write leaves
// any previous file untouched and no partial file behind.

#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace lambert {

/// The temporary for a file NAME is ".NAME.tmp.PID.EXT" in the same directory (PID: the
/// writing process, EXT: NAME's extension). An interrupted process leaves it behind; the
/// first write of a later process into that directory removes it (remove_stale_temporaries).

/// The process id in a temporary file name of ours, nullopt for any other name.
std::optional<long> stale_temporary_pid(const std::string& file_name);

/// Removes the regular files in `directory` named like our temporaries whose process is no
/// longer running (never this process's, nor a live one's). Errors are ignored.
void remove_stale_temporaries(const std::string& directory);

/// True for an existing file that is neither a regular file nor a folder: a device such as
/// /dev/null or /dev/stdout, or a pipe. Such a file is written in place (it cannot be
/// replaced, and renaming a temporary over /dev/null would destroy the device), and a
/// command writes nothing beside it (no summary named after it).
bool writes_in_place(const std::string& path);

/// Calls write(tmp_path) to produce the file, then renames tmp_path to `path`.
/// On any exception the temporary is removed and the exception propagates.
/// A `path` that writes_in_place is written directly (write(path)), outside any OutputSet.
void write_atomically(const std::string& path,
                      const std::function<void(const std::string& tmp_path)>& write);

/// Convenience: writes a text/binary stream atomically; throws IoError on failure.
void write_stream_atomically(const std::string& path,
                             const std::function<void(std::ostream& out)>& write,
                             bool binary = false);

/// The files of one command, replaced as a set. While an OutputSet is open on a thread,
/// write_atomically there writes each file's temporary only. commit() then writes a journal
/// listing the renames, ".lambert-commit.PID", into every folder the set writes to (the
/// commit point), renames, and removes the journals. Killed before the commit point, the
/// previous files all stay (the temporaries go with the next write there, as above); killed
/// after it, the next write into any of those folders finishes the renames first
/// (finish_interrupted_commits). Destroyed without commit(), the set's temporaries are removed.
class OutputSet {
 public:
  OutputSet();
  ~OutputSet();
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  /// Renames every staged temporary to its file. `after_rename(k)` (tests) runs after the
  /// k-th rename. Throws IoError when a rename fails.
  void commit(const std::function<void(std::size_t)>& after_rename = {});
  /// Files staged so far, in order.
  std::vector<std::string> files() const;

 private:
  friend void write_atomically(const std::string&, const std::function<void(const std::string&)>&);
  struct Staged {
    std::string tmp, path;
  };
  std::vector<Staged> staged_;
  OutputSet* outer_;
  bool committed_ = false;
};

/// Finishes the renames of journals in `directory` left by processes that are no longer
/// running, and removes those journals. Errors are ignored.
void finish_interrupted_commits(const std::string& directory);

}  // namespace lambert
