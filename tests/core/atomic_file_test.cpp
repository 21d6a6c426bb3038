#include "core/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "common/temp_dir.hpp"
#include "core/error.hpp"

namespace lambert {

namespace {
std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

TEST(AtomicFile, FailedWriteKeepsTheOldFileAndLeavesNoTemporary) {
  testing::TempDir dir;
  const std::string path = dir.write("out.txt", "old");
  EXPECT_THROW(write_stream_atomically(path,
                                       [](std::ostream& out) {
                                         out << "partial";
                                         throw std::runtime_error("interrupted");
                                       }),
               std::runtime_error);
  EXPECT_EQ(slurp(path), "old");
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) (void)e, ++files;
  EXPECT_EQ(files, 1);
}

TEST(AtomicFile, CompleteWriteReplacesTheFile) {
  testing::TempDir dir;
  const std::string path = dir.write("out.txt", "old");
  write_stream_atomically(path, [](std::ostream& out) { out << "new"; });
  EXPECT_EQ(slurp(path), "new");
}

TEST(AtomicFile, MissingDirectoryIsAnIoError) {
  testing::TempDir dir;
  EXPECT_THROW(write_stream_atomically(dir.file("nope/out.txt"), [](std::ostream&) {}), IoError);
}

TEST(AtomicFile, TemporaryNamesAreRecognisedExactly) {
  EXPECT_EQ(stale_temporary_pid(".B.csv.tmp.123.csv"), 123);
  EXPECT_EQ(stale_temporary_pid(".F.tmp.77"), 77);  // no extension
  EXPECT_FALSE(stale_temporary_pid(".B.csv.tmp.123.exr"));  // extension does not match
  EXPECT_FALSE(stale_temporary_pid("B.csv.tmp.123.csv"));   // not hidden
  EXPECT_FALSE(stale_temporary_pid(".B.csv.tmp..csv"));     // no pid
  EXPECT_FALSE(stale_temporary_pid(".notes.txt"));
}

TEST(AtomicFile, WritingIntoAFolderRemovesTemporariesOfDeadProcessesOnly) {
  testing::TempDir dir;
  // A pid that is certainly dead: a child that has exited and been reaped.
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);
  const std::string dead = dir.write(".B.csv.tmp." + std::to_string(child) + ".csv", "stale");
  const std::string live = dir.write(".B.csv.tmp." + std::to_string(::getppid()) + ".csv", "x");
  const std::string other = dir.write(".B.csv.tmp.old.csv", "not ours");
  write_stream_atomically(dir.file("report.json"), [](std::ostream& out) { out << "{}"; });
  EXPECT_FALSE(std::filesystem::exists(dead));
  EXPECT_TRUE(std::filesystem::exists(live));   // its process may still be writing
  EXPECT_TRUE(std::filesystem::exists(other));  // not our naming
  EXPECT_EQ(slurp(dir.file("report.json")), "{}");
}

// --- OutputSet: a command's files replaced as one set ---

namespace {
// Writes "<tag>" into a.csv, b.exr and sub/c.json of `dir` inside an open set.
void write_three(const testing::TempDir& dir, const std::string& tag) {
  for (const char* f : {"a.csv", "b.exr", "sub/c.json"})
    write_stream_atomically(dir.file(f), [&](std::ostream& out) { out << tag; });
}

std::vector<std::string> contents(const testing::TempDir& dir) {
  return {slurp(dir.file("a.csv")), slurp(dir.file("b.exr")), slurp(dir.file("sub/c.json"))};
}

// Names in `dir` and `dir/sub` other than the three files: temporaries and journals.
std::vector<std::string> leftovers(const testing::TempDir& dir) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir.path())) {
    const std::string name = e.path().filename().string();
    if (name != "a.csv" && name != "b.exr" && name != "c.json" && name != "sub")
      out.push_back(name);
  }
  return out;
}

