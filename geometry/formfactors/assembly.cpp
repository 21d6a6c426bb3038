#include "geometry/formfactors/assembly.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace lambert::ff {

namespace {
// An n x n CSR with every row empty and `capacity` entries of uninitialised storage.
void reserve_csr(SparseF& M, std::int32_t n, std::int64_t capacity) {
  M.resize(n, n);  // row starts all 0
  M.resizeNonZeros(capacity);
}
}  // namespace

CsrAppender::CsrAppender(std::int32_t n, std::int64_t max_entries, bool with_err)
    : n_(n), capacity_(std::max<std::int64_t>(0, max_entries)), with_err_(with_err) {
  reserve_csr(F_, n, capacity_);
  if (with_err_) reserve_csr(err_, n, capacity_);
}

void CsrAppender::append_row(const std::vector<RowEntry>& row) {
  LAMBERT_CHECK(row_ < n_, "CsrAppender: more rows than the matrix has");
  const auto count = static_cast<std::int64_t>(row.size());
  LAMBERT_CHECK(size_ + count <= capacity_, "CsrAppender: more entries than reserved");
  auto* inner = F_.innerIndexPtr();
  double* value = F_.valuePtr();
  for (std::int64_t k = 0; k < count; ++k) {
    inner[size_ + k] = row[k].col;
    value[size_ + k] = row[k].value;
  }
  if (with_err_) {
    auto* err_inner = err_.innerIndexPtr();
    double* err_value = err_.valuePtr();
    for (std::int64_t k = 0; k < count; ++k) {
      err_inner[size_ + k] = row[k].col;
      err_value[size_ + k] = row[k].err;
    }
  }
  size_ += count;
  ++row_;
  F_.outerIndexPtr()[row_] = size_;
  if (with_err_) err_.outerIndexPtr()[row_] = size_;
}

void CsrAppender::append_rows(const std::vector<RowEntry>* rows, std::int32_t count, int threads) {
  LAMBERT_CHECK(count >= 0 && row_ + count <= n_, "CsrAppender: more rows than the matrix has");
  auto* outer = F_.outerIndexPtr();
  for (std::int32_t r = 0; r < count; ++r) {
    const auto size = static_cast<std::int64_t>(rows[r].size());
    LAMBERT_CHECK(outer[row_ + r] + size <= capacity_, "CsrAppender: more entries than reserved");
    outer[row_ + r + 1] = outer[row_ + r] + size;
  }
  if (with_err_)
    std::copy(outer + row_ + 1, outer + row_ + count + 1, err_.outerIndexPtr() + row_ + 1);
  auto* inner = F_.innerIndexPtr();
  double* value = F_.valuePtr();
  auto* err_inner = with_err_ ? err_.innerIndexPtr() : nullptr;
  double* err_value = with_err_ ? err_.valuePtr() : nullptr;
  const std::int32_t first = row_;
  parallel_for(count, 64, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t r = begin; r < end; ++r) {
      const std::vector<RowEntry>& row = rows[r];
      const std::int64_t at = outer[first + r];
      for (size_t k = 0; k < row.size(); ++k) {
        inner[at + k] = row[k].col;
        value[at + k] = row[k].value;
      }
      if (err_inner)
        for (size_t k = 0; k < row.size(); ++k) {
          err_inner[at + k] = row[k].col;
          err_value[at + k] = row[k].err;
        }
    }
  });
  row_ += count;
  size_ = outer[row_];
}

void CsrAppender::finish(SparseF& F, SparseF& err) {
  LAMBERT_CHECK(row_ == n_, "CsrAppender: finished before every row was appended");
  F_.resizeNonZeros(size_);  // within the allocation: no copy
  F.swap(F_);  // swap, not move: keeps the reservation (a copy would not)
  if (with_err_) {
    err_.resizeNonZeros(size_);
    err.swap(err_);
  } else {
    err = SparseF();
  }
}

void mirror_upper(SparseF& F, SparseF* var, const std::vector<double>& area) {
  const std::int32_t n = static_cast<std::int32_t>(F.rows());
  const std::int64_t upper = F.nonZeros();
  const bool with_var = var != nullptr && var->rows() > 0;
  LAMBERT_CHECK(F.data().allocatedSize() >= 2 * upper &&
                    (!with_var || var->data().allocatedSize() >= 2 * upper),
                "mirror_upper: the storage has no room for the lower triangle");
  std::vector<std::int64_t> lower(n, 0);  // entries row i receives from rows above it
  for (std::int64_t k = 0; k < upper; ++k) ++lower[F.innerIndexPtr()[k]];
  std::vector<std::int64_t> start(static_cast<size_t>(n) + 1, 0);
  const auto* old_start = F.outerIndexPtr();
  for (std::int32_t i = 0; i < n; ++i)
    start[i + 1] = start[i] + lower[i] + (old_start[i + 1] - old_start[i]);
  F.resizeNonZeros(2 * upper);  // within the allocation: pointers and contents unchanged
  if (with_var) var->resizeNonZeros(2 * upper);

  auto* outer = F.outerIndexPtr();
  auto* inner = F.innerIndexPtr();
  double* value = F.valuePtr();
  double* v = with_var ? var->valuePtr() : nullptr;
  // Move each row's upper part to its final place, after the slots of its lower part. The
  // final start of row i is at or after its current one (rows above gain their lower
  // parts), so moving from the last row to the first never overwrites a row not yet moved.
  for (std::int32_t i = n - 1; i >= 0; --i) {
    const std::int64_t from = outer[i], count = outer[i + 1] - outer[i];
    const std::int64_t to = start[i] + lower[i];
    std::copy_backward(inner + from, inner + from + count, inner + to + count);
    std::copy_backward(value + from, value + from + count, value + to + count);
    if (v) std::copy_backward(v + from, v + from + count, v + to + count);
  }
  // Lower parts: entry (m, j) of the upper triangle becomes (j, m); visiting m in
  // increasing order keeps every row's columns sorted.
  std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
  for (std::int32_t m = 0; m < n; ++m) {
    for (std::int64_t k = start[m] + lower[m]; k < start[m + 1]; ++k) {
      const auto j = static_cast<std::int32_t>(inner[k]);
      const std::int64_t at = fill[j]++;
      inner[at] = m;
      value[at] = value[k] / area[j];
      if (v) v[at] = std::sqrt(v[k]) / area[j];
    }
  }
  for (std::int32_t i = 0; i < n; ++i) {
    for (std::int64_t k = start[i] + lower[i]; k < start[i + 1]; ++k) {
      value[k] /= area[i];
      if (v) v[k] = std::sqrt(v[k]) / area[i];
    }
  }
  std::copy(start.begin(), start.end(), outer);
  if (with_var) {
    std::copy(start.begin(), start.end(), var->outerIndexPtr());
    std::copy(inner, inner + 2 * upper, var->innerIndexPtr());
  }
}

}  // namespace lambert::ff
