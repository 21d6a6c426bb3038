// CLI-level tests of `solve`, `compare` and `solvers`, on the built-in Cornell box with the
// real form-factor engine (few patches, few samples: fast, and the solvers do not care how
// accurate F is, only that it is the same F for all of them).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "io/exr.hpp"
#include "io/ff_file.hpp"
#include "pipeline/job.hpp"
#include "pipeline/problem.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

using testing::read_json;
using testing::run;
using testing::slurp;
namespace {


std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

const std::vector<std::string> kFast = {"-q", "--patches", "150", "--samples", "4"};

std::vector<std::string> with_fast(std::vector<std::string> args) {
  args.insert(args.end(), kFast.begin(), kFast.end());
  return args;
}

TEST(SolveCommand, WritesPerPatchCsvAndJsonSummary) {
  testing::TempDir dir;
  const std::string csv = dir.file("B.csv");
  ASSERT_EQ(run(with_fast({"solve", "--solver", "gauss-seidel", "-o", csv})), kExitOk);
  const auto lines = read_lines(csv);
  ASSERT_GT(lines.size(), 100u);
  EXPECT_EQ(lines[0], "patch,surface,area,R,G,B");
  EXPECT_EQ(lines[1].rfind("0,", 0), 0u);
  const nlohmann::json json = read_json(dir.file("B.json"));
  EXPECT_EQ(json.at("status"), "converged");
  EXPECT_EQ(json.at("solver"), "gauss-seidel");
  EXPECT_EQ(json.at("patches").get<std::size_t>(), lines.size() - 1);  // one CSV row per patch
  EXPECT_EQ(json.at("options").at("tol").get<double>(), 1e-8);
  ASSERT_EQ(json.at("channels").size(), 3u);
  int iterations = 0;
  double residual = 0.0;
  for (const auto& c : json.at("channels")) {
    EXPECT_EQ(c.at("status"), "converged");
    EXPECT_GT(c.at("iterations").get<int>(), 0);
    // The stopping rule: relative residual <= tol.
    EXPECT_LE(c.at("residual").get<double>(), 1e-8);
    iterations = std::max(iterations, c.at("iterations").get<int>());
    residual = std::max(residual, c.at("residual").get<double>());
    const auto& e = c.at("energy");
    const double emitted = e.at("emitted").get<double>();
    EXPECT_GT(emitted, 0.0);
    // The Cornell box is open: some power escapes, the rest is absorbed, and the sum balances
    // to the residual (hybrid's F is reciprocal to rounding): |sum A r| / emitted <=
    // ||A||_2 ||r||_2 / emitted, a few 1e-8 here (measured 1e-8); 1e-6 leaves room for any mesh.
    EXPECT_GT(e.at("escaped").get<double>(), 0.0);
    EXPECT_GT(e.at("absorbed").get<double>(), 0.0);
    EXPECT_NEAR(e.at("absorbed").get<double>() + e.at("escaped").get<double>(), emitted,
                1e-6 * emitted);
    EXPECT_LE(e.at("relative_imbalance").get<double>(), 1e-6);
    // The split: the parts add up to the signed imbalance (three sums of magnitude <= emitted:
    // rounding 1e-12 relative is generous), and hybrid's F is reciprocal to rounding (per
    // entry ~1e-16 relative, times sum A F (B_i + B_j) <~ 20 emitted): 1e-10.
    const double imbalance =
        emitted - e.at("absorbed").get<double>() - e.at("escaped").get<double>();
    EXPECT_NEAR(e.at("residual_part").get<double>() + e.at("non_reciprocity_part").get<double>(),
                imbalance, 1e-12 * emitted);
    EXPECT_LE(std::abs(e.at("relative_non_reciprocity_part").get<double>()), 1e-10);
    EXPECT_EQ(e.at("relative_residual_part").get<double>(),
              e.at("residual_part").get<double>() / emitted);
  }
  // The top-level figures are the worst channel's.
  EXPECT_EQ(json.at("iterations").get<int>(), iterations);
  EXPECT_EQ(json.at("residual").get<double>(), residual);
  EXPECT_EQ(json.at("timings").at("form_factors_source"), "computed");
  bool tall_block = false;
  double area = 0.0;
  for (const auto& s : json.at("surfaces")) {
    tall_block = tall_block || s.at("name") == "tall_block";
    area += s.at("area").get<double>();
    ASSERT_EQ(s.at("average_radiosity").size(), 3u);
    for (const auto& b : s.at("average_radiosity")) EXPECT_GE(b.get<double>(), 0.0);
  }
  EXPECT_TRUE(tall_block);
  // The surfaces' areas add up to the patches' (column 3 of the CSV), to rounding of two sums
  // of ~100 terms of magnitude <= total: 1e-12 relative.
  double csv_area = 0.0;
  for (size_t k = 1; k < lines.size(); ++k) {
    std::stringstream row(lines[k]);
    std::string field;
    for (int col = 0; col < 3; ++col) std::getline(row, field, ',');
    csv_area += std::stod(field);
  }
  EXPECT_NEAR(area, csv_area, 1e-12 * csv_area);
}

TEST(SolveCommand, HemicubeImbalanceIsReportedAsNonReciprocityNotAsResidual) {
  testing::TempDir dir;
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(run({"solve", "-q", "--patches", "150", "--estimator", "hemicube", "--hemicube-res",
                 "16", "--solver", "direct", "-o", dir.file("B.csv")}),
            kExitOk);
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("non-reciprocity part"), std::string::npos) << out;
  const auto report = read_json(dir.file("B.json"));  // a named value: a temporary would die
  for (const auto& c : report.at("channels")) {
    const auto& e = c.at("energy");
    const double imbalance = e.at("relative_imbalance").get<double>();
    // Hemicube rows are not reciprocal: at N = 16 the imbalance is percent-level (measured
    // 1.3-1.4e-2 on this mesh), so 1e-3 is safe. The direct solve leaves a residual part at
    // rounding, |sum A r| <= ||A||_2 ||r||_2 with ||r|| / ||E|| ~ 1e-16 (measured residual
    // part <= 1.6e-16 of emitted); 1e-12 leaves 1e4 for ||A||_2 ||E||_2 / emitted. The
    // non-reciprocity part is then the imbalance to the same 1e-12.
    EXPECT_GT(imbalance, 1e-3);
    EXPECT_LE(std::abs(e.at("relative_residual_part").get<double>()), 1e-12);
    EXPECT_NEAR(std::abs(e.at("relative_non_reciprocity_part").get<double>()), imbalance, 1e-12);
  }
}

