// Options declared once (pipeline/option_specs.hpp): every option of every command has a
// row, the CLI checks and documents it from the row, the row's default is the bound field's,
// and `lambert options` prints the reference docs/options.md holds.

#include "pipeline/option_specs.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "apps/commands.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "pipeline/job.hpp"
#include "pipeline/medium_stage.hpp"
#include "pipeline/method.hpp"

namespace lambert {
namespace {

using testing::run_capturing;
using testing::run_stdout;

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
    // The rows solve registers with a range or choices (the walk below covers the others).
    if (!s.commands.empty() || s.keyword.empty()) continue;
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
      if (find_option_spec(s.name, cells[1].substr(0, cells[1].find(','))) != &s) continue;
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
    EXPECT_NE(err.find(option_value_error(s, outside(s))), std::string::npos) << err;
    // The default is accepted by the row's own check.
    EXPECT_EQ(option_value_error(s, s.default_text), "");
  }
}

// The whole CLI, as lambert builds it (apps/cli.cpp).
struct WholeCli {
  CLI::App app;
  InfoOptions info;
  RenderOptions render;
  RunOptions run;
  SolveCommandOptions solve;
  CompareOptions compare;
  SolversOptions solvers;
  FormFactorsOptions formfactors;
  HeatOptions heat;
  AccuracyOptions accuracy;
  OptionsOptions options;
  std::vector<CLI::App*> commands;
  WholeCli() {
    commands = {add_info_command(app, info),
                add_render_command(app, render),
                add_run_command(app, run),
                add_solve_command(app, solve),
                add_compare_command(app, compare),
                add_solvers_command(app, solvers),
                add_formfactors_command(app, formfactors),
                add_heat_command(app, heat),
                add_accuracy_command(app, accuracy),
                add_options_command(app, options)};
  }
};

std::string first_long_name(const CLI::Option* o) { return "--" + o->get_lnames().front(); }

// "[4,16,64]" (CLI11's text of a vector) -> "4,16,64"; numbers as number_text writes them.
std::string normalised(std::string text) {
  if (text.size() >= 2 && text.front() == '[' && text.back() == ']')
    text = text.substr(1, text.size() - 2);
  std::string out;
  std::istringstream items(text);
  for (std::string item; std::getline(items, item, ',');) {
    double x = 0;
    out += (out.empty() ? "" : ",") + (parse_finite_number(item, x) ? number_text(x) : item);
  }
  return out;
}

TEST(OptionSpecs, EveryOptionOfEveryCommandIsDeclaredAndEveryRowIsRegistered) {
  WholeCli cli;
  std::map<const OptionSpec*, int> registered;
  for (CLI::App* cmd : cli.commands)
    for (CLI::Option* o : cmd->get_options()) {
      if (o->get_lnames().empty() || o->get_lnames().front() == "help") continue;
      SCOPED_TRACE(cmd->get_name() + " " + first_long_name(o));
      const OptionSpec* spec = find_option_spec(first_long_name(o), cmd->get_name());
      ASSERT_NE(spec, nullptr) << "no row in pipeline/option_specs.cpp";
      ++registered[spec];
      // Described, checked and defaulted from the row.
      EXPECT_EQ(o->get_description(), spec->doc);
      EXPECT_EQ(o->get_type_name().empty(), spec->kind == OptionKind::Flag);
      EXPECT_EQ(o->get_default_str(), spec->default_text);
      // The row's default is the bound field's own (the value an absent option leaves).
      o->capture_default_str();
      const std::string field = o->get_default_str();
      if (!spec->default_text.empty()) {
        EXPECT_EQ(normalised(field), normalised(spec->default_text));
      }
    }
  for (const OptionSpec& s : option_specs()) {
    SCOPED_TRACE(s.name + " (" + s.group + ")");
    EXPECT_GT(registered[&s], 0) << "a row no command registers";
    for (const std::string& c : s.commands)
      EXPECT_TRUE(std::any_of(cli.commands.begin(), cli.commands.end(), [&](CLI::App* cmd) {
        return cmd->get_name() == c && cmd->get_option_no_throw(s.name) != nullptr;
      })) << c;
    EXPECT_FALSE(s.doc.empty());
    EXPECT_FALSE(s.group.empty());
    // A row's default passes its own check.
    if (!s.default_text.empty() && s.kind != OptionKind::Flag) {
      std::istringstream items(s.default_text);
      for (std::string item; std::getline(items, item, s.count == 1 ? '\n' : ',');)
        EXPECT_EQ(option_value_error(s, item), "") << item;
    }
  }
}

TEST(OptionSpecs, MethodsAndMediaTakeTheirOptionListsFromTheRows) {
  for (const OptionSpec& s : option_specs()) {
    if (s.method.empty()) continue;
    const Method& m = find_method(s.method);
    const auto& list = s.method_solver ? m.solver_options : m.problem_options;
    EXPECT_NE(std::find(list.begin(), list.end(), s.name), list.end()) << s.name;
  }
  EXPECT_EQ(medium_option_names(), option_group("medium"));
  EXPECT_EQ(medium_option_names().front(), "--medium-box");
}

TEST(OptionSpecs, TextAndListValuesAreCheckedByTheirRows) {
  // A bad value of each kind is refused on the command line with the row's reason.
  testing::TempDir dir;
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"solve", "--seed", "-1"}, "is not an integer in [0, 2^64 - 1]"},
      {{"solve", "--max-memory", "lots"}, "is not a size such as 512M or 8G"},
      {{"solve", "--default-reflectance", "0.5,2,0.5"}, "three numbers in [0, 1]"},
      {{"run", "--exposure", "100"}, "number of stops in [-64, 64]"},
      {{"solve", "--medium-box", "0,0,0,1,1,nan", "--sigma-a", "1,1,1"}, "is not a finite number"},
      {{"solve", "--sigma-a", "1,-1,1"}, "is not a number >= 0"},
      {{"accuracy", "--mc-samples", "4,0"}, "'0' is not an integer in [1, 1048576]"},
      {{"compare", "--solvers", "sor,nope"}, "'nope' is not one of"},
      {{"heat", "--surfaces", dir.file("missing.json")}, "no such file"},
      {{"solve", "-o", dir.file("no/such/dir/b.csv")}, "does not exist"},
  };
  for (auto [args, message] : cases) {
    args.push_back("-q");
    const auto [code, err] = run_capturing(args);
    EXPECT_EQ(code, kExitUsage) << args[1];
    EXPECT_NE(err.find(message), std::string::npos) << err;
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
