// `lambert heat` end to end: tessellated concentric spheres against the two-surface formula,
// parallel plates with re-radiating walls against the three-surface network, an isothermal
// enclosure, the energy closure, the outputs and the exit codes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/stl_text.hpp"
#include "common/temp_dir.hpp"
#include "geometry/analytic.hpp"
#include "io/exr.hpp"
#include "io/json.hpp"
#include "solvers/thermal.hpp"

namespace lambert {
namespace {

using testing::ascii_stl;
using testing::read_json;
using testing::run;
using testing::slurp;
using testing::TempDir;
using Tri = std::array<Eigen::Vector3d, 3>;

// An icosphere of radius r: the icosahedron's faces split `levels` times, corners pushed to
// the sphere; wound counter-clockwise seen from outside (`inward` reverses it).
std::vector<Tri> icosphere(double r, int levels, bool inward) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  const int f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                        {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                        {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                        {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  std::vector<Tri> tris;
  for (const auto& k : f)
    tris.push_back({v[k[0]].normalized(), v[k[1]].normalized(), v[k[2]].normalized()});
  for (int l = 0; l < levels; ++l) {
    std::vector<Tri> finer;
    for (const auto& a : tris) {
      const Eigen::Vector3d ab = (a[0] + a[1]).normalized(), bc = (a[1] + a[2]).normalized(),
                            ca = (a[2] + a[0]).normalized();
      finer.push_back({a[0], ab, ca});
      finer.push_back({ab, a[1], bc});
      finer.push_back({ca, bc, a[2]});
      finer.push_back({ab, bc, ca});
    }
    tris.swap(finer);
  }
  for (auto& a : tris) {
    for (auto& p : a) p *= r;
    if (inward) std::swap(a[1], a[2]);
  }
  return tris;
}

// A quad (counter-clockwise about its front) as two triangles.
std::vector<Tri> quad(Eigen::Vector3d a, Eigen::Vector3d b, Eigen::Vector3d c, Eigen::Vector3d d) {
  return {{a, b, c}, {a, c, d}};
}

const Json& surface(const Json& j, const std::string& name) {
  for (const auto& s : j["surfaces"])
    if (s["name"] == name) return s;
  throw std::runtime_error("no surface " + name);
}

double sigma_t4(double t) { return kStefanBoltzmann * std::pow(t, 4); }

// Two unit squares at distance 0.5 (hot at z = 0 facing up, cold at z = 0.5 facing down)
// closed by four 1 x 0.5 walls facing in.
std::vector<std::pair<std::string, std::vector<Tri>>> plates_box(bool walls) {
  using V = Eigen::Vector3d;
  const double h = 0.5;
  std::vector<std::pair<std::string, std::vector<Tri>>> s = {
      {"hot", quad(V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0))},
      {"cold", quad(V(0, 0, h), V(0, 1, h), V(1, 1, h), V(1, 0, h))}};
  if (!walls) return s;
  std::vector<Tri> w;
  for (const auto& q : {quad(V(0, 0, 0), V(0, 0, h), V(1, 0, h), V(1, 0, 0)),
                        quad(V(1, 0, 0), V(1, 0, h), V(1, 1, h), V(1, 1, 0)),
                        quad(V(1, 1, 0), V(1, 1, h), V(0, 1, h), V(0, 1, 0)),
                        quad(V(0, 1, 0), V(0, 1, h), V(0, 0, h), V(0, 0, 0))})
    w.insert(w.end(), q.begin(), q.end());
  s.emplace_back("walls", w);
  return s;
}

TEST(HeatCliSlow, ConcentricSpheresMatchTheTwoSurfaceFormula) {
  const TempDir dir;
  // Level 2: 320 triangles per sphere; one patch each (--max-edge above every edge).
  const std::string stl = dir.write("spheres.stl", ascii_stl({{"inner", icosphere(1.0, 2, false)},
                                                              {"outer", icosphere(2.0, 2, true)}}));
  const double e1 = 0.4, e2 = 0.7, t1 = 800.0, t2 = 300.0;
  const std::string json = dir.write("s.json", R"({"inner": {"emissivity": 0.4, "temperature": 800},
                    "outer": {"emissivity": 0.7, "temperature": 300}})");
  ASSERT_EQ(run({"heat", stl, "--surfaces", json, "--max-edge", "10", "--estimator", "hybrid",
                 "--seed", "7", "-o", dir.file("sph"), "-q"}),
            0);
  const Json j = read_json(dir.file("sph.json"));
  const double a1 = surface(j, "inner")["area_m2"], a2 = surface(j, "outer")["area_m2"];
  const double q1 = kStefanBoltzmann * a1 * (std::pow(t1, 4) - std::pow(t2, 4)) /
                    (1.0 / e1 + (a1 / a2) * (1.0 / e2 - 1.0));
  const double got = surface(j, "inner")["power_W"];
  // With the mesh's own areas the formula holds for any convex inner body fully enclosed
  // (F_12 = 1 exactly), up to the non-uniform radiosity of the polyhedral outer surface (its
  // facets differ in size by up to ~1.4x: measured effect < 1e-4) and the
  // estimator's error in the outer's self-view F_22, which enters through A1/A2 only via
  // reciprocity: hybrid's quadrature bound is 1e-6 per entry (docs/form-factors.md), its visibility
  // sampling of the occluded outer-outer pairs ~1e-3 of F_22 per row (32 samples); Q1 depends
  // on F_22 weakly (only the outer's reflections). 2e-3 relative covers both with margin.
  std::printf("spheres: Q1 %.9g, formula %.9g (A1 %.6g, A2 %.6g), relative error %.3e\n", got, q1,
              a1, a2, std::abs(got / q1 - 1.0));
  EXPECT_NEAR(got, q1, 2e-3 * q1);
  EXPECT_NEAR(double(surface(j, "outer")["power_W"]), -q1, 2e-3 * q1);
  EXPECT_NEAR(double(j["closure"]["sum_W"]), 0.0, 1e-9 * q1);
}

// The plates box as an OBJ of quads (an STL would split each face into two triangles).
std::string plates_box_obj() {
  std::string s;
  char buf[100];
  for (const auto& [name, tris] : plates_box(true)) {
    s += "g " + name + "\n";
    for (size_t k = 0; k < tris.size(); k += 2) {  // (a, b, c), (a, c, d) -> a b c d
      for (const auto& p : {tris[k][0], tris[k][1], tris[k][2], tris[k + 1][2]}) {
        std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
        s += buf;
      }
      s += "f -4 -3 -2 -1\n";
    }
  }
  return s;
}

// Open coaxial prisms of n sides (radii r1 < r2 of their corners, length len, along z) as an
// OBJ of quads: the inner one facing out, the outer one facing in, each split lengthwise into
// `rows` quads and into three groups: NAME_end (first and last quarter) and NAME_mid.
std::string coaxial_obj(double r1, double r2, double len, int n, int rows) {
  std::string s;
  char buf[120];
  auto corner = [&](double r, int k, int row) {
    const double a = 2.0 * M_PI * k / n;
    return Eigen::Vector3d(r * std::cos(a), r * std::sin(a), len * row / rows);
  };
  for (const auto& [name, r, out] : {std::tuple<std::string, double, bool>{"inner", r1, true},
                                     std::tuple<std::string, double, bool>{"outer", r2, false}}) {
    for (int row = 0; row < rows; ++row) {
      const bool mid = row >= rows / 4 && row < rows - rows / 4;
      s += "g " + name + (mid ? "_mid" : "_end") + "\n";
      for (int k = 0; k < n; ++k) {
        std::array<Eigen::Vector3d, 4> q = {corner(r, k, row), corner(r, k + 1, row),
                                            corner(r, k + 1, row + 1), corner(r, k, row + 1)};
        if (!out) std::swap(q[1], q[3]);
        for (const auto& p : q) {
          std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
          s += buf;
        }
        s += "f -4 -3 -2 -1\n";
      }
    }
  }
  return s;
}

TEST(HeatCliSlow, LongCoaxialCylindersMatchTheInfiniteFormulaInTheMiddle) {
  const TempDir dir;
  const double r1 = 1.0, r2 = 2.0, len = 40.0;
  const std::string obj = dir.write("coax.obj", coaxial_obj(r1, r2, len, 24, 20));
  const std::string json =
      dir.write("s.json", R"({"inner_mid": {"emissivity": 0.4, "temperature": 800},
                    "inner_end": {"emissivity": 0.4, "temperature": 800},
                    "outer_mid": {"emissivity": 0.7, "temperature": 300},
                    "outer_end": {"emissivity": 0.7, "temperature": 300}})");
  ASSERT_EQ(run({"heat", obj, "--surfaces", json, "--max-edge", "100", "--estimator", "hybrid",
                 "--seed", "3", "-o", dir.file("coax"), "-q"}),
            0);
  const Json j = read_json(dir.file("coax.json"));
  // Per unit area of the inner surface, for infinitely long cylinders; the inscribed n-gons
  // keep A1/A2 = r1/r2 exactly and the inner prism is convex (F_12 = 1 but for the ends).
  const double e1 = 0.4, e2 = 0.7;
  const double q1 = kStefanBoltzmann * (std::pow(800.0, 4) - std::pow(300.0, 4)) /
                    (1.0 / e1 + (r1 / r2) * (1.0 / e2 - 1.0));
  const double got = double(surface(j, "inner_mid")["heat_flux_W_m2"]);
  // The middle half lies >= 10 from either open end (0 K): the annular opening (area
  // pi (r2² - r1²) = 9.4) seen from there subtends at most A / (pi d²) = 0.03 of a
  // hemisphere, and radiation reaches it only along the 1-wide gap at grazing angles, after
  // reflections that each keep at most 1 - e of it (0.6 and 0.3 here), so the end effect
  // on q is well below 0.03 * 0.6 * 0.3 = 5e-3 of it; the total error measured (end effect
  // plus hybrid's sampling at 32 samples, seed 3) is 8e-5. 1e-3 relative holds both.
  std::printf("coaxial: q1 middle %.9g, infinite formula %.9g, relative error %.3e\n", got, q1,
              std::abs(got / q1 - 1.0));
  EXPECT_NEAR(got, q1, 1e-3 * q1);
}

TEST(HeatCli, ReradiatingWallsMatchTheThreeSurfaceNetwork) {
  const TempDir dir;
  const std::string stl = dir.write("plates.obj", plates_box_obj());
  const std::string json = dir.write("s.json", R"({"hot": {"emissivity": 0.8, "temperature": 900},
                    "cold": {"emissivity": 0.5, "temperature": 350},
                    "walls": {"emissivity": 0.3, "heat_flux": 0}})");
  // One patch per face (quads): each plate is one patch, the four walls are one patch each
  // and equal by symmetry, so the lumped three-surface network is exact for this mesh.
  ASSERT_EQ(run({"heat", stl, "--surfaces", json, "--max-edge", "10", "--estimator", "analytic",
                 "--ff-tol", "1e-10", "--solver", "direct", "-o", dir.file("pl"), "-q"}),
            0);
  const Json j = read_json(dir.file("pl.json"));
  const double e1 = 0.8, e2 = 0.5, f12 = parallel_rectangles_factor(1.0, 1.0, 0.5);
  const double f1r = 1.0 - f12, f2r = 1.0 - f12;
  const double space = 1.0 / (f12 + 1.0 / (1.0 / f1r + 1.0 / f2r));  // A1 = 1 m²
  const double q1 = (sigma_t4(900) - sigma_t4(350)) / ((1 - e1) / e1 + space + (1 - e2) / e2);
  const double j1 = sigma_t4(900) - q1 * (1 - e1) / e1, j2 = sigma_t4(350) + q1 * (1 - e2) / e2;
  const double tr = std::pow((f1r * j1 + f2r * j2) / (f1r + f2r) / kStefanBoltzmann, 0.25);
  // The analytic factors are within 1e-10 absolute per entry (--ff-tol); Q1 and J_R move by
  // at most ~10 sigma T1^4 per unit change of a factor in this network (the largest
  // derivative, through the space resistance), i.e. ~1e-9 relative; direct solve: rounding.
  // 1e-7 relative covers both with margin.
  const double got_q = surface(j, "hot")["power_W"], got_t = surface(j, "walls")["temperature_K"];
  std::printf("plates: Q1 %.12g vs %.12g (%.2e), T_R %.12g vs %.12g (%.2e)\n", got_q, q1,
              std::abs(got_q / q1 - 1), got_t, tr, std::abs(got_t / tr - 1));
  EXPECT_NEAR(got_q, q1, 1e-7 * q1);
  EXPECT_NEAR(got_t, tr, 1e-7 * tr);
  EXPECT_NEAR(double(surface(j, "walls")["power_W"]), 0.0, 1e-7 * q1);
}