TEST(SolveCommand, NonConvergenceExitsWithThreeAndStillWrites) {
  testing::TempDir dir;
  const std::string csv = dir.file("B.csv");
  EXPECT_EQ(run(with_fast({"solve", "--solver", "jacobi", "--max-iter", "1", "-o", csv})),
            kExitNotConverged);
  EXPECT_TRUE(std::filesystem::exists(csv));
  const nlohmann::json json = read_json(dir.file("B.json"));
  EXPECT_EQ(json.at("status"), "max-iterations");
  EXPECT_EQ(json.at("iterations").get<int>(), 1);
  for (const auto& c : json.at("channels")) EXPECT_EQ(c.at("status"), "max-iterations");
}

TEST(SolveCommand, BadSolverOptionsAreUsageErrors) {
  testing::TempDir dir;
  const std::string csv = dir.file("B.csv");
  EXPECT_EQ(run({"solve", "-q", "--solver", "magic", "-o", csv}), kExitUsage);
  EXPECT_EQ(run({"solve", "-q", "--omega", "2.5", "-o", csv}), kExitUsage);
  EXPECT_EQ(run(with_fast({"solve", "--solver", "cg", "--preconditioner", "ilut", "-o", csv})),
            kExitUsage);
  EXPECT_FALSE(std::filesystem::exists(csv));
}

