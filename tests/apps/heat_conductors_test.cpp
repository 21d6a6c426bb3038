// `lambert heat --conductors`: the radiative conductors GR_ij = ε_i A_i 𝓑_ij against the
// two-surface closed form (a regular tetrahedron, a cube split into its caps and its walls),
// the three-surface network (the plates box, from Howell's exact plate factor), reciprocity,
// the row sums of a closed enclosure, and the energy balance against heat's own Q.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "geometry/analytic.hpp"
#include "io/json.hpp"
#include "solvers/thermal.hpp"

namespace lambert {
namespace {

using testing::read_json;
using testing::run;
using testing::slurp;
using testing::TempDir;
using V = Eigen::Vector3d;
using Face = std::vector<V>;

// An OBJ of named groups of planar polygons, each turned to face `inside` (the enclosure's
// interior): only fronts emit and receive.
std::string enclosure_obj(const std::vector<std::pair<std::string, std::vector<Face>>>& groups,
                          const V& inside) {
  std::string s;
  char buf[120];
  for (const auto& [name, faces] : groups) {
    s += "g " + name + "\n";
    for (Face f : faces) {
      const V n = (f[1] - f[0]).cross(f[2] - f[0]);
      if (n.dot(inside - f[0]) < 0) std::reverse(f.begin(), f.end());
      for (const V& p : f) {
        std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
        s += buf;
      }
      s += "f";
      for (size_t k = 0; k < f.size(); ++k) s += " -" + std::to_string(f.size() - k);
      s += "\n";
    }
  }
  return s;
}

// The six faces of the box [0, a] x [0, b] x [0, c]: bottom, top, then the four walls.
std::vector<Face> box_faces(double a, double b, double c) {
  return {{V(0, 0, 0), V(a, 0, 0), V(a, b, 0), V(0, b, 0)},
          {V(0, 0, c), V(a, 0, c), V(a, b, c), V(0, b, c)},
          {V(0, 0, 0), V(a, 0, 0), V(a, 0, c), V(0, 0, c)},
          {V(0, b, 0), V(a, b, 0), V(a, b, c), V(0, b, c)},
          {V(0, 0, 0), V(0, b, 0), V(0, b, c), V(0, 0, c)},
          {V(a, 0, 0), V(a, b, 0), V(a, b, c), V(a, 0, c)}};
}

struct Conductors {
  std::vector<std::string> names;
  Eigen::MatrixXd GR;
  Eigen::VectorXd environment;
};

// Reads --conductors' CSV: header GR_m2,<names>,environment, one row per surface.
Conductors read_conductors(const std::string& path) {
  std::istringstream in(slurp(path));
  std::string line, cell;
  std::getline(in, line);
  Conductors c;
  std::stringstream header(line);
  std::getline(header, cell, ',');
  EXPECT_EQ(cell, "GR_m2");
  while (std::getline(header, cell, ',')) c.names.push_back(cell);
  EXPECT_EQ(c.names.back(), "environment");
  c.names.pop_back();
  const auto n = static_cast<Eigen::Index>(c.names.size());
  c.GR.resize(n, n);
  c.environment.resize(n);
  for (Eigen::Index i = 0; i < n && std::getline(in, line); ++i) {
    std::stringstream row(line);
    std::getline(row, cell, ',');
    EXPECT_EQ(cell, c.names[i]);
    for (Eigen::Index j = 0; j <= n; ++j) {
      std::getline(row, cell, ',');
      (j < n ? c.GR(i, j) : c.environment[i]) = std::stod(cell);
    }
  }
  return c;
}

// heat on `obj` with one patch per face, exact factors (`analytic`, 1e-10 per entry) and a
// direct solve; returns the conductors and leaves the summary in DIR/h.json.
Conductors exact_conductors(const TempDir& dir, const std::string& obj, const std::string& json) {
  EXPECT_EQ(run({"heat", dir.write("e.obj", obj), "--surfaces", dir.write("s.json", json),
                 "--max-edge", "100", "--estimator", "analytic", "--ff-tol", "1e-10", "--solver",
                 "direct", "-o", dir.file("h.csv"), "--conductors", dir.file("gr.csv"), "-q"}),
            0);
  return read_conductors(dir.file("gr.csv"));
}

// Two grey surfaces of uniform radiosity: the series network of two surface resistances and
// one space resistance (m²).
double two_surface_conductor(double e1, double a1, double f12, double e2, double a2) {
  return 1.0 / ((1 - e1) / (e1 * a1) + 1.0 / (a1 * f12) + (1 - e2) / (e2 * a2));
}

// Tolerance for conductors from factors within 1e-10 per entry (--ff-tol) on N ≤ 6 patches:
// GR = εA (I − Fρ)⁻¹ F ε moves by at most εA ‖(I − Fρ)⁻¹‖∞² ‖δF‖∞ ≤ εA N 1e-10 / ε_min²
// (‖(I − Fρ)⁻¹‖∞ ≤ 1/ε_min for row sums ≤ 1), i.e. 6e-10/0.09 = 7e-9 εA at ε_min = 0.3;
// direct solve: rounding. 1e-7 εA covers both with margin.
constexpr double kExactRelative = 1e-7;

TEST(HeatConductors, RegularTetrahedronMatchesTheTwoSurfaceFormula) {
  // One face against the other three: a plane face sees only the rest (F12 = 1), and the
  // 3-fold rotation about the opposite vertex maps the three onto each other, so their
  // radiosities are equal and the lumped two-node network is exact on one patch per face.
  const TempDir dir;
  const V p[4] = {V(1, 1, 1), V(1, -1, -1), V(-1, 1, -1), V(-1, -1, 1)};
  const std::string obj =
      enclosure_obj({{"one", {{p[1], p[2], p[3]}}},
                     {"rest", {{p[0], p[2], p[3]}, {p[0], p[1], p[3]}, {p[0], p[1], p[2]}}}},
                    V::Zero());
  const double e1 = 0.4, e2 = 0.7;
  const Conductors c =
      exact_conductors(dir, obj, R"({"one": {"emissivity": 0.4, "temperature": 900},
      "rest": {"emissivity": 0.7, "temperature": 300}})");
  const Json j = read_json(dir.file("h.json"));
  ASSERT_EQ(int(j["patches"]), 4);
  const double a1 = std::sqrt(3.0) / 4.0 * 8.0, a2 = 3.0 * a1;  // edge 2√2
  const double gr12 = two_surface_conductor(e1, a1, 1.0, e2, a2);
  std::printf("tetrahedron: GR_12 %.12g, formula %.12g (%.2e)\n", c.GR(0, 1), gr12,
              std::abs(c.GR(0, 1) / gr12 - 1));
  EXPECT_NEAR(c.GR(0, 1), gr12, kExactRelative * e1 * a1);
  EXPECT_NEAR(c.GR(1, 0), gr12, kExactRelative * e1 * a1);
  EXPECT_NEAR(c.GR(0, 0) + c.GR(0, 1), e1 * a1, kExactRelative * e1 * a1);  // closed
  EXPECT_NEAR(c.GR(1, 0) + c.GR(1, 1), e2 * a2, kExactRelative * e2 * a2);
  EXPECT_NEAR(c.environment.cwiseAbs().maxCoeff(), 0.0, kExactRelative * e2 * a2);
  // And the summary carries the same matrix.
  EXPECT_NEAR(double(j["conductors"]["GR_m2"][0][1]), c.GR(0, 1), 1e-15 * gr12 + 1e-300);
}

TEST(HeatConductors, CubeCapsAgainstWallsMatchTheTwoSurfaceFormula) {
  // Surface 1 = bottom and top (it sees itself: F11 = F_bottom,top), surface 2 = the four
  // walls: the mirror z → 1 − z and the 4-fold rotation about z keep each surface's
  // radiosity uniform, so the two-node network is exact with F12 = 1 − F11.
  const TempDir dir;
  const auto f = box_faces(1, 1, 1);
  const std::string obj = enclosure_obj(
      {{"caps", {f[0], f[1]}}, {"walls", {f[2], f[3], f[4], f[5]}}}, V(0.5, 0.5, 0.5));
  const double e1 = 0.3, e2 = 0.8, a1 = 2.0, a2 = 4.0;
  const Conductors c =
      exact_conductors(dir, obj, R"({"caps": {"emissivity": 0.3, "temperature": 500},
      "walls": {"emissivity": 0.8, "temperature": 300}})");
  const double f12 = 1.0 - parallel_rectangles_factor(1.0, 1.0, 1.0);
  const double gr12 = two_surface_conductor(e1, a1, f12, e2, a2);
  std::printf("cube: GR_12 %.12g, formula %.12g (%.2e)\n", c.GR(0, 1), gr12,
              std::abs(c.GR(0, 1) / gr12 - 1));
  EXPECT_NEAR(c.GR(0, 1), gr12, kExactRelative * e1 * a1);
  EXPECT_NEAR(c.GR(1, 0), gr12, kExactRelative * e1 * a1);
  EXPECT_NEAR(c.GR(0, 0), e1 * a1 - gr12, kExactRelative * e1 * a1);  // the caps' self part
}