TEST(HeatCli, IsothermalEnclosureHasNoNetFlux) {
  const TempDir dir;
  const std::string stl = dir.write("plates.stl", ascii_stl(plates_box(true)));
  const std::string json = dir.write("s.json", R"({"hot": {"emissivity": 0.9, "temperature": 500},
                    "*": {"emissivity": 0.6, "temperature": 500}})");
  // The environment at the same temperature: J = sigma T^4 solves the system for any F (the
  // estimator's row-sum error is filled by the environment at T), so q = 0 up to the solver.
  ASSERT_EQ(run({"heat", stl, "--surfaces", json, "--patches", "200", "--ambient-temperature",
                 "500", "--tol", "1e-12", "-o", dir.file("iso"), "-q"}),
            0);
  const std::string csv = slurp(dir.file("iso_patches.csv"));
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  int rows = 0;
  double worst = 0.0;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ls(line);
    for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
    worst = std::max(worst, std::abs(std::stod(f.at(7))));
    ++rows;
  }
  EXPECT_GT(rows, 100);
  // |q| <= 2 ||K^-1||_inf tol ||E||_2 with ||K^-1||_inf <= 1/e_min = 1/0.6 and
  // ||E||_2 <= sqrt(N) sigma T^4: for N <= 400, 2/0.6 * 1e-12 * 20 * 3544 = 2.4e-7 W/m².
  EXPECT_LE(worst, 2.4e-7);
}