// The settings a report or image states for its F.
void expect_mc_64_5(const nlohmann::json& ff, const std::string& file) {
  EXPECT_EQ(ff.at("estimator"), "mc") << file;
  EXPECT_EQ(ff.at("samples").get<int>(), 64) << file;
  EXPECT_EQ(ff.at("seed").get<std::uint64_t>(), 5u) << file;
  EXPECT_EQ(ff.at("threshold").get<double>(), 1e-4) << file;  // %.17g reads back exactly
  EXPECT_EQ(ff.at("loaded_from"), file);
}
void expect_mc_64_5(const std::string& exr_settings) {
  FormFactorOptions o;
  ASSERT_TRUE(parse_ff_settings(exr_settings, o)) << exr_settings;
  EXPECT_EQ(o.estimator, "mc") << exr_settings;
  EXPECT_EQ(o.pair.samples, 64) << exr_settings;
  EXPECT_EQ(o.run.seed, 5u) << exr_settings;
}

TEST(SolveCommand, LoadedFormFactorsReportTheSettingsThatMadeThem) {
  testing::TempDir dir;
  const std::vector<std::string> mesh = {"-q", "--patches", "150"};
  const auto cmd = [&](std::vector<std::string> args) {
    args.insert(args.end(), mesh.begin(), mesh.end());
    return args;
  };
  for (const std::string& f : {std::string("F.bin"), std::string("F.mtx")}) {
    const std::string file = dir.file(f);
    ASSERT_EQ(run(cmd({"formfactors", "--estimator", "mc", "--samples", "64", "--seed", "5",
                       "--threshold", "1e-4", "-o", file})),
              kExitOk);
    ASSERT_EQ(run(cmd({"solve", "--ff", file, "-o", dir.file("B.csv")})), kExitOk) << f;
    expect_mc_64_5(read_json(dir.file("B.json")).at("form_factors"), file);
  }
  const std::string file = dir.file("F.bin");
  ::testing::internal::CaptureStdout();
  const int code = run(cmd({"run", "--ff", file, "-o", dir.file("out"), "--size", "8x8"}));
  ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, kExitOk);
  const nlohmann::json report = read_json(dir.file("out/report.json"));
  expect_mc_64_5(report.at("form_factors"), file);
  expect_mc_64_5(report.at("settings").get<std::string>());
  ExrInfo info;
  read_image_exr(dir.file("out/cornell.exr"), &info);
  expect_mc_64_5(info.settings);
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(run(cmd({"render", "--ff", file, "-o", dir.file("r.exr"), "--size", "8x8"})), kExitOk);
  ::testing::internal::GetCapturedStdout();
  read_image_exr(dir.file("r.exr"), &info);
  expect_mc_64_5(info.settings);

  // A foreign Matrix Market file (the mesh hash but no settings line): unknown, not defaults.
  // A foreign file states no error, so its row sums may not exceed 1 beyond rounding, which
  // the noisy mc F above does (up to 1.77): its entries are halved (every row sum <= 0.89).
  std::string foreign;
  bool size_line = true;  // the first line that is not a comment: N N nnz, kept
  for (std::string line : read_lines(dir.file("F.mtx"))) {
    int i = 0, j = 0;
    double v = 0;
    char buf[64];
    if (line[0] != '%' && !std::exchange(size_line, false) && std::sscanf(line.c_str(), "%d %d %lf", &i, &j, &v) == 3 &&
        std::snprintf(buf, sizeof buf, "%d %d %.17g", i, j, 0.5 * v) > 0)
      line = buf;
    if (line.rfind("% lambert-settings:", 0) != 0) foreign += line + "\n";
  }
  const std::string foreign_file = dir.write("foreign.mtx", foreign);
  ::testing::internal::CaptureStderr();
  ::testing::internal::CaptureStdout();
  const int foreign_code =  // without -q, which silences warnings too
      run({"solve", "--patches", "150", "--ff", foreign_file, "-o", dir.file("B.csv")});
  ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  ASSERT_EQ(foreign_code, kExitOk) << err;
  EXPECT_NE(err.find("records no form-factor settings"), std::string::npos) << err;
  const nlohmann::json ff = read_json(dir.file("B.json")).at("form_factors");
  for (const char* key :
       {"estimator", "samples", "seed", "threshold", "hemicube_resolution", "symmetrize"})
    EXPECT_TRUE(ff.at(key).is_null()) << key;
}

