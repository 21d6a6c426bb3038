// Radiative conductors (solvers/gebhart.hpp) on a small reciprocal F against the dense Gebhart
// formula 𝓑 = (I − Fρ)⁻¹ F ε computed with Eigen, aggregated to groups.
#include "solvers/gebhart.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <vector>

#include "core/sparse.hpp"

namespace lambert {
namespace {

// Five patches with areas A and a symmetric exchange G = A F (so A_i F_ij = A_j F_ji): rows
// sum to below 1 (an open scene) for patches 0..3 and to 1 for patch 4.
struct SmallScene {
  Eigen::VectorXd area{{1.0, 2.0, 0.5, 1.5, 3.0}};
  Eigen::MatrixXd F;
  SmallScene() {
    Eigen::MatrixXd G(5, 5);
    G << 0.0, 0.30, 0.10, 0.20, 0.30,  //
        0.30, 0.10, 0.20, 0.40, 0.90,  //
        0.10, 0.20, 0.0, 0.05, 0.10,   //
        0.20, 0.40, 0.05, 0.0, 0.80,   //
        0.30, 0.90, 0.10, 0.80, 0.90;  // row 4 sums to 3.0 = A_4: closed there
    F = area.asDiagonal().inverse() * G;
  }
};

TEST(ThermalConductors, MatchTheDenseGebhartFormulaAggregatedToGroups) {
  const SmallScene s;
  const Eigen::VectorXd eps{{0.9, 0.3, 0.6, 0.0, 0.5}};  // a perfect reflector among them
  const std::vector<std::int32_t> group = {0, 0, 1, 2, 3};
  SparseRowMatrix sparse = s.F.sparseView();
  ThermalProblem p;
  p.F = std::make_shared<CsrOperator>(sparse);
  p.area = s.area;
  p.emissivity = eps;
  p.boundary.assign(5, ThermalBoundary::Temperature);
  p.value = Eigen::VectorXd::Zero(5);
  SolveOptions so;
  so.solver = "direct";
  const RadiativeConductors c = radiative_conductors(p, group, 4, so);
  const Eigen::MatrixXd rho = (1.0 - eps.array()).matrix().asDiagonal();
  const Eigen::MatrixXd gebhart =
      (Eigen::MatrixXd::Identity(5, 5) - s.F * rho).lu().solve(s.F * eps.asDiagonal());
  Eigen::MatrixXd per_patch = eps.cwiseProduct(s.area).asDiagonal() * gebhart;
  Eigen::MatrixXd want = Eigen::MatrixXd::Zero(4, 4);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) want(group[i], group[j]) += per_patch(i, j);
  // Both are direct solves of the same 5 x 5 system: ‖ρF‖∞ = 0.967 (the ε = 0 patch 3, row
  // sum 1.45/1.5), so ‖(I − ρF)⁻¹‖∞ ≤ 1/(1 − 0.967) = 30 and rounding errors stay below
  // 30 · 5 · 2.2e-16 · 3 (the largest entry) = 1e-13; 1e-12 leaves margin.
  EXPECT_LE((c.GR - want).cwiseAbs().maxCoeff(), 1e-12) << c.GR << "\n\n" << want;
  EXPECT_LE((c.GR - c.GR.transpose()).cwiseAbs().maxCoeff(), 1e-12);  // reciprocity
  EXPECT_EQ(c.solves, 2);  // four groups, three per solve
  EXPECT_EQ(c.status, SolveStatus::Converged);
  // Every watt emitted ends absorbed somewhere or escapes: rows + environment = ε_S A_S, and
  // the ε = 0 group neither emits nor absorbs.
  for (int g = 0; g < 4; ++g)
    EXPECT_NEAR(c.GR.row(g).sum() + c.environment[g], c.emittance[g], 1e-12) << g;
  EXPECT_EQ(c.emittance[2], 0.0);
  EXPECT_LE(c.GR.row(2).cwiseAbs().maxCoeff() + c.GR.col(2).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_GT(c.environment[0], 0.0);  // rows of patches 0..3 leave some out
}

TEST(ThermalConductors, RefuseGroupsOutOfRange) {
  const SmallScene s;
  SparseRowMatrix sparse = s.F.sparseView();
  ThermalProblem p;
  p.F = std::make_shared<CsrOperator>(sparse);
  p.area = s.area;
  p.emissivity = Eigen::VectorXd::Constant(5, 0.5);
  EXPECT_THROW(radiative_conductors(p, {0, 1, 2, 3, 4}, 4, SolveOptions{}), UsageError);
  EXPECT_THROW(radiative_conductors(p, {0, 1}, 2, SolveOptions{}), UsageError);
}

}  // namespace
}  // namespace lambert
