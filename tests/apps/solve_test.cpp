// CLI-level tests of `solve`, `compare` and `solvers`, on the built-in Cornell box with the
// real form-factor engine (few patches, few samples: fast, and the solvers do not care how
// accurate F is, only that it is the same F for all of them).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "apps/common.hpp"
#include "apps/problem.hpp"
#include "common/temp_dir.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

using testing::run;
using testing::slurp;
namespace {


std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
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
  const std::string json = read_all(dir.file("B.json"));
  EXPECT_NE(json.find("\"status\": \"converged\""), std::string::npos) << json.substr(0, 400);
  for (const char* key : {"\"iterations\"", "\"residual\"", "\"timings\"", "\"energy\"",
                          "\"escaped\"", "\"average_radiosity\"", "\"tall_block\""})
    EXPECT_NE(json.find(key), std::string::npos) << key;
}

TEST(SolveCommand, NonConvergenceExitsWithThreeAndStillWrites) {
  testing::TempDir dir;
  const std::string csv = dir.file("B.csv");
  EXPECT_EQ(run(with_fast({"solve", "--solver", "jacobi", "--max-iter", "1", "-o", csv})),
            kExitNotConverged);
  EXPECT_TRUE(std::filesystem::exists(csv));
  EXPECT_NE(read_all(dir.file("B.json")).find("max-iterations"), std::string::npos);
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

TEST(CompareCommand, WritesTableHistoriesAndPlots) {
  testing::TempDir dir;
  const std::string out = dir.path().string() + "/";
  ASSERT_EQ(run(with_fast({"compare", "--solvers", "jacobi,cg,direct", "-o", out})), kExitOk);
  const auto table = read_lines(dir.file("compare_table.csv"));
  ASSERT_EQ(table.size(), 4u);
  EXPECT_EQ(table[0], "solver,status,iterations,matvecs,seconds,residual,max_diff_direct");
  EXPECT_EQ(table[2].rfind("cg,converged,", 0), 0u);
  const auto history = read_lines(dir.file("compare_history.csv"));
  EXPECT_GT(history.size(), 10u);
  EXPECT_NE(read_all(dir.file("compare_convergence.svg")).find("jacobi"), std::string::npos);
  EXPECT_GT(std::filesystem::file_size(dir.file("compare_convergence.png")), 1000u);
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
  fo.samples = 4;
  fo.progress = false;
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
