// The checks every command makes before any work: no output may overwrite an input or
// another output, every output folder must accept a file, floating-point options must be
// finite, and the job's estimated memory must fit. Each refusal exits with its documented
// code, names the file or option, and leaves every file as it was.

#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "io/obj_loader.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;
using testing::run;
using testing::run_capturing;
using testing::slurp;

// Every file of a folder (recursively) with its content.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files[e.path().string()] = slurp(e.path().string());
  return files;
}

// A temp folder holding a copy of the Cornell box (OBJ, MTL, camera sidecar), a small F of
// it and a per-patch radiosity CSV.
class JobChecks : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const auto& e : fs::directory_iterator(fs::path(builtin_cornell_box_path()).parent_path()))
      fs::copy(e.path(), dir_.path() / e.path().filename());
    fs::create_directories(dir_.path() / "a");
    ASSERT_EQ(run({"formfactors", obj(), "-q", "--patches", "60", "--samples", "4", "-o",
                   file("F.bin")}),
              kExitOk);
    ASSERT_EQ(run({"solve", obj(), "-q", "--ff", file("F.bin"), "--patches", "60", "-o",
                   file("B.csv")}),
              kExitOk);
  }
  std::string file(const std::string& name) const { return dir_.file(name); }
  std::string obj() const { return file("cornell_box.obj"); }

  // Runs a command that must be refused with `code` before writing anything, naming `what`.
  void expect_refused(const std::vector<std::string>& args, int code, const std::string& what) {
    const auto before = snapshot(dir_.path());
    const auto [got, err] = run_capturing(args);
    EXPECT_EQ(got, code) << err;
    EXPECT_NE(err.find(what), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << "one line: " << err;
    EXPECT_EQ(snapshot(dir_.path()), before) << "a file was created or changed: " << err;
  }

  testing::TempDir dir_;
};

TEST_F(JobChecks, OutputOntoTheSceneOrItsMaterialLibraryIsRefused) {
  expect_refused({"formfactors", obj(), "-q", "-o", obj()}, kExitUsage, obj());
  expect_refused({"formfactors", obj(), "-q", "-o", file("cornell_box.mtl")}, kExitUsage,
                 "cornell_box.mtl");
  expect_refused({"formfactors", obj(), "-q", "-o", file("F2.bin"), "--report", obj()},
                 kExitUsage, obj());
  expect_refused({"solve", obj(), "-q", "-o", file("cornell_box.camera")}, kExitUsage,
                 "camera sidecar");
}

TEST_F(JobChecks, PathsAreComparedCanonically) {
  const std::string roundabout = (dir_.path() / "a" / ".." / "cornell_box.obj").string();
  expect_refused({"formfactors", obj(), "-q", "-o", roundabout}, kExitUsage, roundabout);
}

TEST_F(JobChecks, OutputOntoALoadedFileIsRefused) {
  expect_refused({"solve", obj(), "-q", "--patches", "60", "--ff", file("F.bin"), "-o",
                  file("F.bin")},
                 kExitUsage, "--ff");
  expect_refused({"render", obj(), "-q", "--patches", "60", "--radiosity", file("B.csv"), "-o",
                  file("B.csv")},
                 kExitUsage, "--radiosity");
  // solve writes B.json beside B.csv: the summary may not overwrite the loaded F either.
  expect_refused({"solve", obj(), "-q", "--patches", "60", "--ff", file("F.json"), "-o",
                  file("F.csv")},
                 kExitUsage, "F.json");
}

TEST_F(JobChecks, TwoOutputsOnOneFileAreRefused) {
  expect_refused({"render", obj(), "-q", "-o", file("r.exr"), "--vertex-exr", file("r.exr")},
                 kExitUsage, "r.exr");
  expect_refused({"render", obj(), "-q", "-o", file("r.exr"), "--png", file("a/../r.exr")},
                 kExitUsage, "--png");
}

TEST_F(JobChecks, UnwritableOutputFolderIsRefusedBeforeWork) {
  // /proc accepts no new files, even for root (a chmod'ed folder would not stop root).
  expect_refused({"solve", obj(), "-q", "-o", "/proc/lambert_B.csv"}, kExitFailure,
                 "/proc/lambert_B.csv");
  expect_refused({"run", obj(), "-q", "-o", "/proc/self"}, kExitFailure, "/proc/self");
}

