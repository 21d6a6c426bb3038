// Gray-diffuse exchange (solvers/thermal.hpp) on surface-level view factors whose values are
// exact: concentric spheres (F_12 = 1, F_21 = A1/A2), two parallel plates with re-radiating
// walls (the three-surface network), isothermal enclosures and the energy closure.
#include "solvers/thermal.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <utility>

#include "core/error.hpp"

namespace lambert {
namespace {

// F as a CsrOperator owning its matrix (the problem keeps the operator alive).
struct OwnedCsr final : TransportOperator {
  explicit OwnedCsr(const Eigen::MatrixXd& dense) : F(dense.sparseView()), op(F) {}
  SparseRowMatrix F;
  CsrOperator op;
  std::int32_t size() const override { return op.size(); }
  std::int64_t entries() const override { return op.entries(); }
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y, int t) const override {
    op.apply(x, y, t);
  }
  RowSpan row(std::int32_t i) const override { return op.row(i); }
  Eigen::VectorXd diagonal() const override { return op.diagonal(); }
  Eigen::VectorXd row_sums() const override { return op.row_sums(); }
  const SparseRowMatrix* matrix() const override { return &F; }
};

ThermalProblem make(const Eigen::MatrixXd& F, const Eigen::VectorXd& area,
                    const Eigen::VectorXd& eps, std::vector<ThermalBoundary> kind,
                    const Eigen::VectorXd& value, double ambient = 0.0) {
  ThermalProblem p;
  p.F = std::make_shared<OwnedCsr>(F);
  p.area = area;
  p.emissivity = eps;
  p.boundary = std::move(kind);
  p.value = value;
  p.ambient_temperature = ambient;
  return p;
}

SolveOptions direct() {
  SolveOptions o;
  o.solver = "direct";
  return o;
}

double sigma_t4(double t) { return kStefanBoltzmann * std::pow(t, 4); }

constexpr auto kT = ThermalBoundary::Temperature;
constexpr auto kQ = ThermalBoundary::HeatFlux;

// Two parallel unit squares at distance c = 0.5 closed by four walls lumped into one surface
// R (area 4 * 0.5 = 2): F_12 = F_21 = f (Howell C-11, for c = 0.5: 0.41525...), F_1R = F_2R
// = 1 - f, F_R1 = F_R2 = (1 - f) / 2 (reciprocity), F_RR = 1 - 2 F_R1 = f. Closed, reciprocal.
constexpr double kF12 = 0.41525;  // any value in (0, 1) gives a closed reciprocal enclosure
Eigen::MatrixXd plates_and_walls() {
  Eigen::MatrixXd F(3, 3);
  const double r = (1.0 - kF12) / 2.0;
  F << 0.0, kF12, 1.0 - kF12, kF12, 0.0, 1.0 - kF12, r, r, kF12;
  return F;
}

TEST(Thermal, ConcentricSpheresMatchTheTwoSurfaceFormula) {
  // A1 = 1, A2 = 4 (R2 = 2 R1): F_11 = 0, F_12 = 1, F_21 = 1/4, F_22 = 3/4, exactly.
  Eigen::MatrixXd F(2, 2);
  F << 0.0, 1.0, 0.25, 0.75;
  const double e1 = 0.3, e2 = 0.6, t1 = 1000.0, t2 = 400.0, a1 = 1.0, a2 = 4.0;
  const auto p =
      make(F, Eigen::Vector2d(a1, a2), Eigen::Vector2d(e1, e2), {kT, kT}, Eigen::Vector2d(t1, t2));
  const ThermalSolution s = solve_thermal(p, direct());
  const double q1 = kStefanBoltzmann * a1 * (std::pow(t1, 4) - std::pow(t2, 4)) /
                    (1.0 / e1 + (a1 / a2) * (1.0 / e2 - 1.0));
  // Direct LU on a 2x2 system: rounding only, ~1e-15 relative; 1e-12 leaves ample margin.
  EXPECT_NEAR(s.Q[0], q1, 1e-12 * q1);
  EXPECT_NEAR(s.Q[1], -q1, 1e-12 * q1);
  EXPECT_NEAR(s.closure, 0.0, 1e-12 * q1);
}

TEST(Thermal, OverflowingTemperaturesAreErrorsNotInfinity) {
  // Issue 33, item 6: an emissivity of 1e-320 (e sigma underflows to 0) or a flux of 1e308
  // wrote T = inf with exit 0 and no undefined temperature counted.
  for (const auto& [eps, q] : {std::pair{1e-320, 100.0}, std::pair{0.5, 1e308}}) {
    const auto p =
        make(plates_and_walls(), Eigen::Vector3d(1.0, 1.0, 2.0), Eigen::Vector3d(0.8, eps, 0.4),
             {kT, kQ, kQ}, Eigen::Vector3d(300.0, q, 0.0));
    try {
      solve_thermal(p, direct());
      ADD_FAILURE() << "emissivity " << eps << ", flux " << q << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("overflows"), std::string::npos) << e.what();
    }
  }
}

