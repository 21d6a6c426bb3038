#include "apps/cli.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "apps/distributed.hpp"
#include "common/run_cli.hpp"

namespace lambert {

using testing::run;
using testing::slurp;
namespace {
}  // namespace

TEST(Cli, HelpAndVersionSucceed) {
  EXPECT_EQ(run({"--help"}), kExitOk);
  EXPECT_EQ(run({"--version"}), kExitOk);
}

// The default build has no MPI: --distributed is a usage error naming the MPI build, before
// any work (the MPI build's own tests are tests/mpi/*.sh under mpirun).
TEST(Cli, DistributedWithoutMpiIsAUsageError) {
  if (distributed_available()) GTEST_SKIP() << "built with LAMBERT_MPI";
  EXPECT_EQ(run({"formfactors", "--distributed", "--patches", "20", "-o", "F.bin"}), kExitUsage);
  EXPECT_EQ(run({"solve", "--distributed", "--patches", "20", "-o", "B.csv"}), kExitUsage);
  EXPECT_EQ(run({"run", "--distributed", "--patches", "20", "-o", "out"}), kExitUsage);
}

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run({}), kExitUsage);
  EXPECT_EQ(run({"frobnicate"}), kExitUsage);
  EXPECT_EQ(run({"info", "--no-such-option"}), kExitUsage);
  EXPECT_EQ(run({"info", "--patches", "-5"}), kExitUsage);
  EXPECT_EQ(run({"info", "--patches", "10", "--max-edge", "3"}), kExitUsage);
  // The floor is read under a patch target only (issue 35): not with an edge bound or
  // discontinuity meshing, which do not read it.
  EXPECT_EQ(run({"info", "--surface-floor", "8", "--max-edge", "3"}), kExitUsage);
  EXPECT_EQ(run({"info", "--surface-floor", "8", "--discontinuity"}), kExitUsage);
}

TEST(Cli, InfoDescribesTheBuiltInCornellBox) {
  ::testing::internal::CaptureStdout();
  const int code = run({"info", "-q", "--patches", "500"});
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, kExitOk);
  EXPECT_NE(out.find("tall_block"), std::string::npos);
  EXPECT_NE(out.find("emitters: light"), std::string::npos);
}

// Loading options are shared by every command that loads a scene (apps/options.cpp,
// pipeline/job.cpp).
TEST(Cli, SceneLoadingOptionsAreCheckedAndApplied) {
  const std::string room = std::string(LAMBERT_TEST_CORPUS_DIR) + "/obj/blender_room.obj";
  const std::string bare = std::string(LAMBERT_TEST_CORPUS_DIR) + "/obj/no_mtllib.obj";
  for (const char* bad : {"floor=nan,1,1", "floor=1,1", "floor=-1,0,0", "=1,1,1", "floor"})
    EXPECT_EQ(run({"info", "-q", bare, "--emit", bad}), kExitUsage) << bad;
  EXPECT_EQ(run({"info", "-q", bare, "--max-reflectance", "nan"}), kExitUsage);
  EXPECT_EQ(run({"info", "-q", bare, "--max-reflectance", "1.5"}), kExitUsage);
  EXPECT_EQ(run({"info", "-q", bare, "--default-reflectance", "0.5,nan,0.5"}), kExitUsage);
  EXPECT_EQ(run({"info", "-q", bare, "--default-reflectance", "0.5,1.5,0.5"}), kExitUsage);
  // A trailing comma is a fourth, empty value (getline used to drop it silently).
  EXPECT_EQ(run({"info", "-q", bare, "--default-reflectance", "0.5,0.5,0.5,"}), kExitUsage);
  EXPECT_EQ(run({"info", "-q", bare, "--emit", "nothing=1,1,1"}), kExitUsage);
  EXPECT_EQ(run({"info", "-q", bare, "--strict"}), kExitFailure);
  EXPECT_EQ(run({"formfactors", "-q", bare, "--strict", "-o", "/tmp/never.mtx"}), kExitFailure);
  ::testing::internal::CaptureStdout();
  const int code = run({"info", "-q", room, "--list-surfaces", "--emit", "Cube=1,1,1"});
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, kExitOk);
  EXPECT_EQ(out, "Room/Walls\tWalls\tno\nRoom/Red\tRed\tno\nCube\tMaterial\tyes\nLight\tEmission\tyes\n");
  EXPECT_EQ(run({"info", "-q", bare, "--emit", "floor=1,1,1", "--default-reflectance", "0.2,0.2,0.2",
                 "--max-reflectance", "0.9", "--patches", "10"}), kExitOk);
}

TEST(Cli, MissingSceneExitsWithOne) {
  EXPECT_EQ(run({"info", "-q", "/nonexistent.obj"}), kExitFailure);
}

}  // namespace lambert
