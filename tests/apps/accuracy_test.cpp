#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "geometry/analytic.hpp"

namespace lambert {

using testing::run;
using testing::slurp;
namespace {


std::vector<std::string> lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

std::uintmax_t size_of(const std::string& path) {
  std::error_code ec;
  const auto s = std::filesystem::file_size(path, ec);
  return ec ? 0 : s;
}

// Column `name` of a CSV data line (no quoted fields in these tables).
std::string column(const std::string& header, const std::string& line, const std::string& name) {
  std::stringstream h(header), l(line);
  for (std::string k, v; std::getline(h, k, ',') && std::getline(l, v, ',');)
    if (k == name) return v;
  return "";
}

}  // namespace

TEST(AccuracyCommand, TinyAnalyticCaseWritesTableCsvAndPlots) {
  testing::TempDir dir;
  const std::string prefix = dir.file("acc");
  ASSERT_EQ(run({"accuracy", "--case", "perpendicular_squares", "--max-edge", "0.5", "-q",
                 "--mc-samples", "4", "--hybrid-samples", "4", "--hemicube-res", "16,32",
                 "--symmetrize", "-o", prefix}),
            kExitOk);
  for (const char* suffix : {"_table.csv", "_surfaces.csv", "_error_vs_time.svg"})
    EXPECT_GT(size_of(prefix + suffix), 0u) << suffix;
  const auto table = lines(prefix + "_table.csv");
  // Header, the reference, mc k=4, hybrid k=4, hemicube and hemicube-sym at N=16 and 32.
  ASSERT_EQ(table.size(), 1u + 1u + 1u + 1u + 4u);
  EXPECT_EQ(column(table[0], table[1], "setting"), "reference");
  EXPECT_EQ(column(table[0], table[4], "estimator"), "hemicube");
  EXPECT_EQ(column(table[0], table[4], "setting"), "N=16");
  // The symmetrized hemicube is reciprocal to rounding (relative 1e-12 of F ~ 0.2 is far
  // above the 4 ulp the symmetrization leaves); the plain one is not.
  EXPECT_LT(std::stod(column(table[0], table[5], "reciprocity")), 1e-12);
  EXPECT_GT(std::stod(column(table[0], table[4], "reciprocity")), 1e-12);
  // The hybrid estimator is exact for this unoccluded case to its quadrature error (~1e-5
  // for neighbours, see FormFactorHybrid.IsExactForUnoccludedPairs).
  EXPECT_LT(std::stod(column(table[0], table[3], "F_exact_abs_err")), 1e-5);
  const std::string svg = [&] {
    std::ifstream in(prefix + "_error_vs_time.svg");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }();
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("hemicube"), std::string::npos);
}

// The occluded partial_shadow case: the exact floor-to-light factor past the blocker is the
// reference for the surface factor (F_ab), and the hybrid reference's per-patch F lies near
// it. Tolerance: the surface factor sums the pairs' visible fractions, each a binomial of k
// = 256 rays (σ ≤ 1/(2√k) of its G); even fully correlated errors give σ ≤ F/(2√k) = F/32,
// so 4σ = F/8. The unoccluded factor (0.0220) is 32 % above the exact 0.0167: a case that
// ignored the blocker fails.
TEST(AccuracyCommand, PartialShadowCaseHasAnExactOccludedSurfaceFactor) {
  testing::TempDir dir;
  const std::string prefix = dir.file("acc");
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(run({"accuracy", "--case", "partial_shadow", "--max-edge", "1", "-q", "--estimators",
                 "hybrid", "--hybrid-samples", "16", "--reference-samples", "256", "-o", prefix}),
            kExitOk);
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("partial-shadow kernel"), std::string::npos) << out;
  const auto table = lines(prefix + "_table.csv");
  ASSERT_EQ(table.size(), 3u);  // header, reference, hybrid k=16
  const double exact = partial_shadow_floor_light_factor();
  const double f_ref = std::stod(column(table[0], table[1], "F_ab"));
  EXPECT_NEAR(f_ref, exact, exact / 8) << "reference F(floor->light)";
  // F_exact_abs_err is the max over both directions; F(light->floor) = 16 F(floor->light)
  // (the areas' ratio) with the same relative bound.
  EXPECT_LE(std::stod(column(table[0], table[1], "F_exact_abs_err")), 16 * exact / 8);
  EXPECT_GE(std::stod(column(table[0], table[1], "F_exact_abs_err")), std::abs(f_ref - exact));
}

