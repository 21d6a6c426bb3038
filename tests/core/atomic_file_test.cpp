#include "core/atomic_file.hpp"

#include <gtest/gtest.h>

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

}  // namespace lambert
