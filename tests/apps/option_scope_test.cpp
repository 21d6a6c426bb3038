// No option is accepted and ignored (issue 33, item 3). The walk takes every option `solve`
// registers (asked from CLI11, not listed here) under every method x estimator x solver of
// the registries, and runs it on a small scene: the command either refuses the option (exit
// 2) or its result B differs from the same command without it. Options that by design
// change no result (output paths, logging, threads, memory checks) must leave B bitwise
// equal instead. The rows of pipeline/option_specs.cpp decide the refusals; this walk checks
// it against what the code actually reads. (Every option's row: tests/apps/option_specs_test.cpp.)

#include "pipeline/option_scope.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "apps/commands.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "pipeline/option_specs.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {
namespace {

using testing::run;
using testing::run_capturing;

// A lit floor with a blocker above it and a wall beside it, no two faces touching (the
// analytic estimator is quick on it), vertex colours on every corner, a floor above
// --max-reflectance 0.5.
std::string write_scene(const testing::TempDir& dir) {
  dir.write("s.mtl",
            "newmtl white\nKd 0.8 0.8 0.8\n"
            "newmtl grey\nKd 0.4 0.4 0.4\n"
            "newmtl light\nKd 0.2 0.2 0.2\nKe 5 5 5\n");
  return dir.write("s.obj",
                   "mtllib s.mtl\n"
                   "v 0 0 0 0.2 0.7 0.3\nv 1 0 0 0.2 0.7 0.3\nv 1 1 0 0.2 0.7 0.3\n"
                   "v 0 1 0 0.2 0.7 0.3\n"
                   "v 0.3 0.3 1 1 1 1\nv 0.7 0.3 1 1 1 1\nv 0.7 0.7 1 1 1 1\nv 0.3 0.7 1 1 1 1\n"
                   "v 0.35 0.35 0.5 0.5 0.5 0.5\nv 0.65 0.35 0.5 0.5 0.5 0.5\n"
                   "v 0.65 0.65 0.5 0.5 0.5 0.5\nv 0.35 0.65 0.5 0.5 0.5 0.5\n"
                   "v 1.1 0 0.1 0.9 0.1 0.1\nv 1.1 0 0.9 0.9 0.1 0.1\nv 1.1 1 0.9 0.9 0.1 0.1\n"
                   "v 1.1 1 0.1 0.9 0.1 0.1\n"
                   "g floor\nusemtl white\nf 1 2 3 4\n"
                   "g light\nusemtl light\nf 5 8 7 6\n"
                   "g blocker\nusemtl grey\nf 9 12 11 10\n"
                   "g wall\nusemtl grey\nf 13 14 15 16\n");
}

// Each option's long name: the values to try (any of them changing B counts as read),
// companion options that must come with it (given to the run without it too), and base
// options it replaces (they exclude each other).
struct Trial {
  Trial(std::vector<std::vector<std::string>> v, std::vector<std::string> c = {},
        std::vector<std::string> r = {})
      : values(std::move(v)), companions(std::move(c)), replaces(std::move(r)) {}
  std::vector<std::vector<std::string>> values;
  std::vector<std::string> companions;
  std::vector<std::string> replaces;
};

// What the walk gives each option (a new option without a row fails the walk: add one).
std::map<std::string, Trial> trials(const std::string& ff_file, const std::string& scene) {
  // A scattering medium: zones that only absorb hold no radiosity, and a homogeneous box's
  // transmittance does not depend on its zones.
  // One zone keeps the walk's medium runs quick.
  const std::vector<std::string> medium = {
      "--medium-box", "0,0,0.1,1,1,0.4", "--sigma-a", "0.2,0.2,0.2",
      "--sigma-s",    "0.6,0.6,0.6",     "--voxels",  "1"};
  return {
      {"--strict", {{{}}}},
      {"--default-reflectance", {{{"0.2,0.3,0.4"}}}},  // every face has a material: refused
      {"--max-reflectance", {{{"0.5"}}}},
      {"--vertex-colors-as-reflectance", {{{}}}},
      {"--split-angle", {{{"30"}}}},
      {"--emit", {{{"floor=1,2,3"}}}},
      {"--max-edge", {{{"0.3"}}, {}, {"--patches"}}},
      {"--patches", {{{"30"}}}},
      // The floor is inert at the walk's 12-patch target (a quarter of 12 covers no surface at
      // 4 patches each): it comes with a 200-patch target, where a floor of 12 raises the
      // blocker from 9 patches to 16 (MeshPlan.* test the floor's effect itself).
      {"--surface-floor", {{{"12", "--patches", "200"}}, {}, {"--patches"}}},
      {"--discontinuity", {{{}}}},
      {"--discontinuity-sources", {{{"1"}}, {"--discontinuity"}}},
      {"--epsilon", {{{"0.2"}}}},
      {"--min-area", {{{"0.05"}}}},
      {"--link-rays", {{{"2"}}}},
      {"--samples", {{{"3"}}}},
      {"--target-stderr", {{{"1e-3"}}}},
      {"--rays", {{{"20"}}}},
      // analytic is exact to ~1e-6 on this scene already at a loose target.
      {"--ff-tol", {{{"0.9"}, {"1e-8"}}}},
      {"--threshold", {{{"0.05"}}}},
      {"--hemicube-res", {{{"8"}}}},
      // gather averages by default (auto), the others do not.
      {"--reciprocity", {{{"average"}, {"none"}}}},
      {"--symmetrize", {{{}}}},
      {"--specular-depth", {{{"2"}}}},
      {"--specular-rays", {{{"16"}}}},
      {"--ff", {{{ff_file}}}},
      {"--tol", {{{"0.3"}}}},
      {"--max-iter", {{{"1"}}}},
      {"--omega", {{{"1.9"}}}},
      {"--preconditioner", {{{"none"}, {"ilut"}}}},
      {"--restart", {{{"1"}}}},
      {"--ambient", {{{}}}},
      {"--adapt", {{{"1"}}}},
      {"--adapt-patches", {{{"20"}}}},
      // Each needs the other: the pair is the trial, against no medium.
      {"--medium-box", {{{"0,0,0.1,1,1,0.4", "--sigma-a", "0.5,0.5,0.5"}}}},
      {"--sigma-a", {{{"0.5,0.5,0.5", "--medium-box", "0,0,0.1,1,1,0.4"}}}},
      {"--sigma-s", {{{"0.1,0.1,0.1"}}, medium}},
      {"--medium-emission", {{{"1,1,1"}}, medium}},
      {"--voxels", {{{"2"}}, medium}},
      {"--voxel-size", {{{"0.5"}}, medium, {"--voxels"}}},
      // Fewer rays than the default 256 (40) gave patch-to-zone factors above 1, refused by
      // the physics check of F (exit 1): the walk takes more.
      {"--medium-rays", {{{"1024"}}, medium}},
      {"--transmittance-samples", {{{"2"}}, medium}},
      {"--seed", {{{"7"}}}},
      {"--sky", {{{"1,2,3"}}}},
      {"--sun", {{{"0,0,-1,5,5,5"}}}},
      {"--petsc-options", {{{"-ksp_type gmres"}}}},  // needs --distributed (not walked)
      // Leave B bitwise equal by design (see kNoEffect).
      {"--output", {{{scene + ".other.csv"}}}},
      {"--threads", {{{"1"}}}},
      {"--quiet", {{{}}}},
      {"--verbose", {{{}}}},
      {"--max-memory", {{{"16G"}}}},
  };
}

// Options that change no result by design: output paths, logging, threads (results are
// bitwise the same at any thread count), the memory check, the strictness of loading (the
// scene is clean), and --split-angle (every surface here is one flat face: nothing to split;
// SurfaceSplit.* and SplitAngleCli.* show what it changes).
const std::set<std::string> kNoEffect = {"--output",     "--threads", "--quiet",      "--verbose",
                                         "--max-memory", "--strict",  "--split-angle"};
// Not walked, with the reason: --distributed needs mpirun (tests/mpi walk its refusals);
// --medium-grid needs a grid file (tests/apps/medium_test.cpp).
const std::set<std::string> kNotWalked = {"--distributed", "--medium-grid", "--help",  "scene",
                                          "--method",      "--estimator",   "--solver"};

// `args` without the options named in `names` and their values (a following token that is
// no option).
std::vector<std::string> without(const std::vector<std::string>& args,
                                 const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (size_t k = 0; k < args.size(); ++k) {
    if (std::find(names.begin(), names.end(), args[k]) == names.end()) {
      out.push_back(args[k]);
      continue;
    }
    if (k + 1 < args.size() && args[k + 1].rfind("--", 0) != 0) ++k;
  }
  return out;
}

std::string long_name(const CLI::Option* o) {
  return o->get_lnames().empty() ? o->get_name() : "--" + o->get_lnames().front();
}

}  // namespace

