// `--method hierarchical` through the CLI on the built-in Cornell box: every command writes
// what its matrix counterpart writes, for the leaf mesh; the energy balance holds; the
// per-surface averages agree with the matrix method within both methods' estimated errors.
// Coarse epsilons and small images keep each test to a few seconds on 2 cores.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "io/exr.hpp"

namespace lambert {
namespace {

using testing::read_json;
using testing::run;
using testing::slurp;

// Runs the command with stdout captured; returns the exit code and stdout.
std::pair<int, std::string> run_quietly(const std::vector<std::string>& args) {
  ::testing::internal::CaptureStdout();
  const int code = run(args);
  return {code, ::testing::internal::GetCapturedStdout()};
}

std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

// Per-surface average radiosity from a `solve` summary or a `run` report's list.
std::map<std::string, std::vector<double>> averages(const nlohmann::json& surfaces) {
  std::map<std::string, std::vector<double>> out;
  for (const auto& s : surfaces)
    out[s.at("name").get<std::string>()] = s.at("average_radiosity").get<std::vector<double>>();
  return out;
}

// Largest reflectance of the built-in Cornell box (the light's Kd 0.78; the walls <= 0.74).
constexpr double kCornellRhoMax = 0.78;

// The hierarchical energy balance is an identity up to rounding: with the header's
// definitions, emitted - absorbed - escaped = sum over leaves of A (E + rho H - B), and every
// leaf's B is E + rho H after a sweep's push-pull. Four sums of n terms each carry a rounding
// error <= n u x (their total), and each total is <= the power sent, sum A B <= emitted /
// (1 - rho_max) (every bounce keeps at most rho_max): relative imbalance <= 4 n u /
// (1 - rho_max).
double rounding_bound(std::int64_t leaves) {
  const double u = std::numeric_limits<double>::epsilon() / 2;
  return 4.0 * static_cast<double>(leaves) * u / (1.0 - kCornellRhoMax);
}

void expect_balanced(const nlohmann::json& energy, std::int64_t leaves) {
  ASSERT_EQ(energy.size(), 3u);
  for (const auto& e : energy) {
    // The matrix method's keys that apply; no residual / non-reciprocity split (no F).
    for (const char* key : {"emitted", "absorbed", "escaped", "relative_imbalance"})
      EXPECT_TRUE(e.contains(key)) << key;
    EXPECT_FALSE(e.contains("residual_part"));
    EXPECT_GT(e.at("emitted").get<double>(), 0.0);
    EXPECT_GT(e.at("absorbed").get<double>(), 0.0);
    EXPECT_GT(e.at("escaped").get<double>(), 0.0);  // the box is open at the front
    EXPECT_LE(e.at("relative_imbalance").get<double>(), rounding_bound(leaves)) << e.dump();
  }
}

}  // namespace

TEST(HierarchicalRun, CornellBoxWritesEveryFileWithABalancedReport) {
  testing::TempDir dir;
  const std::string out = dir.file("h");
  const auto [code, text] =
      run_quietly({"run", "--method", "hierarchical", "--epsilon", "1e-2", "-o", out, "--size",
                   "32x32", "--antialias", "1", "-q", "-j", "2"});
  ASSERT_EQ(code, kExitOk) << text;
  for (const char* f : {"cornell.exr", "cornell.png", "cornell_vertices.exr", "cornell.ply",
                        "cornell.glb", "index.html", "report.json"}) {
    const std::string path = out + "/" + f;
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    EXPECT_GT(std::filesystem::file_size(path), 0u) << path;
    EXPECT_NE(text.find(path), std::string::npos) << "summary does not list " << path;
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(out),
                          std::filesystem::directory_iterator()),
            7);  // no temporaries left
  const nlohmann::json report = read_json(out + "/report.json");
  EXPECT_EQ(report.at("method"), "hierarchical");
  EXPECT_FALSE(report.contains("form_factors"));
  const nlohmann::json& h = report.at("hierarchical");
  EXPECT_EQ(h.at("status"), "converged");
  EXPECT_EQ(h.at("options").at("epsilon").get<double>(), 1e-2);
  EXPECT_EQ(h.at("options").at("link_rays").get<int>(), 16);
  // Without --tol the method's own default (a relative change), not the solvers' 1e-8.
  EXPECT_EQ(h.at("options").at("tol").get<double>(), 1e-6);
  EXPECT_LE(h.at("change").get<double>(), 1e-6);
  const auto leaves = h.at("leaves").get<std::int64_t>();
  EXPECT_EQ(report.at("patches").get<std::int64_t>(), leaves);
  // The leaves refine the 20 root faces (the mesher's faces of the box, no edge bound).
  EXPECT_EQ(h.at("faces").get<std::int64_t>(), 20);
  EXPECT_GE(leaves, h.at("faces").get<std::int64_t>());
  EXPECT_GT(h.at("links").get<std::int64_t>(), 0);
  EXPECT_GT(h.at("rays").get<std::int64_t>(), 0);
  // Per-surface one-bounce error bounds: one per surface, finite, positive where the surface
  // receives light through links (every surface of the box does).
  ASSERT_EQ(h.at("surface_error_bounds").size(), 8u);
  for (const auto& b : h.at("surface_error_bounds")) {
    const double v = b.at("error_bound").get<double>();
    EXPECT_TRUE(std::isfinite(v) && v > 0.0) << b.at("name");
  }
  EXPECT_EQ(report.at("rays_total").get<std::int64_t>(),
            h.at("rays").get<std::int64_t>() + report.at("render").at("rays").get<std::int64_t>());
  expect_balanced(report.at("energy_balance"), leaves);
  // The light is the only emitter: emitted = A_light Ke = 13650 x (17, 11.8, 4), a sum of a
  // few leaf areas that tile it exactly (to rounding, 1e-12 relative).
  const auto& e = report.at("energy_balance");
  EXPECT_NEAR(e[0].at("emitted").get<double>(), 13650.0 * 17.0, 1e-12 * 13650.0 * 17.0);
  EXPECT_NEAR(e[2].at("emitted").get<double>(), 13650.0 * 4.0, 1e-12 * 13650.0 * 4.0);
  const auto& power = report.at("vertex_power");
  EXPECT_LE(power.at("max_relative_error").get<double>(), power.at("tolerance").get<double>());
  ASSERT_EQ(report.at("surface_averages").size(), 8u);
  std::int64_t patches = 0;
  for (const auto& s : report.at("surface_averages")) patches += s.at("patches").get<int>();
  EXPECT_EQ(patches, leaves);
  const Image img = read_image_exr(out + "/cornell.exr");
  EXPECT_EQ(img.width, 32);
  const VertexExr v = read_vertex_exr(out + "/cornell_vertices.exr");
  EXPECT_EQ(v.info.surface_names.size(), 8u);
  EXPECT_NE(v.info.settings.find("method=hierarchical"), std::string::npos) << v.info.settings;
  for (const char* word : {"leaves", "links", "hierarchy", "energy", "time", "files"})
    EXPECT_NE(text.find(word), std::string::npos) << word;
}