// Runs `body` in a child process that kills itself with SIGKILL where body says so.
void in_killed_child(const std::function<void()>& body) {
  const pid_t child = ::fork();
  if (child == 0) {
    body();
    ::_exit(0);  // body did not kill: the test sees exit 0 and fails
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
}

// The previous run's set, written by another process: a process finishes interrupted
// commits and removes dead temporaries on its first write into a folder only, so this one
// must not have written there yet.
void old_set(const testing::TempDir& dir) {
  std::filesystem::create_directory(dir.file("sub"));
  const pid_t child = ::fork();
  if (child == 0) {
    write_three(dir, "old");
    ::_exit(0);
  }
  ::waitpid(child, nullptr, 0);
}

// This process's first write into the folder of `path`.
void first_write(const std::string& path) {
  write_stream_atomically(path, [](std::ostream& out) { out << "x"; });
}
}  // namespace

TEST(OutputSet, FilesAppearOnlyAtCommitAndAllTogether) {
  const testing::TempDir dir;
  old_set(dir);
  OutputSet set;
  write_three(dir, "new");
  EXPECT_EQ(contents(dir), (std::vector<std::string>{"old", "old", "old"}));
  EXPECT_EQ(set.files().size(), 3u);
  set.commit();
  EXPECT_EQ(contents(dir), (std::vector<std::string>{"new", "new", "new"}));
  EXPECT_TRUE(leftovers(dir).empty());
}

TEST(OutputSet, AnAbandonedSetLeavesThePreviousFilesAndNoTemporary) {
  const testing::TempDir dir;
  old_set(dir);
  {
    OutputSet set;
    write_three(dir, "new");
  }  // an exception unwinding a command
  EXPECT_EQ(contents(dir), (std::vector<std::string>{"old", "old", "old"}));
  EXPECT_TRUE(leftovers(dir).empty());
}

TEST(OutputSet, ATargetThatIsAFolderFailsTheWholeSetBeforeAnyRename) {
  const testing::TempDir dir;
  old_set(dir);
  std::filesystem::create_directory(dir.file("d.png"));
  OutputSet set;
  write_three(dir, "new");
  write_stream_atomically(dir.file("d.png"), [](std::ostream& out) { out << "png"; });
  EXPECT_THROW(set.commit(), IoError);
  EXPECT_EQ(contents(dir), (std::vector<std::string>{"old", "old", "old"}));
}

TEST(OutputSet, KilledBeforeTheCommitPointThePreviousSetStays) {
  const testing::TempDir dir;
  old_set(dir);
  in_killed_child([&] {
    OutputSet set;
    write_three(dir, "new");
    ::raise(SIGKILL);
  });
  EXPECT_EQ(contents(dir), (std::vector<std::string>{"old", "old", "old"}));
  EXPECT_EQ(leftovers(dir).size(), 3u);  // the dead process's temporaries
  // The next write into each folder removes them.
  first_write(dir.file("other.txt"));
  first_write(dir.file("sub/other.txt"));
  EXPECT_EQ(leftovers(dir), (std::vector<std::string>{"other.txt", "other.txt"}));
  EXPECT_EQ(contents(dir), (std::vector<std::string>{"old", "old", "old"}));
}

TEST(OutputSet, KilledBetweenRenamesTheNextWriteFinishesTheSet) {
  for (const char* where : {"sub/other.txt", "other.txt"}) {  // from either folder
    const testing::TempDir dir;
    old_set(dir);
    in_killed_child([&] {
      OutputSet set;
      write_three(dir, "new");
      set.commit([](std::size_t k) {
        if (k == 0) ::raise(SIGKILL);
      });
    });
    // Between the renames the set is mixed, and the journals say how to finish it.
    EXPECT_EQ(contents(dir), (std::vector<std::string>{"new", "old", "old"}));
    // The next lambert process to write into either folder finishes the renames first.
    first_write(dir.file(where));
    EXPECT_EQ(contents(dir), (std::vector<std::string>{"new", "new", "new"})) << where;
    EXPECT_EQ(leftovers(dir), std::vector<std::string>{"other.txt"}) << where;
  }
}

TEST(OutputSet, AForeignFileNamedLikeAJournalIsLeftAlone) {
  const testing::TempDir dir;
  const pid_t child = ::fork();  // a dead pid
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  const std::string name = dir.write(".lambert-commit." + std::to_string(child), "not a journal");
  finish_interrupted_commits(dir.path());
  EXPECT_EQ(slurp(name), "not a journal");
}

}  // namespace lambert