TEST(HeatConductors, PlatesBoxMatchesTheThreeSurfaceNetwork) {
  // Hot floor, cold ceiling (1 x 1, 0.5 apart) and four walls, each wall its own face: the
  // walls are equivalent under the 4-fold rotation, so the network of three surfaces is exact
  // on one patch per face. The reference: 𝓑 = (I − Fρ)⁻¹ F ε on the surface factors from
  // Howell's parallel-plate closed form and closure, GR = diag(εA) 𝓑.
  const TempDir dir;
  const auto f = box_faces(1, 1, 0.5);
  const std::string obj = enclosure_obj(
      {{"hot", {f[0]}}, {"cold", {f[1]}}, {"walls", {f[2], f[3], f[4], f[5]}}}, V(0.5, 0.5, 0.25));
  const Conductors c =
      exact_conductors(dir, obj, R"({"hot": {"emissivity": 0.8, "temperature": 900},
      "cold": {"emissivity": 0.5, "temperature": 350}, "walls": {"emissivity": 0.3, "heat_flux": 0}})");
  ASSERT_EQ(c.names, (std::vector<std::string>{"hot", "cold", "walls"}));
  const Eigen::Vector3d eps(0.8, 0.5, 0.3), area(1.0, 1.0, 2.0);
  const double fp = parallel_rectangles_factor(1.0, 1.0, 0.5), fw = (1.0 - fp) / 2.0;
  Eigen::Matrix3d F;
  F << 0, fp, 1 - fp, fp, 0, 1 - fp, fw, fw, 1 - 2 * fw;
  const Eigen::Matrix3d rho = (1.0 - eps.array()).matrix().asDiagonal();
  const Eigen::Matrix3d want = eps.cwiseProduct(area).asDiagonal() *
                               (Eigen::Matrix3d::Identity() - F * rho).inverse() * F *
                               eps.asDiagonal();
  std::ostringstream table;
  table << "GR (m²), lambert vs network:\n"
        << c.GR << "\n\n"
        << want << "\nlargest difference " << (c.GR - want).cwiseAbs().maxCoeff() << " m²\n";
  std::printf("%s", table.str().c_str());
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(c.GR(i, k), want(i, k), kExactRelative * eps[i] * area[i]) << i << k;
      EXPECT_NEAR(c.GR(i, k), c.GR(k, i), kExactRelative * eps[i] * area[i]) << i << k;
    }
    EXPECT_NEAR(c.GR.row(i).sum(), eps[i] * area[i], kExactRelative * eps[i] * area[i]) << i;
  }
}

