// Options declared once (pipeline/option_specs.hpp): the CLI checks and documents each
// declared option from its row, and `lambert options` prints the reference docs/options.md
// holds.

#include "pipeline/option_specs.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "common/run_cli.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

using testing::run_capturing;

// `lambert ARGS` with stdout captured: the exit code and what went to stdout.
std::pair<int, std::string> run_stdout(const std::vector<std::string>& args) {
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const int code = testing::run(args);
  ::testing::internal::GetCapturedStderr();
  return {code, ::testing::internal::GetCapturedStdout()};
}

// A value just outside the row's range, or not one of its choices.
std::string outside(const OptionSpec& s) {
  if (s.kind == OptionKind::Choice) return "not-a-choice";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", s.hi + (s.kind == OptionKind::Integer ? 1.0 : 0.5));
  return buf;
}

TEST(OptionSpecs, EveryRowIsCheckedAndDescribedByTheCliFromTheRow) {
  const auto [code, reference] = run_stdout({"options", "--markdown"});
  ASSERT_EQ(code, kExitOk);
  for (const OptionSpec& s : option_specs()) {
    SCOPED_TRACE(s.name);
    // The reference rows (one per way the commands register it: `run` has cheaper
    // defaults): every one with the declared values, and solve's with the declared default.
    int rows = 0;
    bool solve_default = false;
    std::istringstream lines(reference);
    for (std::string row; std::getline(lines, row);) {
      std::vector<std::string> cells;  // "| a | b |": "a", "b"
      for (std::size_t at = 2, next; (next = row.find(" | ", at)) != std::string::npos;
           at = next + 3)
        cells.push_back(row.substr(at, next - at));
      if (cells.size() < 4) continue;
      if (cells[0] != "`" + s.name + "`" && cells[0].rfind("`" + s.name + ",", 0) != 0) continue;
      ++rows;
      EXPECT_EQ(cells[2], accepted_text(s)) << row;
      if ((", " + cells[1] + ",").find(", solve,") != std::string::npos)
        solve_default = cells[3] == s.default_text;
    }
    EXPECT_GE(rows, 1);
    EXPECT_TRUE(solve_default) << "solve's row shows the declared default " << s.default_text;
    // Refused on the command line before any work, with what the row accepts. (solve
    // registers every declared option.)
    const auto [refused, err] = run_capturing({"solve", s.name, outside(s), "-q"});
    EXPECT_EQ(refused, kExitUsage) << err;
    EXPECT_NE(err.find(accepted_text(s)), std::string::npos) << err;
    // The default is accepted by the row's own check.
    EXPECT_EQ(option_value_error(s, s.default_text), "");
  }
}

TEST(OptionSpecs, ValuesAreCheckedWholeFiniteAndInRange) {
  const OptionSpec& samples = option_spec("--samples");
  EXPECT_EQ(option_value_error(samples, "1"), "");
  EXPECT_EQ(option_value_error(samples, "1048576"), "");
  for (const char* bad : {"0", "1048577", "1.5", "nan", "inf", "12abc", ""})
    EXPECT_NE(option_value_error(samples, bad), "") << bad;
  const OptionSpec& omega = option_spec("--omega");
  EXPECT_THROW(check_option_value(omega, 2.0, "omega"), UsageError);
  EXPECT_THROW(check_option_value(omega, std::nan(""), "omega"), UsageError);
  EXPECT_NO_THROW(check_option_value(omega, 1.5, "omega"));
  try {
    check_option_choice(option_spec("--preconditioner"), "jacobi", "preconditioner");
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_EQ(std::string(e.what()), "preconditioner: 'jacobi' is not one of none, diagonal, ilut");
  }
}

}  // namespace
}  // namespace lambert
