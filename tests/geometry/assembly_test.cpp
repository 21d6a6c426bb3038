// Streaming CSR assembly (geometry/formfactors/assembly.hpp): rows appended in order, and
// the in-place completion of an upper triangle into a reciprocal F.

#include "geometry/formfactors/assembly.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "core/error.hpp"
#include "core/sampling.hpp"

namespace lambert::ff {
namespace {

// A random upper triangle (about half the pairs present, some rows empty) as G_ij and
// variances, and the areas.
struct Upper {
  std::int32_t n = 9;
  std::vector<std::vector<RowEntry>> rows;
  std::vector<double> area;
  Upper() {
    Rng rng(hash_keys(7, 1, 2));
    rows.resize(n);
    for (std::int32_t i = 0; i < n; ++i) {
      area.push_back(0.5 + rng.uniform());
      if (i == 3) continue;  // an empty row in the middle
      for (std::int32_t j = i + 1; j < n; ++j)
        if (rng.uniform() < 0.5) rows[i].push_back({j, rng.uniform(), rng.uniform()});
    }
  }
};

TEST(Assembly, AppendedRowsFormTheCsr) {
  const Upper u;
  std::int64_t total = 0;
  for (const auto& r : u.rows) total += static_cast<std::int64_t>(r.size());
  CsrAppender app(u.n, total + 5, true);  // spare room: the reservation is not the size
  for (const auto& r : u.rows) app.append_row(r);
  SparseF F, err;
  app.finish(F, err);
  ASSERT_EQ(F.nonZeros(), total);
  ASSERT_EQ(err.nonZeros(), total);
  for (std::int32_t i = 0; i < u.n; ++i) {
    ASSERT_EQ(F.outerIndexPtr()[i + 1] - F.outerIndexPtr()[i],
              static_cast<std::int64_t>(u.rows[i].size()));
    for (const RowEntry& e : u.rows[i]) {
      EXPECT_EQ(F.coeff(i, e.col), e.value);
      EXPECT_EQ(err.coeff(i, e.col), e.err);
    }
  }
}

TEST(Assembly, AppendingBeyondTheReservationIsAnError) {
  CsrAppender app(2, 1, false);
  EXPECT_THROW(app.append_row({{0, 1.0, 0.0}, {1, 1.0, 0.0}}), InternalError);
}

// mirror_upper must give F_ij = G_ij / A_i and F_ji = G_ij / A_j, errors sqrt(var) / A,
// sorted columns, and so exactly A_i F_ij = A_j F_ji up to one rounding of each division.
TEST(Assembly, MirroredUpperTriangleIsTheReciprocalMatrix) {
  const Upper u;
  std::int64_t total = 0;
  for (const auto& r : u.rows) total += static_cast<std::int64_t>(r.size());
  CsrAppender app(u.n, 2 * total, true);
  for (const auto& r : u.rows) app.append_row(r);
  SparseF F, var;
  app.finish(F, var);
  mirror_upper(F, &var, u.area);
  ASSERT_EQ(F.nonZeros(), 2 * total);
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(u.n, u.n), V = G;
  for (std::int32_t i = 0; i < u.n; ++i) {
    for (const RowEntry& e : u.rows[i]) {
      G(i, e.col) = G(e.col, i) = e.value;
      V(i, e.col) = V(e.col, i) = e.err;
    }
  }
  for (std::int32_t i = 0; i < u.n; ++i) {
    std::int64_t count = 0;
    for (std::int32_t j = 0; j < u.n; ++j) count += G(i, j) > 0.0;
    ASSERT_EQ(F.outerIndexPtr()[i + 1] - F.outerIndexPtr()[i], count);
    for (auto k = F.outerIndexPtr()[i]; k < F.outerIndexPtr()[i + 1]; ++k) {
      const auto j = F.innerIndexPtr()[k];
      if (k > F.outerIndexPtr()[i]) {
        EXPECT_LT(F.innerIndexPtr()[k - 1], j);
      }
      EXPECT_EQ(var.innerIndexPtr()[k], j);
      EXPECT_EQ(F.valuePtr()[k], G(i, j) / u.area[i]);
      EXPECT_EQ(var.valuePtr()[k], std::sqrt(V(i, j)) / u.area[i]);
    }
  }
}

TEST(Assembly, MirroringWithoutRoomIsAnError) {
  CsrAppender app(2, 1, false);
  app.append_row({{1, 1.0, 0.0}});
  app.append_row({});
  SparseF F, err;
  app.finish(F, err);
  EXPECT_THROW(mirror_upper(F, nullptr, {1.0, 1.0}), InternalError);
}

}  // namespace
}  // namespace lambert::ff