TEST_F(JobChecks, NonFiniteFloatingPointOptionsAreUsageErrors) {
  const std::vector<std::vector<std::string>> cases = {
      {"info", "--max-edge", "nan"},          {"info", "--max-edge", "inf"},
      {"solve", "--tol", "nan"},              {"solve", "--omega", "nan"},
      {"solve", "--threshold", "nan"},        {"compare", "--tol", "inf"},
      {"render", "--fov", "nan"},             {"render", "--eye", "nan", "0", "0"},
      {"render", "--look-at", "0", "inf", "0"}, {"render", "--up", "0", "0", "nan"},
      {"formfactors", "--point", "nan,0,0", "--normal", "0,0,1"},
      {"formfactors", "--normal", "0,inf,1", "--point", "0,0,0"},
      {"info", "--max-reflectance", "nan"},   {"run", "--exposure", "nan"},
  };
  for (auto args : cases) {
    const std::string option = args[1];
    args.insert(args.begin() + 1, obj());
    args.push_back("-q");
    expect_refused(args, kExitUsage, option);
  }
}

TEST_F(JobChecks, RangeMessagesAreShortAndRight) {
  const auto [code, err] = run_capturing({"info", obj(), "--max-edge", "-1"});
  EXPECT_EQ(code, kExitUsage);
  EXPECT_NE(err.find("> 0"), std::string::npos) << err;
  EXPECT_LT(err.size(), 120u) << "no 309-digit DBL_MAX: " << err;
  const auto [tol_code, tol_err] = run_capturing({"solve", obj(), "--tol", "nan"});
  EXPECT_EQ(tol_code, kExitUsage);
  EXPECT_NE(tol_err.find("[1e-16, 0.5]"), std::string::npos) << tol_err;
}

TEST_F(JobChecks, JobsBeyondTheMemoryLimitAreRefused) {
  // The documented maximum mesh: about 1e8 x 456 bytes (mesh_peak_bytes) = 42 GiB > 1 GiB.
  expect_refused({"info", obj(), "-q", "--patches", "100000000", "--max-memory", "1G"},
                 kExitUsage, "--max-memory");
  // 20000 patches with hybrid: F's all-pairs bound 2e8 pairs x 32 bytes = 6 GiB > 1 GiB.
  expect_refused({"formfactors", obj(), "-q", "--patches", "20000", "--estimator", "hybrid",
                  "--max-memory", "1G", "-o", file("F3.bin")},
                 kExitUsage, "form factors");
  // The same with auto (gather there): 2 x 20000 x 1024 entries x 16 bytes = 655 MB > 256 MiB.
  expect_refused({"formfactors", obj(), "-q", "--patches", "20000", "--max-memory", "256M", "-o",
                  file("F3.bin")},
                 kExitUsage, "form factors");
  ::setenv("LAMBERT_MAX_MEMORY", "1M", 1);
  expect_refused({"solve", obj(), "-q", "--patches", "2000", "-o", file("B2.csv")}, kExitUsage,
                 "LAMBERT_MAX_MEMORY");
  ::unsetenv("LAMBERT_MAX_MEMORY");
  expect_refused({"info", obj(), "-q", "--max-memory", "lots"}, kExitUsage, "lots");
}

TEST_F(JobChecks, MemoryLimitZeroTurnsTheCheckOff) {
  ::setenv("LAMBERT_MAX_MEMORY", "1K", 1);
  EXPECT_EQ(run({"info", obj(), "-q", "--patches", "60", "--max-memory", "0"}), kExitOk);
  // A size in plain bytes ("B" suffix) is a size: 512B is far too small, so refused as such.
  expect_refused({"info", obj(), "-q", "--patches", "60", "--max-memory", "512B"}, kExitUsage,
                 "needs about");
  ::unsetenv("LAMBERT_MAX_MEMORY");
}

TEST_F(JobChecks, RunReportListsItsOwnFilesAndStaleTemporariesGo) {
  const fs::path out = dir_.path() / "out";
  fs::create_directories(out);
  // What an interrupted run leaves: a temporary of a process that no longer runs (pid
  // 999999999 is above Linux's pid_max of at most 2^22).
  const std::string stale = (out / ".first.exr.tmp.999999999.exr").string();
  std::ofstream(stale) << "partial";
  const std::vector<std::string> fast = {"-q", "--patches", "60", "--samples", "4", "--size",
                                         "16x12", "-o", out.string()};
  std::vector<std::string> first = {"run", obj(), "--name", "first"}, second = first;
  second[3] = "second";
  first.insert(first.end(), fast.begin(), fast.end());
  second.insert(second.end(), fast.begin(), fast.end());
  ASSERT_EQ(run(first), kExitOk);
  EXPECT_FALSE(fs::exists(stale));
  ASSERT_EQ(run(second), kExitOk);
  const auto report = nlohmann::json::parse(slurp((out / "report.json").string()));
  std::vector<std::string> files;
  for (const auto& f : report.at("files")) files.push_back(fs::path(f.get<std::string>()).filename());
  EXPECT_EQ(files,
            (std::vector<std::string>{"second.exr", "second.png", "second_vertices.exr",
                                      "second.ply", "second.glb", "index.html", "report.json"}));
}

}  // namespace
}  // namespace lambert
