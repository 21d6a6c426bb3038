#include "solvers/operator.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace lambert {

CsrOperator::CsrOperator(const SparseRowMatrix& F) : F_(F) {
  if (!F.isCompressed()) throw UsageError("form-factor matrix is not in compressed storage");
}

void CsrOperator::apply(const Eigen::VectorXd& x, Eigen::VectorXd& y, int threads) const {
  using Offset = SparseRowMatrix::StorageIndex;  // entry offsets: as wide as F's storage
  const std::int32_t n = size();
  y.resize(n);
  const double* values = F_.valuePtr();
  const Offset* inner = F_.innerIndexPtr();
  const Offset* outer = F_.outerIndexPtr();
  const double* xs = x.data();
  double* ys = y.data();
  auto rows = [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      double s = 0.0;
      for (Offset k = outer[i]; k < outer[i + 1]; ++k) s += values[k] * xs[inner[k]];
      ys[i] = s;
    }
  };
  // Threads only pay off when there is enough work per product (thread start ~50 us).
  constexpr std::int64_t kMinNonZerosPerThread = 1 << 18;
  const int workers = resolve_threads(threads);
  if (workers <= 1 || entries() < kMinNonZerosPerThread * 2) {
    rows(0, n);
  } else {
    parallel_for(n, std::max<std::int64_t>(64, n / (8 * workers)), workers, rows);
  }
}

TransportOperator::RowSpan CsrOperator::row(std::int32_t i) const {
  const auto begin = F_.outerIndexPtr()[i];
  const auto end = F_.outerIndexPtr()[i + 1];
  return {F_.innerIndexPtr() + begin, F_.valuePtr() + begin, static_cast<std::int64_t>(end - begin)};
}

Eigen::VectorXd CsrOperator::row_sums() const {
  Eigen::VectorXd s(size());
  for (std::int32_t i = 0; i < size(); ++i) {
    const RowSpan r = row(i);
    double sum = 0.0;
    for (std::int64_t k = 0; k < r.count; ++k) sum += r.values[k];
    s[i] = sum;
  }
  return s;
}

}  // namespace lambert