TEST(OptionScope, RefusalsNameTheOptionTheChoiceAndTheReader) {
  testing::TempDir dir;
  const std::string scene = write_scene(dir);
  const auto [code, err] = run_capturing(
      {"solve", scene, "--solver", "jacobi", "--omega", "1.2", "-o", dir.file("b.csv")});
  EXPECT_EQ(code, kExitUsage);
  EXPECT_NE(err.find("--omega does not apply to solve --method matrix --estimator auto --solver "
                     "jacobi (read by the solver sor)"),
            std::string::npos)
      << err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("b.csv")));
  // The cases: hierarchical reads neither --ff-tol nor --specular-rays; the hemicube
  // reads no --samples; auto refuses what its pick does not read, before the work; analytic
  // draws no random numbers; direct does not iterate.
  const std::string surfaces = dir.write("h.json", "{}");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"solve", "--method", "hierarchical", "--ff-tol", "1e-6"}, "--ff-tol does not apply"},
      {{"solve", "--method", "hierarchical", "--specular-rays", "64"},
       "--specular-rays does not apply"},
      {{"solve", scene, "--estimator", "hemicube", "--samples", "4"}, "--samples does not apply"},
      {{"solve", scene, "--rays", "64", "--patches", "20"},
       "--rays does not apply: --estimator auto picks hybrid for 20 patches"},
      {{"solve", scene, "--specular-depth", "2", "--patches", "20"},
       "the scene has no mirror or glass surface"},
      {{"formfactors", scene, "--estimator", "analytic", "--seed", "3"}, "--seed does not apply"},
      {{"heat", scene, "--solver", "direct", "--max-iter", "5", "--surfaces", surfaces},
       "--max-iter does not apply"},
  };
  for (auto [args, message] : cases) {
    args.insert(args.end(), {"-q", "-o", dir.file("out")});
    const auto [c, e] = run_capturing(args);
    EXPECT_EQ(c, kExitUsage) << args[0] << ' ' << message;
    EXPECT_NE(e.find(message), std::string::npos) << e;
    EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << e;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
}

