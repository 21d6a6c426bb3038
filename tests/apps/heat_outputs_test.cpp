// Where `heat` and `solve` write: -o FILE.csv is the table itself, --patches-csv, a device or
// pipe target with nothing beside it, and a folder that -o DIR/ creates taking the other
// outputs. Regression tests of issue 36 (item 4): each failed on the earlier code.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;
using testing::run;
using testing::run_capturing;
using testing::slurp;
using testing::TempDir;

// A closed 1 x 1 x 0.5 box: floor "hot", ceiling "cold", four "walls", one quad each.
std::string box_obj() {
  return "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 0.5\nv 1 0 0.5\nv 1 1 0.5\nv 0 1 0.5\n"
         "g hot\nf 1 2 3 4\ng cold\nf 5 8 7 6\n"
         "g walls\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";
}

std::vector<std::string> heat_args(const TempDir& dir) {
  return {"heat",
          dir.write("box.obj", box_obj()),
          "--surfaces",
          dir.write("s.json", R"({"hot": {"emissivity": 0.8, "temperature": 900},
                                        "*": {"emissivity": 0.5, "temperature": 300}})"),
          "--patches",
          "24",
          "-q"};
}

// The names in `dir`, sorted.
std::vector<std::string> listing(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// Drains a FIFO on a thread while a command writes into it (opened before, non-blocking, so
// that the writer's open does not wait for a reader).
class FifoReader {
 public:
  explicit FifoReader(const std::string& path)
      : fd_(::open(path.c_str(), O_RDONLY | O_NONBLOCK)), thread_([this] { loop(); }) {}
  ~FifoReader() {
    if (thread_.joinable()) finish();
  }
  std::string finish() {
    stop_ = true;
    thread_.join();
    ::close(fd_);
    return text_;
  }

 private:
  void loop() {
    char buf[4096];
    for (;;) {
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n > 0) {
        text_.append(buf, static_cast<size_t>(n));
      } else if (stop_) {
        return;
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    }
  }
  int fd_;
  std::atomic<bool> stop_{false};
  std::string text_;
  std::thread thread_;
};

TEST(HeatOutputs, CsvOutputIsTheSurfaceTableAndPatchesCsvThePatchTable) {
  const TempDir dir;
  auto args = heat_args(dir);
  args.insert(args.end(), {"-o", dir.file("r.csv")});
  ASSERT_EQ(run(args), kExitOk);
  // Was r.csv_surfaces.csv, r.csv_patches.csv and r.csv.json.
  EXPECT_EQ(listing(dir.path()),
            (std::vector<std::string>{"box.obj", "r.csv", "r.json", "s.json"}));
  EXPECT_EQ(slurp(dir.file("r.csv")).rfind("surface,emissivity,condition,", 0), 0u);
  EXPECT_EQ(testing::read_json(dir.file("r.json"))["surfaces"].size(), 3u);
  args.insert(args.end(), {"--patches-csv", dir.file("p.csv")});
  ASSERT_EQ(run(args), kExitOk);
  EXPECT_EQ(slurp(dir.file("p.csv")).rfind("patch,surface,area_m2,", 0), 0u);
}

TEST(HeatOutputs, VtuOutputIsTheVtuWithItsSummaryAndNoSurfaceCsv) {
  const TempDir dir;
  auto args = heat_args(dir);
  args.insert(args.end(), {"-o", dir.file("r.vtu")});
  ASSERT_EQ(run(args), kExitOk);
  EXPECT_EQ(listing(dir.path()),
            (std::vector<std::string>{"box.obj", "r.json", "r.vtu", "s.json"}));
  EXPECT_NE(slurp(dir.file("r.vtu")).find("<VTKFile type=\"UnstructuredGrid\""),
            std::string::npos);  // the structure: tests/io/vtu_test.cpp, the values: pytest
  EXPECT_EQ(testing::read_json(dir.file("r.json"))["surfaces"].size(), 3u);
  args.insert(args.end(), {"--patches-csv", dir.file("p.csv")});
  ASSERT_EQ(run(args), kExitOk);
  EXPECT_EQ(slurp(dir.file("p.csv")).rfind("patch,surface,area_m2,", 0), 0u);
}

TEST(HeatOutputs, APrefixKeepsItsThreeFilesAndPatchesCsvMovesOne) {
  const TempDir dir;
  auto args = heat_args(dir);
  args.insert(args.end(), {"-o", dir.file("x"), "--patches-csv", dir.file("p.csv")});
  ASSERT_EQ(run(args), kExitOk);
  EXPECT_EQ(listing(dir.path()),
            (std::vector<std::string>{"box.obj", "p.csv", "s.json", "x.json", "x_surfaces.csv"}));
}

TEST(HeatOutputs, AFolderThatOutputCreatesTakesEveryOtherOutput) {
  const TempDir dir;
  auto args = heat_args(dir);
  const std::string out = dir.file("new/sub") + "/";
  args.insert(args.end(), {"-o", out, "--ply", out + "h.ply", "--image", out + "t.png", "--size",
                           "32x24", "--conductors", out + "gr.csv", "--patches-csv", out + "p.csv",
                           "--vertex-exr", out + "v.exr"});
  const auto [code, err] = run_capturing(args);  // was refused: "directory does not exist"
  ASSERT_EQ(code, kExitOk) << err;
  EXPECT_EQ(listing(out),
            (std::vector<std::string>{"gr.csv", "h.ply", "heat.json", "heat_surfaces.csv", "p.csv",
                                      "t.png", "v.exr"}));
}

TEST(HeatOutputs, PictureOptionsWithoutAPictureAreRefused) {
  // The camera options set --image's and --glb's camera, --image-quantity what --image and
  // --ply colour: without those outputs nothing reads them (they were silently ignored).
  TempDir dir;
  const std::vector<std::vector<std::string>> unread = {
      {"--eye", "1", "2", "3"}, {"--fov", "30"}, {"--size", "64x64"}, {"--image-quantity", "flux"}};
  for (const auto& extra : unread) {
    std::vector<std::string> args = heat_args(dir);
    args.insert(args.end(), {"-o", dir.file("h.csv")});
    args.insert(args.end(), extra.begin(), extra.end());
    const auto [code, err] = run_capturing(args);
    EXPECT_EQ(code, kExitUsage) << extra[0] << ": " << err;
    EXPECT_NE(err.find(extra[0] + " does not apply to heat"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir.file("h.csv"))) << extra[0];
  }
  // With the picture that reads them they are accepted.
  std::vector<std::string> args = heat_args(dir);
  args.insert(args.end(), {"-o", dir.file("h.csv"), "--glb", dir.file("h.glb"), "--eye", "0.5",
                           "0.5", "2", "--ply", dir.file("h.ply"), "--image-quantity", "flux"});
  EXPECT_EQ(run(args), kExitOk);
  EXPECT_TRUE(fs::exists(dir.file("h.glb")) && fs::exists(dir.file("h.ply")));
}

TEST(HeatOutputs, AnOutputIntoAFolderNobodyCreatesIsRefusedBeforeAnyFolderIsMade) {
  const TempDir dir;
  auto args = heat_args(dir);
  args.insert(args.end(), {"-o", dir.file("made") + "/", "--ply", dir.file("nowhere/h.ply")});
  const auto [code, err] = run_capturing(args);
  EXPECT_EQ(code, kExitUsage);
  EXPECT_NE(err.find("(--ply): directory '"), std::string::npos) << err;
  EXPECT_NE(err.find("nowhere' does not exist"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir.file("made")));  // the plan's folder is made once it is checked
}

TEST(HeatOutputs, APipeTargetGetsTheTableAndNothingBesideIt) {
  const TempDir dir;
  const std::string fifo = dir.file("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  auto args = heat_args(dir);
  args.insert(args.end(), {"-o", fifo});
  FifoReader reader(fifo);
  ASSERT_EQ(run(args), kExitOk);
  const std::string text = reader.finish();
  EXPECT_EQ(text.rfind("surface,emissivity,condition,", 0), 0u) << text;
  EXPECT_TRUE(fs::is_fifo(fifo));  // not replaced by a renamed temporary
  EXPECT_EQ(listing(dir.path()), (std::vector<std::string>{"box.obj", "pipe", "s.json"}));
}

TEST(SolveOutputs, APipeTargetGetsTheTableAndNoSummaryBesideIt) {
  // `solve -o /dev/null` wrote /dev/null.json (and, run as root, renamed its temporary over
  // the device); a FIFO is a device-like target any user can make.
  const TempDir dir;
  const std::string fifo = dir.file("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  FifoReader reader(fifo);
  ASSERT_EQ(run({"solve", "--patches", "40", "-o", fifo, "-q"}), kExitOk);
  const std::string text = reader.finish();
  EXPECT_EQ(text.rfind("patch,surface,area,R,G,B\n", 0), 0u) << text;
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_EQ(listing(dir.path()), (std::vector<std::string>{"pipe"}));
}

}  // namespace
}  // namespace lambert
