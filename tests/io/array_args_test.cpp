// The checks on arrays handed in by a caller (Python's numpy arguments): every inconsistency
// is a UsageError before the arrays are read past what the checks made safe.
#include "io/array_args.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace lambert {
namespace {

using I = ArrayArg<std::int64_t>;
using D = ArrayArg<double>;

TEST(ArrayArgs, AValidCsrRoundTrips) {
  const std::int64_t p[] = {0, 1, 3}, c[] = {1, 0, 1};
  const double v[] = {0.25, 0.5, 0.125};
  const SparseRowMatrix F = csr_from_arrays(2, I{p, {3}}, I{c, {3}}, D{v, {3}}, "F");
  EXPECT_EQ(F.nonZeros(), 3);
  EXPECT_EQ(F.coeff(0, 1), 0.25);
  EXPECT_EQ(F.coeff(1, 0), 0.5);
  EXPECT_EQ(F.coeff(1, 1), 0.125);
}

TEST(ArrayArgs, EveryInconsistencyIsAUsageError) {
  const std::int64_t c[] = {1, 0, 1}, bad_c[] = {2, 0, 1}, unsorted[] = {1, 1, 0};
  const double v[] = {0.25, 0.5, 0.125}, nan[] = {0.25, std::nan(""), 0.1};
  const std::int64_t decreasing[] = {0, 3, 1}, over[] = {0, 4, 3}, late[] = {1, 1, 3};
  const std::int64_t good[] = {0, 1, 3};
  for (const std::int64_t* p : {decreasing, over, late})
    EXPECT_THROW(csr_from_arrays(2, I{p, {3}}, I{c, {3}}, D{v, {3}}, "F"), UsageError);
  EXPECT_THROW(csr_from_arrays(2, I{good, {3}}, I{bad_c, {3}}, D{v, {3}}, "F"), UsageError);
  EXPECT_THROW(csr_from_arrays(2, I{good, {3}}, I{unsorted, {3}}, D{v, {3}}, "F"), UsageError);
  EXPECT_THROW(csr_from_arrays(2, I{good, {3}}, I{c, {3}}, D{nan, {3}}, "F"), UsageError);
  EXPECT_THROW(csr_from_arrays(2, I{good, {3}}, I{c, {3}}, D{v, {2}}, "F"), UsageError);
  EXPECT_THROW(csr_from_arrays(3, I{good, {3}}, I{c, {3}}, D{v, {3}}, "F"), UsageError);
  EXPECT_THROW(csr_from_arrays(2, I{good, {3, 1}}, I{c, {3}}, D{v, {3}}, "F"), UsageError);
}

TEST(ArrayArgs, AnEmptyMatrixIsEmpty) {
  // Found by python_args_fuzz: Eigen's reserve + makeCompressed on 0 rows read past its
  // buffer (ASan heap-buffer-overflow).
  const std::int64_t p[] = {0};
  const SparseRowMatrix F = csr_from_arrays(0, I{p, {1}}, I{nullptr, {0}}, D{nullptr, {0}}, "F");
  EXPECT_EQ(F.rows(), 0);
}

TEST(ArrayArgs, RowsOfThreeNeedTheShapeAndFiniteValues) {
  const double v[] = {1, 2, 3, 4, 5, 6}, inf[] = {1, 2, std::numeric_limits<double>::infinity()};
  EXPECT_EQ(rows_of_three(D{v, {2, 3}}, 2, "E")(1, 2), 6.0);
  EXPECT_THROW(rows_of_three(D{v, {3, 2}}, 2, "E"), UsageError);
  EXPECT_THROW(rows_of_three(D{v, {6}}, 2, "E"), UsageError);
  EXPECT_THROW(rows_of_three(D{inf, {1, 3}}, 1, "E"), UsageError);
}

}  // namespace
}  // namespace lambert