// The matrix method at N and 4N patches and the hierarchical at epsilon and epsilon/4: each
// pair's difference estimates the error of its coarser member, which bounds the finer one's
// when the error falls under refinement (4N patches halve the patch size; the issue asks the
// hierarchical error to fall as epsilon falls). Then |B_h(eps) - B_m(4N)| <= err_h(eps) +
// err_m(4N) <= 2 (|B_h(eps) - B_h(eps/4)| + |B_m(N) - B_m(4N)|): a one-step estimate
// underrates an error by 1/(1 - r), r the ratio of successive errors, 2 for r <= 1/2. The
// matrix runs use hybrid with 4 samples: its visibility noise is part of |B_m(N) - B_m(4N)|.
TEST(HierarchicalSolveSlow, SurfaceAveragesAgreeWithTheMatrixMethodWithinBothErrors) {
  testing::TempDir dir;
  const auto solve = [&](std::vector<std::string> args, const std::string& name) {
    args.insert(args.begin(), "solve");
    args.insert(args.end(), {"-o", dir.file(name + ".csv"), "-q", "-j", "2"});
    const auto [code, text] = run_quietly(args);
    EXPECT_EQ(code, kExitOk) << name;
    return averages(read_json(dir.file(name + ".json")).at("surfaces"));
  };
  const auto m1 = solve({"--patches", "500", "--samples", "4"}, "m1");
  const auto m4 = solve({"--patches", "2000", "--samples", "4"}, "m4");
  const auto h1 = solve({"--method", "hierarchical", "--epsilon", "1e-4"}, "h1");
  const auto h4 = solve({"--method", "hierarchical", "--epsilon", "2.5e-5"}, "h4");
  ASSERT_EQ(m1.size(), 8u);
  for (const auto& [name, m] : m4) {
    ASSERT_TRUE(h1.count(name) && h4.count(name) && m1.count(name)) << name;
    for (int c = 0; c < 3; ++c) {
      const double err_m = std::abs(m1.at(name)[c] - m[c]);
      const double err_h = std::abs(h1.at(name)[c] - h4.at(name)[c]);
      EXPECT_LE(std::abs(h1.at(name)[c] - m[c]), 2.0 * (err_h + err_m))
          << name << " channel " << c << ": hierarchical " << h1.at(name)[c] << " (eps/4 "
          << h4.at(name)[c] << "), matrix " << m[c] << " (N/4 " << m1.at(name)[c] << ")";
    }
  }
}