TEST(Thermal, ReradiatingWallMatchesTheThreeSurfaceNetwork) {
  const double e1 = 0.8, e2 = 0.5, t1 = 900.0, t2 = 350.0;
  const Eigen::Vector3d area(1.0, 1.0, 2.0);
  const auto p = make(plates_and_walls(), area, Eigen::Vector3d(e1, e2, 0.4), {kT, kT, kQ},
                      Eigen::Vector3d(t1, t2, 0.0));
  const ThermalSolution s = solve_thermal(p, direct());
  // Network: surface resistances (1 - e)/(e A), space resistances 1/(A_i F_ij); the walls'
  // node floats (q_R = 0), so its two space resistances are in series.
  const double f1r = 1.0 - kF12, f2r = 1.0 - kF12;
  const double space = 1.0 / (kF12 + 1.0 / (1.0 / f1r + 1.0 / f2r));
  const double total = (1.0 - e1) / e1 + space + (1.0 - e2) / e2;
  const double q1 = (sigma_t4(t1) - sigma_t4(t2)) / total;
  const double j1 = sigma_t4(t1) - q1 * (1.0 - e1) / e1, j2 = sigma_t4(t2) + q1 * (1.0 - e2) / e2;
  const double jr = (f1r * j1 + f2r * j2) / (f1r + f2r);    // node balance at R
  const double tr = std::pow(jr / kStefanBoltzmann, 0.25);  // q = 0: J_R = H_R = sigma T_R^4
  // Direct solve of a 3x3 system: rounding only (~1e-15 relative); 1e-12 leaves margin.
  EXPECT_NEAR(s.Q[0], q1, 1e-12 * q1);
  EXPECT_NEAR(s.T[2], tr, 1e-12 * tr);
  EXPECT_NEAR(s.q[2], 0.0, 1e-12 * q1);
}

TEST(Thermal, IsothermalClosedEnclosureHasNoNetFlux) {
  const Eigen::Vector3d area(1.0, 1.0, 2.0);
  const double t = 600.0;
  const auto p = make(plates_and_walls(), area, Eigen::Vector3d(0.9, 0.2, 0.55), {kT, kT, kT},
                      Eigen::Vector3d::Constant(t));
  for (const std::string solver : {"direct", "jacobi", "gauss-seidel", "gmres"}) {
    SolveOptions o;
    o.solver = solver;
    o.tol = 1e-12;
    const ThermalSolution s = solve_thermal(p, o);
    // ||J - J*||_inf <= ||K^-1||_inf ||r||_2 with ||r||_2 <= tol ||E||_2; K = I - (1-e)F has
    // ||K^-1||_inf <= 1/e_min = 5. q = J - F J then errs by at most 2 ||J - J*||_inf.
    const double bound = 2.0 * 5.0 * o.tol * std::sqrt(3.0) * sigma_t4(t);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(s.q[i], 0.0, bound) << solver << " patch " << i;
  }
}

