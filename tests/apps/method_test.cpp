// The method level of the CLI (pipeline/method.*): --method matrix|hierarchical in run, solve,
// render and compare, and the refusal of every option that only the other method reads.
// Refusals happen before any work, so these tests are fast.

#include "pipeline/method.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"

namespace lambert {
namespace {

using testing::run;
using testing::run_capturing;

// An option with a valid value, and the commands that have it.
struct OptionCase {
  std::vector<std::string> args;
  std::vector<std::string> commands;
};

const std::vector<std::string> kMethodCommands = {"run", "solve", "render", "compare"};

// Every option of the matrix method, with a value its parser accepts (files need not exist:
// the refusal comes before anything is read).
const std::vector<OptionCase> kMatrixOptions = {
    {{"--patches", "100"}, kMethodCommands},
    {{"--max-edge", "50"}, kMethodCommands},
    {{"--estimator", "hybrid"}, kMethodCommands},
    {{"--samples", "4"}, kMethodCommands},
    {{"--rays", "64"}, kMethodCommands},
    {{"--threshold", "0.01"}, kMethodCommands},
    {{"--hemicube-res", "16"}, kMethodCommands},
    {{"--reciprocity", "none"}, kMethodCommands},
    {{"--symmetrize"}, kMethodCommands},
    {{"--ff", "F.bin"}, kMethodCommands},
    {{"--solver", "jacobi"}, {"run", "solve", "render"}},
    {{"--omega", "1.2"}, kMethodCommands},
    {{"--preconditioner", "none"}, kMethodCommands},
    {{"--restart", "10"}, kMethodCommands},
    {{"--ambient"}, kMethodCommands},
    {{"--radiosity", "B.csv"}, {"render"}},
    {{"--solvers", "jacobi"}, {"compare"}},
};

// The options compare --method hierarchical reads for its matrix reference.
bool sets_up_the_reference(const std::string& option) {
  const auto& p = find_method("matrix").problem_options;
  return std::find(p.begin(), p.end(), option) != p.end();
}

}  // namespace

TEST(MethodOption, TheRegistryNamesBothMethodsMatrixFirst) {
  EXPECT_EQ(method_names(), (std::vector<std::string>{"matrix", "hierarchical"}));
  // Every option the tests give a method belongs to exactly one registry row.
  for (const auto& c : kMatrixOptions) {
    int owners = 0;
    for (const Method& m : methods())
      for (const auto* list : {&m.problem_options, &m.solver_options})
        owners += static_cast<int>(std::count(list->begin(), list->end(), c.args[0]));
    EXPECT_EQ(owners, 1) << c.args[0];
  }
}

TEST(MethodOption, HierarchicalRefusesEveryMatrixOption) {
  testing::TempDir dir;
  for (const auto& c : kMatrixOptions)
    for (const auto& command : c.commands) {
      if (command == "compare" && sets_up_the_reference(c.args[0])) continue;
      std::vector<std::string> args = {command, "--method", "hierarchical", "-q"};
      args.insert(args.end(), c.args.begin(), c.args.end());
      const std::string out = command == "compare" ? dir.file("cmp") : dir.file("o");
      args.insert(args.end(), {"-o", command == "render" ? out + ".exr" : out});
      const auto [code, err] = run_capturing(args);
      EXPECT_EQ(code, kExitUsage) << command << ' ' << c.args[0];
      EXPECT_NE(err.find(c.args[0] + " does not apply to --method hierarchical"), std::string::npos)
          << err;
      EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    }
  // Nothing was written, not even run's output folder.
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(MethodOption, MatrixRefusesEveryHierarchicalOption) {
  testing::TempDir dir;
  const std::vector<std::vector<std::string>> options = {
      {"--epsilon", "0.01"}, {"--min-area", "1"}, {"--link-rays", "4"}};
  for (const auto& command : kMethodCommands)
    for (const auto& o : options)
      for (bool explicit_method : {false, true}) {
        std::vector<std::string> args = {command, "-q"};
        if (explicit_method) args.insert(args.end(), {"--method", "matrix"});
        args.insert(args.end(), o.begin(), o.end());
        args.insert(args.end(), {"-o", dir.file(command == "render" ? "o.exr" : "o")});
        const auto [code, err] = run_capturing(args);
        EXPECT_EQ(code, kExitUsage) << command << ' ' << o[0];
        EXPECT_NE(err.find(o[0] + " does not apply to --method matrix"), std::string::npos) << err;
        EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
      }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(MethodOption, BadValuesAreUsageErrors) {
  for (const auto& command : kMethodCommands) {
    EXPECT_EQ(run({command, "-q", "--method", "radiance"}), kExitUsage) << command;
    // epsilon is a fraction of the emitted power in (0, 1): 0 and 1 are outside.
    for (const char* bad : {"0", "1", "-0.1", "nan", "inf", "1e-3x"})
      EXPECT_EQ(run({command, "-q", "--method", "hierarchical", "--epsilon", bad}), kExitUsage)
          << command << " --epsilon " << bad;
    for (const char* bad : {"0", "1025", "two"})
      EXPECT_EQ(run({command, "-q", "--method", "hierarchical", "--link-rays", bad}), kExitUsage)
          << command << " --link-rays " << bad;
    for (const char* bad : {"-1", "nan", "inf"})
      EXPECT_EQ(run({command, "-q", "--method", "hierarchical", "--min-area", bad}), kExitUsage)
          << command << " --min-area " << bad;
  }
  // formfactors is matrix-only: it has no --method.
  EXPECT_EQ(run({"formfactors", "-q", "--method", "hierarchical", "-o", "/tmp/never.bin"}),
            kExitUsage);
  // Only compare takes a list of epsilons.
  EXPECT_EQ(run({"run", "-q", "--method", "hierarchical", "--epsilon", "0.1,0.01"}), kExitUsage);
}

}  // namespace lambert