TEST(HierarchicalSolve, WritesOneCsvRowPerLeafAndTheOptionsItWasGiven) {
  testing::TempDir dir;
  const std::string csv = dir.file("B.csv");
  const auto [code, text] =
      run_quietly({"solve",      "--method",   "hierarchical", "--epsilon", "2e-2",
                   "--min-area", "200",        "--link-rays",  "8",         "--tol",
                   "1e-5",       "--max-iter", "500",          "--seed",    "3",
                   "-o",         csv,          "-q",           "-j",        "2"});
  ASSERT_EQ(code, kExitOk) << text;
  const auto rows = read_csv(csv);
  ASSERT_GT(rows.size(), 1u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"patch", "surface", "area", "R", "G", "B"}));
  const nlohmann::json j = read_json(dir.file("B.json"));
  EXPECT_EQ(j.at("method"), "hierarchical");
  EXPECT_EQ(j.at("status"), "converged");
  const nlohmann::json& h = j.at("hierarchical");
  EXPECT_EQ(j.at("patches").get<std::size_t>(), rows.size() - 1);
  EXPECT_EQ(h.at("leaves").get<std::size_t>(), rows.size() - 1);
  const nlohmann::json& o = h.at("options");
  EXPECT_EQ(o.at("epsilon").get<double>(), 2e-2);
  EXPECT_EQ(o.at("min_area").get<double>(), 200.0);
  EXPECT_EQ(h.at("min_area").get<double>(), 200.0);  // given, so used as it is
  EXPECT_EQ(o.at("link_rays").get<int>(), 8);
  EXPECT_EQ(o.at("tol").get<double>(), 1e-5);
  EXPECT_EQ(o.at("max_iterations").get<int>(), 500);
  EXPECT_EQ(o.at("seed").get<std::uint64_t>(), 3u);
  EXPECT_LE(j.at("change").get<double>(), 1e-5);
  // No leaf is below the area bound: a split keeps every child at >= min_area. (The CSV
  // prints %.17g, which reads back exactly.)
  double csv_area = 0.0;
  for (size_t k = 1; k < rows.size(); ++k) {
    const double a = std::stod(rows[k][2]);
    EXPECT_GE(a, 200.0) << "leaf " << rows[k][0];
    csv_area += a;
  }
  // The leaves tile the faces: the surfaces' areas add up to the leaves' (two sums of a few
  // hundred terms: 1e-12 relative is rounding with a margin).
  double area = 0.0;
  for (const auto& s : j.at("surfaces")) area += s.at("area").get<double>();
  EXPECT_NEAR(area, csv_area, 1e-12 * csv_area);
  ASSERT_EQ(j.at("channels").size(), 3u);
  nlohmann::json energy = nlohmann::json::array();
  for (const auto& c : j.at("channels")) energy.push_back(c.at("energy"));
  expect_balanced(energy, h.at("leaves").get<std::int64_t>());
}

TEST(HierarchicalSolve, ResultsAreIdenticalForAnyThreadCount) {
  testing::TempDir dir;
  for (const char* j : {"1", "2"})
    ASSERT_EQ(run_quietly({"solve", "--method", "hierarchical", "--epsilon", "2e-2", "-j", j, "-o",
                           dir.file(std::string("B") + j + ".csv"), "-q"})
                  .first,
              kExitOk);
  EXPECT_EQ(slurp(dir.file("B1.csv")), slurp(dir.file("B2.csv")));
}

TEST(HierarchicalSolve, NonConvergenceExitsWithThreeAndStillWrites) {
  testing::TempDir dir;
  const std::string csv = dir.file("B.csv");
  ::testing::internal::CaptureStderr();
  const auto [code, text] = run_quietly(
      {"solve", "--method", "hierarchical", "--epsilon", "2e-2", "--max-iter", "1", "-o", csv});
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, kExitNotConverged) << text;
  EXPECT_NE(err.find("warning:"), std::string::npos) << err;
  EXPECT_TRUE(std::filesystem::exists(csv));
  const nlohmann::json j = read_json(dir.file("B.json"));
  EXPECT_EQ(j.at("status"), "max-iterations");
  EXPECT_FALSE(j.at("hierarchical").at("converged").get<bool>());
}

