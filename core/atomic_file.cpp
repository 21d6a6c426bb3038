#include "core/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>

#include "core/error.hpp"

namespace lambert {
namespace {

constexpr const char* kTmpTag = ".tmp.";

// ".NAME.tmp.PID.EXT" for the file NAME (EXT: NAME's extension, kept last for the writers
// that look at it).
std::string temporary_name(const std::string& name, const std::string& pid) {
  return "." + name + kTmpTag + pid + std::filesystem::path(name).extension().string();
}

}  // namespace

std::optional<long> stale_temporary_pid(const std::string& file_name) {
  // The last ".tmp." splits ".NAME" from "PID.EXT"; the name must rebuild exactly.
  const auto tag = file_name.rfind(kTmpTag);
  if (file_name.size() < 2 || file_name[0] != '.' || tag == std::string::npos || tag < 2)
    return std::nullopt;
  const std::string name = file_name.substr(1, tag - 1);
  const std::string rest = file_name.substr(tag + std::strlen(kTmpTag));
  const auto digits = rest.find_first_not_of("0123456789");
  const std::string pid = rest.substr(0, digits);
  if (pid.empty() || pid.size() > 9 || temporary_name(name, pid) != file_name) return std::nullopt;
  return std::stol(pid);
}

void remove_stale_temporaries(const std::string& directory) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec)) {
    const auto pid = stale_temporary_pid(it->path().filename().string());
    if (!pid || *pid == ::getpid() || !it->is_regular_file(ec)) continue;
    // A live process (another lambert writing here, or a reused pid) keeps its file.
    if (::kill(static_cast<pid_t>(*pid), 0) == 0 || errno != ESRCH) continue;
    fs::remove(it->path(), ec);
  }
}

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw IoError(path + ": cannot write: directory '" + dir.string() + "' does not exist");
  }
  {  // once per directory and process: an interrupted run's temporaries go
    static std::mutex mutex;
    static std::set<std::string> cleaned;
    const std::lock_guard<std::mutex> lock(mutex);
    if (cleaned.insert(fs::absolute(dir, ec).string()).second) remove_stale_temporaries(dir.string());
  }
  const std::string tmp =
      (dir / temporary_name(target.filename().string(), std::to_string(::getpid()))).string();
  try {
    write(tmp);
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw IoError(path + ": cannot write: " + why);
  }
}

void write_stream_atomically(const std::string& path,
                             const std::function<void(std::ostream&)>& write, bool binary) {
  write_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, binary ? std::ios::binary : std::ios::out);
    if (!out) throw IoError(path + ": cannot open for writing: " + std::strerror(errno));
    write(out);
    out.flush();
    if (!out) throw IoError(path + ": write failed (disk full?)");
  });
}

}  // namespace lambert