TEST(SolveCommand, OptionsThatOnlySteerAComputationAreRefusedWithFf) {
  testing::TempDir dir;
  const std::string file = dir.file("F.bin");
  ASSERT_EQ(run({"formfactors", "-q", "--patches", "60", "--samples", "2", "-o", file}), kExitOk);
  for (const std::vector<std::string>& extra : {std::vector<std::string>{"--estimator", "mc"},
                                                {"--samples", "8"},
                                                {"--threshold", "0.1"},
                                                {"--hemicube-res", "64"},
                                                {"--rays", "64"},
                                                {"--reciprocity", "average"},
                                                {"--symmetrize"}}) {
    // Outputs that would be accepted, so that only the option clash can refuse the command.
    for (const auto& [command, output] :
         std::vector<std::pair<std::string, std::string>>{{"solve", dir.file("B.csv")},
                                                          {"run", dir.file("out")},
                                                          {"render", dir.file("r.exr")},
                                                          {"compare", dir.file("c/")}}) {
      std::vector<std::string> args = {command, "-q", "--patches", "60",
                                       "--ff",  file, "-o",        output};
      args.insert(args.end(), extra.begin(), extra.end());
      ::testing::internal::CaptureStderr();
      EXPECT_EQ(run(args), kExitUsage) << command << ' ' << extra[0];
      const std::string err = ::testing::internal::GetCapturedStderr();
      EXPECT_NE(err.find(extra[0] + " excludes --ff"), std::string::npos) << err;
      EXPECT_FALSE(std::filesystem::exists(output)) << command << ' ' << extra[0];
    }
  }
}

TEST(CompareCommand, WritesTableHistoriesAndPlots) {
  testing::TempDir dir;
  const std::string out = dir.path().string() + "/";
  ASSERT_EQ(run(with_fast({"compare", "--solvers", "jacobi,cg,direct", "-o", out})), kExitOk);
  const auto table = read_lines(dir.file("compare_table.csv"));
  ASSERT_EQ(table.size(), 4u);
  EXPECT_EQ(table[0], "solver,status,iterations,matvecs,seconds,residual,max_diff,reference");
  EXPECT_EQ(table[2].rfind("cg,converged,", 0), 0u);
  EXPECT_EQ(table[3].substr(table[3].rfind(',') + 1), "direct");
  const auto history = read_lines(dir.file("compare_history.csv"));
  EXPECT_GT(history.size(), 10u);
  EXPECT_NE(slurp(dir.file("compare_convergence.svg")).find("jacobi"), std::string::npos);
  // PNGs come from `python3 -m lambert.plot compare` (tests/python/test_plot.py).
  EXPECT_FALSE(std::filesystem::exists(dir.file("compare_convergence.png")));
}

// 150 patches: a dense LU needs 8 * 150^2 = 180 KB (the Cornell box's F is ~50% full, the
// dense path) plus K, the mesh ~75 KB (mesh_peak_bytes). 150K lets the mesh through and not
// direct, at the plan stage (computed F: the all-pairs bound) and in the solver (loaded F).
const std::string kBelowDirect = "150K";

TEST(SolveCommand, DirectAboveTheMemoryLimitIsAUsageError) {
  testing::TempDir dir;
  const std::string ff = dir.file("F.bin");
  ASSERT_EQ(run({"formfactors", "-q", "--patches", "150", "--samples", "2", "-o", ff}), kExitOk);
  for (const std::vector<std::string>& source :
       {std::vector<std::string>{"--patches", "150", "--samples", "2"},
        std::vector<std::string>{"--patches", "150", "--ff", ff}}) {
    std::vector<std::string> args = {"solve", "-q", "--solver", "direct", "--max-memory",
                                     kBelowDirect, "-o", dir.file("B.csv")};
    args.insert(args.end(), source.begin(), source.end());
    ::testing::internal::CaptureStderr();
    EXPECT_EQ(run(args), kExitUsage) << source.back();
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("direct: a dense LU of"), std::string::npos) << err;
    EXPECT_NE(err.find("(--max-memory 150K)"), std::string::npos) << err;
    EXPECT_NE(err.find("raise it with --max-memory or LAMBERT_MAX_MEMORY"), std::string::npos)
        << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;  // one line
    EXPECT_FALSE(std::filesystem::exists(dir.file("B.csv"))) << source.back();
  }
}