TEST(OptionScopeSlow, NoOptionOfSolveIsAcceptedAndIgnored) {
  testing::TempDir dir;
  const std::string scene = write_scene(dir);
  const std::string ff_file = dir.file("F.bin");
  // A saved F of the walk's mesh made otherwise than any base run (mc, 2 samples, seed 9).
  ASSERT_EQ(run({"formfactors", scene, "-q", "--patches", "12", "--estimator", "mc", "--samples",
                 "2", "--seed", "9", "-o", ff_file}),
            kExitOk);
  const std::map<std::string, Trial> table = trials(ff_file, scene);

  CLI::App app;
  SolveCommandOptions solve_opts;
  const CLI::App* cmd = add_solve_command(app, solve_opts);
  std::vector<std::string> options;
  for (const CLI::Option* o : cmd->get_options()) {
    const std::string name = long_name(o);
    if (kNotWalked.count(name)) continue;
    options.push_back(name);
    EXPECT_TRUE(table.count(name)) << name << ": give it a value in trials()";
  }

  // The axes, from the registries: the hierarchical method, every estimator with the default
  // solver and every solver with the default estimator. No row of the scope table reads the
  // estimator and the solver together (pipeline/option_specs.cpp: a row's predicate looks at
  // one of them), and what an option changes does not depend on the other, so the star
  // covers every row for every registry entry at a fraction of the cross product's runs.
  struct Axes {
    std::string method, estimator, solver;
  };
  std::vector<Axes> axes = {{"hierarchical", "", ""}};
  const std::string default_solver = SolveOptions().solver;
  for (const std::string& e : form_factor_estimator_choices())
    axes.push_back({"matrix", e, default_solver});
  for (const std::string& s : solver_names())
    if (s != default_solver) axes.push_back({"matrix", "auto", s});

  const std::string out = dir.file("b.csv");
  int runs = 0, refused = 0, read = 0;
  for (const Axes& a : axes) {
    // The base command: the axis values that differ from the defaults (a default given
    // explicitly would itself exclude --ff), a small mesh; analytic at a loose target.
    std::vector<std::string> base = {"solve",  scene,      "--quiet", "--method",
                                     a.method, "--output", out};
    if (a.method == "matrix") {
      if (a.estimator != "auto") base.insert(base.end(), {"--estimator", a.estimator});
      if (a.solver != SolveOptions().solver) base.insert(base.end(), {"--solver", a.solver});
      base.insert(base.end(), {"--patches", "12"});
      if (a.estimator == "analytic") base.insert(base.end(), {"--ff-tol", "1e-3"});
    }
    const std::string axes_text = a.method + " " + a.estimator + " " + a.solver;
    std::map<std::vector<std::string>, std::string> baselines;  // by companions
    // B of the base with the companions; "" when the companions themselves are refused
    // here (a medium with --method hierarchical): the option is then refused with them.
    auto baseline = [&](const std::vector<std::string>& companions) -> const std::string& {
      auto it = baselines.find(companions);
      if (it != baselines.end()) return it->second;
      std::vector<std::string> args = base;
      args.insert(args.end(), companions.begin(), companions.end());
      std::filesystem::remove(out);
      const auto [code, err] = run_capturing(args);
      EXPECT_TRUE(code == kExitOk || code == kExitNotConverged ||
                  (code == kExitUsage && !companions.empty()))
          << axes_text << " baseline with " << ::testing::PrintToString(companions) << ": " << err;
      ++runs;
      return baselines[companions] = code == kExitUsage ? "" : testing::slurp(out);
    };
    ASSERT_FALSE(baseline({}).empty()) << axes_text;

    for (const std::string& name : options) {
      const auto it = table.find(name);
      if (it == table.end()) continue;
      const Trial& t = it->second;
      const std::string& before = baseline(t.companions);
      if (before.empty()) {
        ++refused;
        continue;
      }
      bool accepted = false, changed = false;
      for (const auto& value : t.values) {
        // The option replaces a base or companion setting of the same name (and its value),
        // and those it excludes.
        std::vector<std::string> dropped = t.replaces;
        dropped.push_back(name);
        std::vector<std::string> args = without(base, dropped);
        const std::vector<std::string> companions = without(t.companions, dropped);
        args.insert(args.end(), companions.begin(), companions.end());
        args.push_back(name);
        args.insert(args.end(), value.begin(), value.end());
        std::filesystem::remove(out);
        const auto [code, err] = run_capturing(args);
        ++runs;
        if (code == kExitUsage) continue;
        EXPECT_TRUE(code == kExitOk || code == kExitNotConverged)
            << axes_text << ' ' << name << ": exit " << code << ' ' << err;
        accepted = true;
        const std::string after =
            name == "--output" ? testing::slurp(value[0]) : testing::slurp(out);
        changed = changed || after != before;
        if (kNoEffect.count(name)) {
          EXPECT_EQ(after, before) << axes_text << ' ' << name << " changed B";
        }
      }
      if (!accepted) {
        ++refused;
        continue;
      }
      ++read;
      // --symmetrize restates gather's own default (reciprocity auto = average for gather).
      const bool restates_default = name == "--symmetrize" && a.estimator == "gather";
      if (!kNoEffect.count(name) && !restates_default) {
        EXPECT_TRUE(changed) << "solve --method " << a.method << " --estimator " << a.estimator
                             << " --solver " << a.solver << ' ' << name
                             << " was accepted and changed nothing";
      }
    }
  }
  std::printf("%zu options x %zu method/estimator/solver choices: %d runs, %d refused, %d read\n",
              options.size(), axes.size(), runs, refused, read);
}

}  // namespace lambert

