// A test double of a new estimator: "uniform", registered here only (its own test
// executable), with one parameter, --uniform-weight. Its declaration on the registry entry is
// all it takes for the parameter to reach the CLI (--help, checks, the "does not apply"
// refusal for the other estimators), the option table and the settings stored with a saved F:
// adding an estimator with one parameter is one file plus one registry row.

#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "io/ff_file.hpp"
#include "io/ff_settings.hpp"
#include "pipeline/option_specs.hpp"

namespace lambert {
namespace {

using testing::run_capturing;
using testing::run_stdout;

// F_ij = w / (N - 1) for every i != j: each row sums to w, the parameter.
FormFactors compute_uniform(const PatchMesh& mesh, const FormFactorOptions& o, const Bvh*) {
  const std::int32_t n = mesh.size();
  const double w = estimator_param(o, "--uniform-weight");
  std::vector<Eigen::Triplet<double, std::int64_t>> entries;
  for (std::int32_t i = 0; i < n; ++i)
    for (std::int32_t j = 0; j < n; ++j)
      if (i != j) entries.emplace_back(i, j, w / (n - 1));
  FormFactors out;
  out.F.resize(n, n);
  out.F.setFromTriplets(entries.begin(), entries.end());
  out.F.makeCompressed();
  return out;
}

// The one registry row: the estimator and its parameter.
const bool kRegistered = [] {
  FormFactorEstimator e;
  e.name = "uniform";
  e.compute = compute_uniform;
  e.peak_bytes = [](std::int64_t n, const FormFactorOptions&) { return 16.0 * n * n; };
  e.params = {real_param("--uniform-weight", "uniform_weight", 0.0, 1.0, 0.5,
                         "Row sum of the uniform test estimator", true)};
  register_form_factor_estimator(e);
  return true;
}();

TEST(TestEstimator, ItsParameterIsAnOptionWithItsRangeInHelpAndTheReference) {
  ASSERT_TRUE(kRegistered);
  const auto [code, help] = run_stdout({"formfactors", "--help"});
  EXPECT_EQ(code, kExitOk);
  EXPECT_NE(help.find("--uniform-weight"), std::string::npos) << help;
  EXPECT_NE(help.find("a number in (0, 1]"), std::string::npos) << help;
  EXPECT_NE(help.find("Row sum of the uniform test estimator"), std::string::npos);
  const OptionSpec& row = option_spec("--uniform-weight");
  EXPECT_EQ(row.keyword, "uniform_weight");
  EXPECT_EQ(row.reader, "the estimator uniform");
  EXPECT_EQ(row.default_text, "0.5");
  const auto [md_code, reference] = run_stdout({"options", "--markdown"});
  EXPECT_EQ(md_code, kExitOk);
  EXPECT_NE(reference.find("--uniform-weight"), std::string::npos);
}

TEST(TestEstimator, OutOfRangeAndOtherEstimatorsAreUsageErrors) {
  testing::TempDir dir;
  const std::string out = dir.file("F.mtx");
  for (const char* bad : {"0", "1.5", "x"}) {
    const auto [code, err] = run_capturing(
        {"formfactors", "-q", "--estimator", "uniform", "--uniform-weight", bad, "-o", out});
    EXPECT_EQ(code, kExitUsage) << bad << ": " << err;
  }
  // Another estimator does not read it: refused before any work, naming what reads it.
  for (const char* other : {"mc", "hemicube", "auto"}) {
    const auto [code, err] = run_capturing(
        {"formfactors", "-q", "--estimator", other, "--uniform-weight", "0.25", "-o", out});
    EXPECT_EQ(code, kExitUsage) << other;
    EXPECT_NE(err.find("--uniform-weight does not apply"), std::string::npos) << err;
    EXPECT_NE(err.find("the estimator uniform"), std::string::npos) << err;
  }
  // And the others' parameters do not apply to it.
  const auto [code, err] =
      run_capturing({"formfactors", "-q", "--estimator", "uniform", "--samples", "4", "-o", out});
  EXPECT_EQ(code, kExitUsage);
  EXPECT_NE(err.find("--samples does not apply"), std::string::npos) << err;
}

TEST(TestEstimator, ItsValueReachesTheEstimatorAndTheSavedSettings) {
  testing::TempDir dir;
  const std::string out = dir.file("F.bin");
  ASSERT_EQ(run_stdout({"formfactors", "-q", "--patches", "20", "--estimator", "uniform",
                        "--uniform-weight", "0.25", "-o", out})
                .first,
            kExitOk);
  FormFactorFileInfo info;
  const FormFactors ff = read_form_factors(out, 0, -1, &info);
  // Every row sums to the weight (N - 1 entries of w / (N - 1): rounding only).
  ASSERT_GT(ff.F.rows(), 1);
  for (Eigen::Index i = 0; i < ff.F.rows(); ++i) EXPECT_NEAR(ff.F.row(i).sum(), 0.25, 1e-14) << i;
  // Stored after the settings every estimator has, when the estimator reads it.
  EXPECT_NE(info.settings.find("estimator=uniform samples=32 rays=1024 seed=1 threshold=0 "
                               "hemicube_res=128 reciprocity=none symmetrize=0 "
                               "uniform_weight=0.25"),
            std::string::npos)
      << info.settings;
  FormFactorOptions back;
  ASSERT_TRUE(parse_ff_settings(info.settings, back));
  EXPECT_EQ(back.estimator, "uniform");
  EXPECT_EQ(estimator_param(back, "--uniform-weight"), 0.25);
  EXPECT_EQ(ff_settings_report(back)["uniform_weight"], 0.25);
  // Not stored for another estimator (it does not read it), and reported as null.
  FormFactorOptions mc;
  mc.estimator = "mc";
  EXPECT_EQ(format_ff_settings(mc).find("uniform_weight"), std::string::npos);
  EXPECT_TRUE(ff_settings_report(mc)["uniform_weight"].is_null());
}

TEST(TestEstimator, TheLibraryChecksItsParameterAgainstItsDeclaration) {
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.5, 0});
  FormFactorOptions o;
  o.estimator = "uniform";
  o.run.progress = false;
  // Unset: the declared default, which the kernel reads (each row sums to it).
  const FormFactors ff = compute_form_factors(mesh, o);
  for (Eigen::Index i = 0; i < ff.F.rows(); ++i) EXPECT_NEAR(ff.F.row(i).sum(), 0.5, 1e-14);
  for (const double bad : {0.0, 1.5}) {
    set_estimator_param(o, "--uniform-weight", bad);
    EXPECT_THROW(compute_form_factors(mesh, o), UsageError) << bad;
  }
}

}  // namespace
}  // namespace lambert
