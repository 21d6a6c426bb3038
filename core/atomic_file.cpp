#include "core/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"

namespace lambert {

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw IoError(path + ": cannot write: directory '" + dir.string() + "' does not exist");
  }
  // Keep the real extension last: some writers (OpenEXR, PNG tools) look at it.
  const std::string tmp = (dir / ("." + target.filename().string() + ".tmp." +
                                  std::to_string(::getpid()) + target.extension().string()))
                              .string();
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
