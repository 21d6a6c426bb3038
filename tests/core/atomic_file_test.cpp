#include "core/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

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

}  // namespace lambert