TEST(CompareCommand, SkipsDirectAboveTheMemoryLimitAndSaysSo) {
  testing::TempDir dir;
  const std::string ff = dir.file("F.bin");
  ASSERT_EQ(run({"formfactors", "-q", "--patches", "150", "--samples", "2", "-o", ff}), kExitOk);
  const std::string out = dir.path().string() + "/";
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(run({"compare", "-q", "--patches", "150", "--ff", ff, "--solvers", "jacobi,direct", "--max-memory",
                 kBelowDirect, "-o", out}),
            kExitOk);
  const std::string stdout_text = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(stdout_text.find("reference for max |B-ref|: gauss-seidel at tol 1e-10"),
            std::string::npos)
      << stdout_text;
  const auto table = read_lines(dir.file("compare_table.csv"));
  ASSERT_EQ(table.size(), 3u);
  EXPECT_EQ(table[1].rfind("jacobi,converged,", 0), 0u);
  EXPECT_NE(table[1].find(",gauss-seidel at tol 1e-10"), std::string::npos) << table[1];
  EXPECT_EQ(table[2].rfind("direct,skipped,,,,,,", 0), 0u) << table[2];
  EXPECT_NE(table[2].find("direct: a dense LU of"), std::string::npos) << table[2];
}

TEST(SolversCommand, ListsEverySolver) {
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(run({"solvers"}), kExitOk);
  const std::string out = ::testing::internal::GetCapturedStdout();
  for (const auto& name : solver_names()) EXPECT_NE(out.find(name), std::string::npos) << name;
}

TEST(CornellBox, EverySolverAgreesWithDirect) {
  SceneArgs args;
  args.patches = 200;
  const LoadedScene scene = load_scene(args);
  FormFactorOptions fo;
  fo.pair.samples = 4;
  fo.run.progress = false;
  const FormFactors ff = compute_form_factors(scene.mesh, fo);
  const RadiosityProblem problem = make_problem(scene.mesh, ff.F);
  const double tol = 1e-9;
  SolveOptions o;
  o.tol = tol;
  o.solver = "direct";
  const RadiositySolution ref = solve_radiosity(problem, o);
  ASSERT_EQ(ref.status, SolveStatus::Converged);
  // ||K^-1||_inf <= 1 / (1 - max_i rho_i sum_j F_ij): estimated rows may sum slightly above 1.
  const Eigen::VectorXd row_sum = ff.F * Eigen::VectorXd::Ones(ff.F.cols());
  for (const auto& name : solver_names()) {
    o.solver = name;
    const RadiositySolution s = solve_radiosity(problem, o);
    EXPECT_EQ(s.status, SolveStatus::Converged) << name;
    for (int c = 0; c < 3; ++c) {
      const double contraction = (problem.rho.col(c).cwiseProduct(row_sum)).maxCoeff();
      ASSERT_LT(contraction, 1.0);
      // Both solutions lie within residual * ||E||_2 * ||K^-1||_inf of the exact one.
      const double bound =
          (tol + ref.channels[c].residual) * problem.emission.col(c).norm() / (1.0 - contraction);
      EXPECT_LE((s.B.col(c) - ref.B.col(c)).lpNorm<Eigen::Infinity>(), bound) << name << c;
      // Energy balances within the residual: |sum A r| <= ||A||_2 ||r||_2, plus
      // non-reciprocity of the estimate, which the engine's hybrid estimator keeps at rounding.
      EXPECT_LE(s.energy[c].relative_imbalance, problem.area.norm() * s.channels[c].residual *
                                                        problem.emission.col(c).norm() /
                                                        s.energy[c].emitted +
                                                    1e-9)
          << name << c;
    }
  }
}

}  // namespace
}  // namespace lambert