TEST(HeatCli, EnergyClosesForAnOpenScene) {
  const TempDir dir;
  const std::string stl = dir.write("open.stl", ascii_stl(plates_box(false)));
  const std::string json = dir.write("s.json", R"({"hot": {"emissivity": 0.8, "temperature": 700},
                    "cold": {"emissivity": 0.5, "heat_flux": -200}})");
  ASSERT_EQ(run({"heat", stl, "--surfaces", json, "--patches", "200", "--ambient-temperature",
                 "300", "-o", dir.file("open"), "-q"}),
            0);
  const Json j = read_json(dir.file("open.json"));
  const double scale = std::abs(double(surface(j, "hot")["power_W"])) +
                       std::abs(double(surface(j, "cold")["power_W"]));
  // A pair estimator keeps A_i F_ij = A_j F_ji to rounding, so sum Q + environment is an
  // identity up to rounding (~1e-16 N of the powers); 1e-10 leaves margin.
  EXPECT_NEAR(double(j["closure"]["sum_W"]), 0.0, 1e-10 * scale);
  EXPECT_LT(double(j["closure"]["environment_W"]), -0.1 * scale);  // most escapes
  // The flux surface gets its flux: to the solver's tolerance (1e-8 of ||E||).
  EXPECT_NEAR(double(surface(j, "cold")["heat_flux_W_m2"]), -200.0, 1e-3);
}