TEST(AccuracyCommand, SceneWithoutClosedFormUsesAHybridReference) {
  testing::TempDir dir;
  const std::string out = dir.path().string() + "/";
  ASSERT_EQ(run({"accuracy", "--patches", "40", "-q", "--estimators", "hemicube",
                 "--hemicube-res", "16", "--reference-samples", "16", "-o", out}),
            kExitOk);
  const auto table = lines(out + "accuracy_table.csv");
  ASSERT_EQ(table.size(), 3u);
  EXPECT_EQ(column(table[0], table[1], "estimator"), "hybrid");
  EXPECT_EQ(column(table[0], table[1], "setting"), "reference");
  EXPECT_GT(size_of(out + "accuracy_error_vs_time.svg"), 0u);
}

// With a medium every F, the reference's too, has each patch pair's factor multiplied by
// the same kernel-weighted transmittance T (same pair streams whatever the estimator), so
// each per-pair error is T times the one without the medium. Between the squares 1 apart
// every segment runs >= 1 through the box's sigma_t = 0.5, so T <= exp(-0.5): the hemicube's
// max and RMS |dF| shrink at least that much (rounding: 1e-12 relative).
TEST(AccuracyCommand, AMediumScalesEveryPairErrorByItsTransmittance) {
  testing::TempDir dir;
  const std::vector<std::string> common = {
      "accuracy", "--case",       "parallel_squares", "--max-edge",     "0.25",
      "-q",       "--estimators", "hemicube",         "--hemicube-res", "16"};
  std::vector<std::string> clear = common, fog = common;
  clear.insert(clear.end(), {"-o", dir.file("clear")});
  fog.insert(fog.end(), {"-o", dir.file("fog"), "--medium-box", "-1,-1,-1,2,2,2", "--sigma-a",
                         "0.5,0.5,0.5", "--voxels", "3", "--medium-rays", "16"});
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(run(clear), kExitOk);
  ASSERT_EQ(run(fog), kExitOk);
  const std::string text = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(text.find("27 zones"), std::string::npos) << text;
  const auto a = lines(dir.file("clear") + "_table.csv");
  const auto b = lines(dir.file("fog") + "_table.csv");
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 3u);
  const double bound = std::exp(-0.5) * (1 + 1e-12);
  for (const char* col : {"max_abs_err", "rms_abs_err"}) {
    const double without = std::stod(column(a[0], a[2], col));
    const double with = std::stod(column(b[0], b[2], col));
    EXPECT_GT(without, 0.0) << col;
    EXPECT_LE(with, bound * without) << col;
    EXPECT_GT(with, 0.0) << col;
  }
  // The closed form holds without a medium only: not compared (empty in the CSV).
  EXPECT_EQ(column(b[0], b[2], "F_exact_abs_err"), "nan");
}

TEST(AccuracyCommand, SceneAndCaseTogetherIsAUsageError) {
  EXPECT_EQ(run({"accuracy", "some.obj", "--case", "unit_cube", "-q"}), kExitUsage);
}

}  // namespace lambert

namespace lambert {

// --estimators gather --gather-rays: one row per K, and its F within 4 standard errors of
// the closed form. Unit squares 1 apart, one patch each, F = 0.19982; one row's K = 4096
// Bernoulli rays have sigma <= sqrt(F (1 - F) / K) = 0.0063 (the stratified lattice only
// lowers it, averaging with the mirror row lowers it by up to sqrt 2): 4 sigma = 0.025.
TEST(AccuracyCommand, GatherRunsAtEveryRequestedRayCount) {
  testing::TempDir dir;
  const std::string prefix = dir.file("acc");
  ASSERT_EQ(run({"accuracy", "--case", "parallel_squares", "--max-edge", "1", "-q",
                 "--estimators", "gather", "--gather-rays", "1024,4096", "-o", prefix}),
            kExitOk);
  const auto table = lines(prefix + "_table.csv");
  ASSERT_EQ(table.size(), 1u + 1u + 2u);  // header, reference, K = 1024 and 4096
  EXPECT_EQ(column(table[0], table[2], "estimator"), "gather");
  EXPECT_EQ(column(table[0], table[2], "setting"), "K=1024");
  EXPECT_EQ(column(table[0], table[3], "setting"), "K=4096");
  EXPECT_LT(std::stod(column(table[0], table[3], "F_exact_abs_err")), 0.025);
}

}  // namespace lambert
