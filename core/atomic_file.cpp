#include "core/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

#include "core/error.hpp"

namespace lambert {
namespace {

constexpr const char* kTmpTag = ".tmp.";
constexpr const char* kJournalPrefix = ".lambert-commit.";
constexpr const char* kJournalHeader = "lambert commit 1";

// ".NAME.tmp.PID.EXT" for the file NAME (EXT: NAME's extension, kept last for the writers
// that look at it).
std::string temporary_name(const std::string& name, const std::string& pid) {
  return "." + name + kTmpTag + pid + std::filesystem::path(name).extension().string();
}

thread_local OutputSet* open_set = nullptr;

// Renames tmp over path; on failure removes tmp and throws IoError naming path.
void rename_into_place(const std::string& tmp, const std::string& path) {
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw IoError(path + ": cannot write: " + why);
  }
}

bool process_is_dead(long pid) {
  return pid != ::getpid() && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

// Writes `content` to `path` through a temporary and a rename (never staged in a set).
void write_now(const std::string& path, const std::string& content) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const std::string tmp = (target.parent_path() /
                           temporary_name(target.filename().string(), std::to_string(::getpid())))
                              .string();
  {
    std::ofstream out(tmp, std::ios::binary);
    out << content;
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw IoError(path + ": cannot write: " + std::strerror(errno));
    }
  }
  rename_into_place(tmp, path);
}

// Journal: the header, then the count of renames, each as two length-prefixed paths
// (temporary, file), then the count of journal copies and their paths. Length prefixes keep
// any byte of a path.
void put_path(std::ostream& out, const std::string& p) { out << p.size() << ' ' << p << '\n'; }

bool get_path(std::istream& in, std::string& p) {
  std::size_t n = 0;
  if (!(in >> n) || in.get() != ' ' || n > 1 << 16) return false;
  p.assign(n, '\0');
  return static_cast<bool>(in.read(p.data(), static_cast<std::streamsize>(n))) && in.get() == '\n';
}

// The renames and journal copies a journal lists; false when it cannot be read.
bool read_journal(const std::string& path,
                  std::vector<std::pair<std::string, std::string>>& renames,
                  std::vector<std::string>& journals) {
  std::ifstream in(path, std::ios::binary);
  std::string header;
  std::size_t n = 0;
  if (!std::getline(in, header) || header != kJournalHeader || !(in >> n) || in.get() != '\n' ||
      n > 1 << 20)
    return false;
  renames.resize(n);
  for (auto& [tmp, file] : renames)
    if (!get_path(in, tmp) || !get_path(in, file)) return false;
  if (!(in >> n) || in.get() != '\n' || n > 1 << 20) return false;
  journals.resize(n);
  for (auto& j : journals)
    if (!get_path(in, j)) return false;
  return true;
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

bool writes_in_place(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  return !ec && fs::exists(st) && !fs::is_regular_file(st) && !fs::is_directory(st);
}

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
  namespace fs = std::filesystem;
  if (writes_in_place(path)) {  // a device or a pipe: nothing to stage, nothing to rename
    write(path);
    return;
  }
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw IoError(path + ": cannot write: directory '" + dir.string() + "' does not exist");
  }
  {  // once per directory and process: an interrupted run's commit is finished, its
     // temporaries go
    static std::mutex mutex;
    static std::set<std::string> cleaned;
    const std::lock_guard<std::mutex> lock(mutex);
    if (cleaned.insert(fs::absolute(dir, ec).string()).second) {
      finish_interrupted_commits(dir.string());
      remove_stale_temporaries(dir.string());
    }
  }
  const std::string tmp =
      (dir / temporary_name(target.filename().string(), std::to_string(::getpid()))).string();
  try {
    write(tmp);
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (open_set != nullptr) {  // renamed with the rest of the set
    const std::string abs_tmp = fs::absolute(tmp, ec).string();
    const std::string abs_path = fs::absolute(path, ec).string();
    for (const auto& s : open_set->staged_)
      if (s.tmp == abs_tmp) return;  // the same file written again: its temporary was replaced
    open_set->staged_.push_back({abs_tmp, abs_path});
    return;
  }
  rename_into_place(tmp, path);
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

OutputSet::OutputSet() : outer_(open_set) { open_set = this; }

OutputSet::~OutputSet() {
  open_set = outer_;
  if (!committed_)
    for (const auto& s : staged_) std::remove(s.tmp.c_str());
}

std::vector<std::string> OutputSet::files() const {
  std::vector<std::string> out;
  for (const auto& s : staged_) out.push_back(s.path);
  return out;
}

void OutputSet::commit(const std::function<void(std::size_t)>& after_rename) {
  namespace fs = std::filesystem;
  committed_ = true;
  if (staged_.empty()) return;
  std::error_code ec;
  for (const auto& s : staged_)  // the one rename failure that can be foreseen
    if (fs::is_directory(s.path, ec)) {
      for (const auto& t : staged_) std::remove(t.tmp.c_str());
      throw IoError(s.path + ": cannot write: it is a folder");
    }
  std::vector<std::string> journals;
  for (const auto& s : staged_) {
    const std::string j =
        (fs::path(s.path).parent_path() / (kJournalPrefix + std::to_string(::getpid()))).string();
    if (std::find(journals.begin(), journals.end(), j) == journals.end()) journals.push_back(j);
  }
  std::ostringstream text;
  text << kJournalHeader << '\n' << staged_.size() << '\n';
  for (const auto& s : staged_) {
    put_path(text, s.tmp);
    put_path(text, s.path);
  }
  text << journals.size() << '\n';
  for (const auto& j : journals) put_path(text, j);
  const auto drop = [&] {
    for (const auto& s : staged_) std::remove(s.tmp.c_str());
    for (const auto& j : journals) std::remove(j.c_str());
  };
  try {
    for (const auto& j : journals) write_now(j, text.str());  // the commit point
  } catch (...) {
    drop();
    throw;
  }
  for (std::size_t k = 0; k < staged_.size(); ++k) {
    if (std::rename(staged_[k].tmp.c_str(), staged_[k].path.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      drop();
      throw IoError(staged_[k].path + ": cannot write: " + why);
    }
    if (after_rename) after_rename(k);
  }
  for (const auto& j : journals) std::remove(j.c_str());
}

void finish_interrupted_commits(const std::string& directory) {
  namespace fs = std::filesystem;
  std::error_code ec;
  std::vector<fs::path> found;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(kJournalPrefix, 0) != 0) continue;
    const std::string pid = name.substr(std::strlen(kJournalPrefix));
    if (pid.empty() || pid.size() > 9 || pid.find_first_not_of("0123456789") != std::string::npos)
      continue;
    if (process_is_dead(std::stol(pid))) found.push_back(it->path());
  }
  for (const auto& journal : found) {
    std::vector<std::pair<std::string, std::string>> renames;
    std::vector<std::string> copies;
    if (!read_journal(journal.string(), renames, copies)) continue;  // not ours: left alone
    for (const auto& [tmp, file] : renames)
      if (fs::exists(tmp, ec)) std::rename(tmp.c_str(), file.c_str());
    for (const auto& j : copies) std::remove(j.c_str());
    fs::remove(journal, ec);
  }
}

}  // namespace lambert