TEST(HeatCli, WritesEveryOutputAtomically) {
  const TempDir dir;
  const std::string stl = dir.write("plates.stl", ascii_stl(plates_box(true)));
  const std::string json = dir.write("s.json", R"({"hot": {"emissivity": 0.8, "temperature": 900},
                    "*": {"emissivity": 0.5, "heat_flux": 0}})");
  ASSERT_EQ(run({"heat", stl, "--surfaces", json, "--patches", "100", "-o", dir.file("out") + "/",
                 "--vertex-exr", dir.file("v.exr"), "--ply", dir.file("h.ply"), "--image",
                 dir.file("t.png"), "--size", "64x48", "-q"}),
            kExitOk);
  for (const char* f : {"out/heat_surfaces.csv", "out/heat_patches.csv", "out/heat.json", "v.exr",
                        "h.ply", "t.png"})
    EXPECT_TRUE(std::filesystem::exists(dir.file(f))) << f;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  const Json j = read_json(dir.file("out/heat.json"));
  EXPECT_EQ(j["settings"]["length_unit"], "m");
  EXPECT_EQ(j["status"], "converged");
  const VertexExr v = read_vertex_exr(dir.file("v.exr"), {"temperature", "heat_flux", "radiosity"});
  EXPECT_GT(v.vertex_count, 0);
  EXPECT_NEAR(v.radiosity.col(0).maxCoeff(), 900.0, 1e-3);  // float channel
  EXPECT_NE(slurp(dir.file("h.ply")).find("property float temperature"), std::string::npos);
}