namespace lambert {
namespace {

// A value of a text option without a default that its check accepts.
const std::map<std::string, std::string> kTextExamples = {{"--sun", "0,0,-1,5,5,5"}};

// A value the row accepts (its default where it has one; the bound or a choice otherwise;
// `count` of them, joined by the row's delimiter where it has one).
std::vector<std::string> value_of(const OptionSpec& s) {
  std::string one;
  switch (s.kind) {
    case OptionKind::Flag:
      return {};
    case OptionKind::Choice:
      one = s.default_text.empty() ? s.choices.front() : s.default_text;
      break;
    case OptionKind::Integer:
    case OptionKind::Real:
      one = s.default_text.empty() ? number_text(s.lo) : s.default_text;
      break;
    case OptionKind::Text:
      one = kTextExamples.count(s.name) ? kTextExamples.at(s.name) : s.default_text;
      break;
  }
  if (s.count <= 1) return {one};
  if (s.delimiter == 0) return std::vector<std::string>(static_cast<size_t>(s.count), one);
  std::string joined = one;
  for (int k = 1; k < s.count; ++k) joined += s.delimiter + one;
  return {joined};
}

}  // namespace

TEST(OptionScope, EveryCommandRefusesEveryOptionItsChoicesDoNotRead) {
  // Every option with a reader (pipeline/option_specs.cpp `read_by`) x every command that
  // takes it x every registry entry (--method hierarchical; each named estimator; each
  // solver): where the row says the command line's choices do not read it, the command
  // refuses it before any work (exit 2, "OPTION does not apply"). The other half (a read
  // option changes the result) is OptionScopeSlow's walk.
  testing::TempDir dir;
  const std::string scene = write_scene(dir);
  struct Command {
    std::string name;
    bool method, solver, shading;
  };
  const std::vector<Command> commands = {
      {"run", true, true, true},    {"render", true, true, true},
      {"solve", true, true, false}, {"compare", true, false, false},
      {"heat", false, true, false}, {"formfactors", false, false, false}};
  const std::string surfaces =
      dir.write("h.json", "{\"*\": {\"emissivity\": 0.5, \"temperature\": 300}}");
  int refusals = 0;
  for (const Command& c : commands) {
    // The axes this command offers: {extra args, the Selection they make}.
    std::vector<std::pair<std::vector<std::string>, Selection>> axes;
    const std::string solver = SolveOptions().solver;
    std::vector<std::string> all_solvers = solver_names();
    const auto solvers_of = [&](const std::string& s) {
      return c.name == "compare"       ? all_solvers
             : c.name == "formfactors" ? std::vector<std::string>{}
                                       : std::vector<std::string>{s};
    };
    // run and render draw random pixel samples at their default --antialias 2.
    const Selection base{c.name, "matrix", "", {}, c.shading ? "gouraud" : "", false, c.shading};
    for (const std::string& e : form_factor_estimators()) {
      Selection s = base;
      s.estimator = e;
      s.solvers = solvers_of(solver);
      axes.push_back({{"--estimator", e}, s});
    }
    if (c.solver)
      for (const std::string& v : solver_names()) {
        Selection s = base;
        s.estimator = "hybrid";
        s.solvers = {v};
        axes.push_back({{"--estimator", "hybrid", "--solver", v}, s});
      }
    if (c.method) {
      Selection s = base;
      s.method = "hierarchical";
      // compare's hierarchical runs are checked against a matrix reference it computes
      // (F with --estimator auto, solved directly): the estimator options apply there.
      if (c.name == "compare") s.estimator = "auto";
      axes.push_back({{"--method", "hierarchical"}, s});
    }
    // The command as the CLI registers it: the rows it takes under their own name (the
    // --tol of formfactors is --ff-tol's alias, --ff-tol's row).
    CLI::App app;
    RunOptions ro;
    RenderOptions dr;
    SolveCommandOptions so;
    CompareOptions co;
    HeatOptions ho;
    FormFactorsOptions fo;
    const CLI::App* cmd = c.name == "run"       ? add_run_command(app, ro)
                          : c.name == "render"  ? add_render_command(app, dr)
                          : c.name == "solve"   ? add_solve_command(app, so)
                          : c.name == "compare" ? add_compare_command(app, co)
                          : c.name == "heat"    ? add_heat_command(app, ho)
                                                : add_formfactors_command(app, fo);
    const auto takes = [&](const std::string& name) {
      const CLI::Option* o = cmd->get_option_no_throw(name);
      return o != nullptr && "--" + o->get_lnames().front() == name;
    };
    for (const OptionSpec& row : option_specs()) {
      if (!row.reads || find_option_spec(row.name, c.name) != &row || !takes(row.name)) continue;
      for (const auto& [extra, selection] : axes) {
        if (row.reads(selection)) continue;
        const std::string out = c.name == "formfactors" ? dir.file("out.bin")
                                : c.name == "solve"     ? dir.file("out.csv")
                                : c.name == "render"    ? dir.file("out.exr")
                                                        : dir.file("out/");
        std::vector<std::string> args = {c.name, scene, "-q", "-o", out};
        if (c.name == "heat") args.insert(args.end(), {"--surfaces", surfaces});
        args.insert(args.end(), extra.begin(), extra.end());
        args.push_back(row.name);
        const std::vector<std::string> value = value_of(row);
        args.insert(args.end(), value.begin(), value.end());
        const auto [code, err] = run_capturing(args);
        EXPECT_EQ(code, kExitUsage) << ::testing::PrintToString(args) << ": " << err;
        EXPECT_NE(err.find(row.name + " does not apply"), std::string::npos)
            << ::testing::PrintToString(args) << ": " << err;
        ++refusals;
      }
    }
  }
  for (const char* out : {"out.bin", "out.csv", "out.exr"})
    EXPECT_FALSE(std::filesystem::exists(dir.file(out))) << out;
  EXPECT_TRUE(!std::filesystem::exists(dir.file("out")) ||
              std::filesystem::is_empty(dir.file("out")));
  std::printf("%d refusals checked\n", refusals);
}

}  // namespace lambert