TEST(Thermal, EverySolverMatchesDirectWithFluxRowsAndNegativeSources) {
  // A known-flux patch (rho = 1) removing heat (q < 0: E < 0) and a re-radiating one.
  const Eigen::Vector3d area(1.0, 1.0, 2.0);
  const auto p = make(plates_and_walls(), area, Eigen::Vector3d(0.8, 0.5, 0.3), {kT, kQ, kQ},
                      Eigen::Vector3d(1000.0, -5000.0, 0.0));
  const ThermalSolution ref = solve_thermal(p, direct());
  const RadiosityProblem sys = make_thermal_system(p);
  Eigen::MatrixXd K = Eigen::MatrixXd::Identity(3, 3);
  K -= sys.rho.col(0).asDiagonal() * plates_and_walls();
  const double k_inv = K.inverse().cwiseAbs().rowwise().sum().maxCoeff();
  for (const auto& solver : solver_names()) {
    SolveOptions o;
    o.solver = solver;
    o.tol = 1e-10;
    const ThermalSolution s = solve_thermal(p, o);
    ASSERT_EQ(s.radiosity.status, SolveStatus::Converged) << solver;
    // ||J - J*||_inf <= ||K^-1||_inf ||r||_inf <= ||K^-1||_inf tol ||E||_2 (computed here).
    const double bound = k_inv * o.tol * sys.emission.col(0).norm() * 1.01;
    EXPECT_LE((s.J - ref.J).cwiseAbs().maxCoeff(), bound) << solver;
    // The flux patch gets the flux it asked for, to the same bound (q = J - F J: twice).
    EXPECT_NEAR(s.q[1], -5000.0, 2.0 * bound) << solver;
  }
}

TEST(Thermal, EnergyClosesOpenAndClosed) {
  // Open: two parallel plates alone (F_12 = F_21 = f, the rest escapes) at ambient 300 K.
  Eigen::MatrixXd open(2, 2);
  open << 0.0, kF12, kF12, 0.0;
  const auto p_open = make(open, Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(0.7, 0.4), {kT, kQ},
                           Eigen::Vector2d(800.0, 1000.0), 300.0);
  const ThermalSolution so = solve_thermal(p_open, direct());
  // Sum Q + environment = sum_ij A_i F_ij (J_j - J_i)-type terms cancel by reciprocity: only
  // rounding remains, ~1e-16 of the largest power; 1e-12 leaves margin.
  const double scale_open = so.Q.cwiseAbs().sum();
  EXPECT_NEAR(so.closure, 0.0, 1e-12 * scale_open);
  EXPECT_GT(std::abs(so.environment_power), 0.1 * scale_open);  // the environment matters
  const auto p_closed =
      make(plates_and_walls(), Eigen::Vector3d(1.0, 1.0, 2.0), Eigen::Vector3d(0.7, 0.4, 0.5),
           {kT, kT, kQ}, Eigen::Vector3d(800.0, 300.0, 0.0));
  const ThermalSolution sc = solve_thermal(p_closed, direct());
  EXPECT_NEAR(sc.closure, 0.0, 1e-12 * sc.Q.cwiseAbs().sum());
  EXPECT_NEAR(sc.environment_power, 0.0, 1e-12 * sc.Q.cwiseAbs().sum());  // rows sum to 1
}

TEST(Thermal, ImpossibleFluxGivesUndefinedTemperature) {
  // Asking a flux patch to lose far more than it can radiate even at 0 K.
  const auto p =
      make(plates_and_walls(), Eigen::Vector3d(1.0, 1.0, 2.0), Eigen::Vector3d(0.8, 0.5, 0.3),
           {kT, kQ, kQ}, Eigen::Vector3d(300.0, -1e6, 0.0));
  const ThermalSolution s = solve_thermal(p, direct());
  EXPECT_GE(s.undefined_temperatures, 1);
  EXPECT_TRUE(std::isnan(s.T[1]));
}

TEST(Thermal, RefusesBadInput) {
  EXPECT_THROW(make_thermal_system(make(plates_and_walls(), Eigen::Vector3d(1, 1, 2),
                                        Eigen::Vector3d(0.8, 0.0, 0.3), {kT, kQ, kQ},
                                        Eigen::Vector3d(300, 0, 0))),
               UsageError);  // flux patch with emissivity 0
  EXPECT_THROW(make_thermal_system(make(plates_and_walls(), Eigen::Vector3d(1, 1, 2),
                                        Eigen::Vector3d(1.2, 0.5, 0.3), {kT, kQ, kQ},
                                        Eigen::Vector3d(300, 0, 0))),
               UsageError);  // emissivity above 1
}

}  // namespace
}  // namespace lambert