TEST(HeatCli, AFailedRunLeavesThePreviousSetOfOutputsWhole) {
  // heat's CSVs, image and JSON are one result: a run that fails to write one of them must
  // not leave new CSVs beside an old JSON (they used to be renamed one by one as written).
  const TempDir dir;
  const std::string stl = dir.write("plates.stl", ascii_stl(plates_box(true)));
  const auto conditions = [&](int t) {
    return dir.write("s.json", R"({"hot": {"emissivity": 0.8, "temperature": )" +
                                   std::to_string(t) +
                                   R"(}, "*": {"emissivity": 0.5, "heat_flux": 0}})");
  };
  const std::vector<std::string> common = {"--patches", "100", "-o", dir.file("out"), "-q"};
  std::vector<std::string> first = {"heat", stl, "--surfaces", conditions(900)};
  first.insert(first.end(), common.begin(), common.end());
  ASSERT_EQ(run(first), kExitOk);
  const std::string csv = slurp(dir.file("out_surfaces.csv")), json = slurp(dir.file("out.json"));
  std::filesystem::create_directory(dir.file("t.png"));  // an image path that cannot be written
  std::vector<std::string> second = {
      "heat", stl, "--surfaces", conditions(700), "--image", dir.file("t.png"), "--size", "32x24"};
  second.insert(second.end(), common.begin(), common.end());
  EXPECT_EQ(testing::run_capturing(second).first, kExitFailure);
  EXPECT_EQ(slurp(dir.file("out_surfaces.csv")), csv);
  EXPECT_EQ(slurp(dir.file("out.json")), json);
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(HeatCli, LengthUnitScalesAreasAndPowers) {
  const TempDir dir;
  std::vector<std::pair<std::string, std::vector<Tri>>> solids = plates_box(true);
  for (auto& [name, tris] : solids)
    for (auto& t : tris)
      for (auto& p : t) p *= 1000.0;  // the same box in millimetres
  const std::string stl = dir.write("mm.stl", ascii_stl(solids));
  const std::string json = dir.write(
      "s.json",
      R"({"hot": {"emissivity": 0.8, "temperature": 900}, "*": {"emissivity": 0.5, "temperature": 300}})");
  ASSERT_EQ(run({"heat", stl, "--surfaces", json, "--max-edge", "10000", "--length-unit", "mm",
                 "--estimator", "analytic", "--ff-tol", "1e-10", "-o", dir.file("mm"), "-q"}),
            0);
  const Json j = read_json(dir.file("mm.json"));
  EXPECT_NEAR(double(surface(j, "hot")["area_m2"]), 1.0, 1e-12);
}

int heat_exit(const std::vector<std::string>& extra, std::string* err) {
  ::testing::internal::CaptureStderr();
  std::vector<std::string> args = {"heat"};
  args.insert(args.end(), extra.begin(), extra.end());
  const int code = run(args);
  *err = ::testing::internal::GetCapturedStderr();
  return code;
}

TEST(HeatCli, RefusesBadInputWithTheRightExitCode) {
  const TempDir dir;
  const std::string stl = dir.write("plates.stl", ascii_stl(plates_box(true)));
  const std::string out = dir.file("o");
  std::string err;
  const std::string bad = dir.write("bad.json", "{\"hot\": {\"emissivity\": 0.8,");
  EXPECT_EQ(heat_exit({stl, "--surfaces", bad, "-o", out, "-q"}, &err), kExitFailure);
  EXPECT_NE(err.find("bad.json: not valid JSON"), std::string::npos) << err;
  const std::string partial =
      dir.write("p.json", R"({"hot": {"emissivity": 0.8, "temperature": 900}})");
  EXPECT_EQ(heat_exit({stl, "--surfaces", partial, "-o", out, "-q"}, &err), kExitFailure);
  EXPECT_NE(err.find("surface \"cold\" has no condition"), std::string::npos) << err;
  const std::string typo = dir.write(
      "t.json",
      R"({"hott": {"emissivity": 0.8, "temperature": 900}, "*": {"emissivity": 0.5, "temperature": 300}})");
  EXPECT_EQ(heat_exit({stl, "--surfaces", typo, "-o", out, "-q"}, &err), kExitFailure);
  EXPECT_NE(err.find("surface \"hott\" is not in the scene"), std::string::npos) << err;
  const std::string both =
      dir.write("b.json", R"({"*": {"emissivity": 0.5, "temperature": 3, "heat_flux": 1}})");
  EXPECT_EQ(heat_exit({stl, "--surfaces", both, "-o", out, "-q"}, &err), kExitFailure);
  EXPECT_NE(err.find("exactly one of"), std::string::npos) << err;
  const std::string floating = dir.write("f.json", R"({"*": {"emissivity": 0.5, "heat_flux": 0}})");
  EXPECT_EQ(heat_exit({stl, "--surfaces", floating, "--patches", "50", "-o", out, "-q"}, &err),
            kExitFailure);
  EXPECT_NE(err.find("no temperature fixes the level"), std::string::npos) << err;
  const std::string ok = dir.write("ok.json", R"({"*": {"emissivity": 0.5, "temperature": 300}})");
  EXPECT_EQ(heat_exit({stl, "--surfaces", ok, "--ambient", "-o", out, "-q"}, &err), kExitUsage);
  EXPECT_EQ(heat_exit({stl, "-o", out, "-q"}, &err), kExitUsage);  // --surfaces is required
  EXPECT_EQ(heat_exit({stl, "--surfaces", ok, "--length-unit", "ft", "-q"}, &err), kExitUsage);
  EXPECT_EQ(heat_exit({stl, "--surfaces", ok, "--ambient-temperature", "nan", "-q"}, &err),
            kExitUsage);
  EXPECT_FALSE(std::filesystem::exists(out + ".json"));  // nothing written on refusal
}

}  // namespace
}  // namespace lambert