namespace lambert {

// --vertex-colors-as-reflectance reaches the patches through the shared scene options:
// the floor's colours (0.3 0.4 0.4 and 0.55 0.2 0.2 instead of Kd 0.7) change its B.
TEST(SolveCommand, VertexColoursAsReflectanceChangeTheSolution) {
  testing::TempDir dir;
  const std::string obj = std::string(LAMBERT_TEST_CORPUS_DIR) + "/obj/vertex_colors_reflectance.obj";
  for (const char* flag : {"", "--vertex-colors-as-reflectance"}) {
    std::vector<std::string> args = {"solve", obj, "-q", "--emit", "wall=1,1,1", "--samples", "4", "--max-edge", "0.5",
                                     "-o", dir.file(flag[0] ? "colours.csv" : "kd.csv")};
    if (flag[0]) args.push_back(flag);
    EXPECT_EQ(testing::run(args), kExitOk) << flag;
  }
  EXPECT_NE(testing::slurp(dir.file("colours.csv")), testing::slurp(dir.file("kd.csv")));
}

}  // namespace lambert

namespace lambert {

// --adapt refines and re-solves: the summary reports every round, the patch count grows
// round by round while only the changed patches get new factors, the estimated error is
// lower after the rounds than before, and the written CSV has the final mesh's rows.
TEST(SolveCommandSlow, AdaptReportsRoundsAndWritesTheRefinedMesh) {
  testing::TempDir dir;
  const std::string csv = dir.file("B.csv");
  ASSERT_EQ(run({"solve", "-q", "--patches", "150", "--adapt", "2", "--estimator", "hybrid",
                 "--samples", "16", "-o", csv}),
            kExitOk);
  const nlohmann::json json = read_json(dir.file("B.json"));
  const auto& rounds = json.at("adapt");
  ASSERT_EQ(rounds.size(), 3u);
  for (size_t k = 1; k < rounds.size(); ++k) {
    EXPECT_GT(rounds[k].at("patches").get<int>(), rounds[k - 1].at("patches").get<int>());
    EXPECT_LT(rounds[k].at("changed").get<int>(), rounds[k].at("patches").get<int>());
  }
  EXPECT_LT(rounds.back().at("estimated_error").get<double>(), rounds[0].at("estimated_error").get<double>());
  EXPECT_EQ(json.at("patches").get<int>(), rounds.back().at("patches").get<int>());
  EXPECT_EQ(read_lines(csv).size(), json.at("patches").get<std::size_t>() + 1);
  // A patch budget stops the rounds once reached.
  ASSERT_EQ(run(with_fast({"solve", "--adapt-patches", "400", "-o", csv})), kExitOk);
  EXPECT_GE(read_json(dir.file("B.json")).at("patches").get<int>(), 400);
}

// Adaptation computes F: a saved F cannot be used; --discontinuity-sources needs
// --discontinuity; the hierarchical method refuses both (it meshes on its own).
TEST(SolveCommand, AdaptAndDiscontinuityOptionMisuseIsAUsageError) {
  testing::TempDir dir;
  const std::string csv = dir.file("B.csv");
  const std::string ff = dir.file("F.bin");
  ASSERT_EQ(run(with_fast({"formfactors", "-o", ff})), kExitOk);
  EXPECT_EQ(run({"solve", "-q", "--patches", "150", "--adapt", "1", "--ff", ff, "-o", csv}), kExitUsage);
  EXPECT_EQ(run(with_fast({"solve", "--discontinuity-sources", "2", "-o", csv})), kExitUsage);
  EXPECT_EQ(run({"solve", "-q", "--method", "hierarchical", "--discontinuity", "-o", csv}), kExitUsage);
  EXPECT_EQ(run({"solve", "-q", "--method", "hierarchical", "--adapt", "2", "-o", csv}), kExitUsage);
}

namespace {
// The partial-shadow scene of geometry/analytic.hpp as an OBJ: a grey floor [0, 4]² (rho 0.5),
// a black square light [1.5, 2.5]² at z = 3 (E = 1) and a black blocker at z = 1.5.
void write_partial_shadow_scene(const testing::TempDir& dir) {
  dir.write("ps.mtl",
            "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 1 1 1\n"
            "newmtl black\nKd 0 0 0\n");
  dir.write("ps.obj",
            "mtllib ps.mtl\n"
            "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\n"
            "v 1.5 1.5 3\nv 1.5 2.5 3\nv 2.5 2.5 3\nv 2.5 1.5 3\n"
            "v 1.6 1.3 1.5\nv 2.6 1.3 1.5\nv 2.6 2.1 1.5\nv 1.6 2.1 1.5\n"
            "g floor\nusemtl grey\nf 1 2 3 4\n"
            "g light\nusemtl light\nf 5 6 7 8\n"
            "g blocker\nusemtl black\nf 9 10 11 12\n");
}
}  // namespace

// What --discontinuity is for, through the CLI, on the soft-shadow scene whose floor field is
// known exactly: B(x) = 0.5 F_{dx->light, visible}(x) (nothing else reflects onto the floor).
// (1) `run` meshes along the shadow's D1/D2 lines: every line x = c and y = c of
// partial_shadow_lines carries floor vertices (a line is a mesh edge, at least its two ends).
// (2) Its vertex field is the exact direct light (the floor's indirect irradiance is exactly 0),
// so every floor vertex value equals B(x): the tolerance is the vertex EXR's float32 storage,
// 2^-24 relative of B <= 0.5, rounded up to 1e-7 (the exact kernel itself errs by ~1e-13).
// (3) `solve` with the analytic estimator (--ff-tol 1e-6): the floor's power sum B_i A_i is
// 0.5 A_floor F_{floor->light} to within 0.5 sum_i A_i |dF_i| <= 0.5 A_floor tol = 8e-6,
// against the exact occluded factor (partial_shadow_floor_light_factor, ~1e-16).
TEST(SolveCommand, DiscontinuityMeshGivesTheExactSoftShadow) {
  testing::TempDir dir;
  write_partial_shadow_scene(dir);
  const std::string scene = dir.file("ps.obj");
  ASSERT_EQ(run({"run", scene, "-q", "--discontinuity", "--patches", "300", "--size", "16x16", "-o",
                 dir.file("out")}),
            kExitOk);
  const VertexExr v = read_vertex_exr(dir.file("out/ps_vertices.exr"));
  const auto& names = v.info.surface_names;
  const auto floor_index = std::find(names.begin(), names.end(), "floor") - names.begin();
  ASSERT_LT(floor_index, static_cast<long>(names.size()));
  const auto [xs, ys] = partial_shadow_lines();
  std::vector<int> on_x(xs.size(), 0), on_y(ys.size(), 0);
  int floor_vertices = 0;
  double worst = 0.0;
  for (std::int64_t k = 0; k < v.vertex_count; ++k) {
    if (v.surface[k] != floor_index) continue;
    ++floor_vertices;
    const Eigen::Vector3d x = v.positions[k];
    worst = std::max(worst, std::abs(v.radiosity.row(k).mean() -
                                     partial_shadow_floor_radiosity({x.x(), x.y(), 0.0})));
    // Positions are float32 too: within 2^-24 x 4 ~ 2.4e-7 of the line, 1e-6 allowed.
    for (std::size_t i = 0; i < xs.size(); ++i) on_x[i] += std::abs(x.x() - xs[i]) < 1e-6;
    for (std::size_t i = 0; i < ys.size(); ++i) on_y[i] += std::abs(x.y() - ys[i]) < 1e-6;
  }
  ASSERT_GT(floor_vertices, 50);
  EXPECT_LT(worst, 1e-7) << "the exact-direct vertex field differs from the exact soft shadow";
  for (std::size_t i = 0; i < xs.size(); ++i) EXPECT_GE(on_x[i], 2) << "line x = " << xs[i];
  for (std::size_t i = 0; i < ys.size(); ++i) EXPECT_GE(on_y[i], 2) << "line y = " << ys[i];

  const std::string csv = dir.file("B.csv");
  ASSERT_EQ(run({"solve", scene, "-q", "--discontinuity", "--patches", "80", "--ff-tol", "1e-6",
                 "-o", csv}),
            kExitOk);
  double power = 0.0;
  for (const auto& line : read_lines(csv)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (cells.size() == 6 && cells[1] == "floor")
      power += std::stod(cells[2]) * std::stod(cells[3]);
  }
  EXPECT_NEAR(power, 0.5 * 16.0 * partial_shadow_floor_light_factor(), 8e-6);
}

}  // namespace lambert
