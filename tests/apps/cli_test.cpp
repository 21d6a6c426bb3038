#include "apps/cli.hpp"
#include "common/run_cli.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace lambert {

using testing::run;
using testing::slurp;
namespace {
}  // namespace

TEST(Cli, HelpAndVersionSucceed) {
  EXPECT_EQ(run({"--help"}), kExitOk);
  EXPECT_EQ(run({"--version"}), kExitOk);
}

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run({}), kExitUsage);
  EXPECT_EQ(run({"frobnicate"}), kExitUsage);
  EXPECT_EQ(run({"info", "--no-such-option"}), kExitUsage);
  EXPECT_EQ(run({"info", "--patches", "-5"}), kExitUsage);
  EXPECT_EQ(run({"info", "--patches", "10", "--max-edge", "3"}), kExitUsage);
}

TEST(Cli, InfoDescribesTheBuiltInCornellBox) {
  ::testing::internal::CaptureStdout();
  const int code = run({"info", "-q", "--patches", "500"});
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, kExitOk);
  EXPECT_NE(out.find("tall_block"), std::string::npos);
  EXPECT_NE(out.find("emitters: light"), std::string::npos);
}

TEST(Cli, MissingSceneExitsWithOne) {
  EXPECT_EQ(run({"info", "-q", "/nonexistent.obj"}), kExitFailure);
}

}  // namespace lambert