TEST(HierarchicalSolve, MemoryLimitStopsTheSolveWithOneLine) {
  testing::TempDir dir;
  ::testing::internal::CaptureStderr();
  const auto [code, text] = run_quietly(
      {"solve", "--method", "hierarchical", "--max-memory", "16K", "-o", dir.file("B.csv"), "-q"});
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, kExitFailure) << text;
  EXPECT_NE(err.find("16.0 KiB"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("B.csv")));
}

// Peak resident memory (bytes) and exit code of the lambert binary run with `args`.
std::pair<long, int> peak_of_lambert(const std::vector<std::string>& args) {
  std::vector<std::string> all = {LAMBERT_BIN};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t child = ::fork();
  if (child == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  struct rusage use {};
  ::wait4(child, &status, 0, &use);
  return {use.ru_maxrss * 1024L, WIFEXITED(status) ? WEXITSTATUS(status) : -1};
}

TEST(HierarchicalSolveSlow, TheMemoryLimitBoundsThePeakNotJustTheStateAfterAWave) {
  // --epsilon 1e-300 refines until the limit stops it. The limit bounds the hierarchy's
  // nodes, links and BVH at their peak: the process may use at most the limit beyond what
  // the same solve uses at the default epsilon (the rest of the process, and a small
  // hierarchy). It used to check after each wave had been allocated, and a wave of the
  // Cornell box grows the links ~4x: 100 MiB gave a 243 MB peak (200 MB over that base).
  testing::TempDir dir;
  const std::vector<std::string> solve = {"solve", "--method", "hierarchical",
                                          "-q",    "-o",       dir.file("B.csv")};
  const auto [base, base_code] = peak_of_lambert(solve);
  ASSERT_EQ(base_code, kExitOk);
  std::vector<std::string> fine = solve;
  for (const char* a : {"--epsilon", "1e-300", "--max-memory", "100M"}) fine.push_back(a);
  const auto [peak, code] = peak_of_lambert(fine);
  EXPECT_EQ(code, kExitFailure);
  EXPECT_LE(peak - base, 100L << 20) << "peak " << peak << " B, base " << base << " B";
}

TEST(HierarchicalRender, SolvesAndWritesEveryRequestedFile) {
  testing::TempDir dir;
  const auto [code, text] =
      run_quietly({"render", "--method", "hierarchical", "--epsilon", "2e-2", "-o",
                   dir.file("img.exr"), "--size", "24x16", "--vertex-exr", dir.file("v.exr"),
                   "--ply", dir.file("m.ply"), "-q", "-j", "2"});
  ASSERT_EQ(code, kExitOk) << text;
  for (const char* f : {"img.exr", "img.png", "v.exr", "m.ply"})
    EXPECT_TRUE(std::filesystem::exists(dir.file(f))) << f;
  const Image img = read_image_exr(dir.file("img.exr"));
  EXPECT_EQ(img.width, 24);
  EXPECT_EQ(img.height, 16);
}

TEST(HierarchicalCompare, WritesOneRowPerEpsilonAgainstTheMatrixReference) {
  testing::TempDir dir;
  const auto [code, text] =
      run_quietly({"compare", "--method", "hierarchical", "--epsilon", "2e-2,1e-2", "--patches",
                   "150", "--samples", "4", "-o", dir.file("c/"), "-q", "-j", "2"});
  ASSERT_EQ(code, kExitOk) << text;
  const auto table = read_csv(dir.file("c/compare_table.csv"));
  ASSERT_EQ(table.size(), 4u);  // header, the reference, one row per epsilon
  EXPECT_EQ(table[0][0], "method");
  EXPECT_EQ(table[1][0], "matrix");
  EXPECT_EQ(table[1][6], "reference");
  const auto surfaces = read_csv(dir.file("c/compare_surfaces.csv"));
  ASSERT_EQ(surfaces.size(), 1u + 8u * 3u);  // per surface: the reference and two runs
  for (size_t r = 2; r < table.size(); ++r) {
    EXPECT_EQ(table[r][0], "hierarchical");
    EXPECT_EQ(table[r][6], "converged");
    // The table's max is the largest per-surface difference of that epsilon's rows.
    double max_diff = 0.0;
    for (const auto& row : surfaces)
      if (row[2] == "hierarchical" && row[3] == table[r][1])
        for (int c = 7; c < 10; ++c)
          if (!row[c].empty()) max_diff = std::max(max_diff, std::stod(row[c]));
    EXPECT_EQ(std::stod(table[r][7]), max_diff) << table[r][1];
    EXPECT_GT(max_diff, 0.0);
  }
}

}  // namespace lambert