double emissive_power(double t) { return kStefanBoltzmann * std::pow(t, 4); }

// Q_S from heat against Σ_T GR_ST σ(T_S⁴ − T_T⁴) + GR_S,env σ(T_S⁴ − T_amb⁴) for isothermal
// surfaces (every condition a temperature): linearity of the exchange and reciprocity make
// it an identity for any reciprocal F (hybrid is a pair estimator), so the meshed F's own
// error does not enter. With direct solves it holds to rounding: the system's
// ‖(I − ρF)⁻¹‖∞ ≤ 1/ε_min = 2 times N ε_mach of the largest term ε_S A_S σT_S⁴;
// 1e-9 of the sum of |terms| leaves a wide margin.
void expect_energy_balance(const std::string& obj, const std::string& json,
                           const std::map<std::string, double>& temperature, double ambient) {
  const TempDir dir;
  ASSERT_EQ(run({"heat", dir.write("e.obj", obj), "--surfaces", dir.write("s.json", json),
                 "--patches", "120", "--estimator", "hybrid", "--solver", "direct",
                 "--ambient-temperature", std::to_string(ambient), "-o", dir.file("h.csv"),
                 "--conductors", dir.file("gr.csv"), "-q"}),
            0);
  const Conductors c = read_conductors(dir.file("gr.csv"));
  const Json j = read_json(dir.file("h.json"));
  ASSERT_GT(int(j["patches"]), 60);
  for (Eigen::Index s = 0; s < c.GR.rows(); ++s) {
    const double ts = temperature.at(c.names[s]);
    double network = c.environment[s] * (emissive_power(ts) - emissive_power(ambient));
    double scale = std::abs(network);
    for (Eigen::Index t = 0; t < c.GR.cols(); ++t) {
      const double term =
          c.GR(s, t) * (emissive_power(ts) - emissive_power(temperature.at(c.names[t])));
      network += term;
      scale += std::abs(term);
    }
    double q = 0.0;
    for (const auto& x : j["surfaces"])
      if (x["name"] == c.names[s]) q = x["power_W"];
    std::printf("%s: Q %.12g W, network %.12g W\n", c.names[s].c_str(), q, network);
    EXPECT_NEAR(q, network, 1e-9 * scale) << c.names[s];
  }
}

TEST(HeatConductors, NetworkFlowsReproduceHeatsPowersInAClosedBox) {
  const auto f = box_faces(1, 1, 0.5);
  expect_energy_balance(
      enclosure_obj({{"hot", {f[0]}}, {"cold", {f[1]}}, {"walls", {f[2], f[3], f[4], f[5]}}},
                    V(0.5, 0.5, 0.25)),
      R"({"hot": {"emissivity": 0.8, "temperature": 900},
          "cold": {"emissivity": 0.5, "temperature": 350},
          "walls": {"emissivity": 0.6, "temperature": 600}})",
      {{"hot", 900.0}, {"cold", 350.0}, {"walls", 600.0}}, 0.0);
}

TEST(HeatConductors, NetworkFlowsReproduceHeatsPowersInAnOpenSceneWithItsEnvironment) {
  const auto f = box_faces(1, 1, 0.5);
  expect_energy_balance(enclosure_obj({{"hot", {f[0]}}, {"cold", {f[1]}}}, V(0.5, 0.5, 0.25)),
                        R"({"hot": {"emissivity": 0.8, "temperature": 900},
          "cold": {"emissivity": 0.5, "temperature": 350}})",
                        {{"hot", 900.0}, {"cold", 350.0}}, 300.0);
}

}  // namespace
}  // namespace lambert
