#pragma once
// Streaming CSR assembly for the estimators (internal).
//
// Rows are appended in order into storage reserved for an upper bound of entries. The
// reservation is address space only: the allocation is never initialised, and Linux commits
// a page on its first write, so resident memory follows the entries written, and the peak
// of an assembly is the final CSR plus the caller's staging of one block of rows. No
// per-pair lists, no second copy, no growth by doubling.

#include <cstdint>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"

namespace lambert::ff {

/// One entry of a row being built: column, value (and its standard error or variance,
/// whichever the caller keeps).
struct RowEntry {
  std::int32_t col;
  double value;
  double err;
};

/// Appends rows 0, 1, ..., n-1 in order to a CSR F (and a CSR of errors with the same
/// pattern when `with_err`).
class CsrAppender {
 public:
  /// An n x n matrix with room for `max_entries` entries (address space, see above).
  CsrAppender(std::int32_t n, std::int64_t max_entries, bool with_err);

  /// Appends the next row (columns strictly increasing). Throws Error past max_entries.
  void append_row(const std::vector<RowEntry>& row);
  /// Appends rows[0..count) in order, exactly as append_row one by one would, with the
  /// copies (and the first touch of their pages) on `threads` threads.
  void append_rows(const std::vector<RowEntry>* rows, std::int32_t count, int threads);
  /// Entries appended so far.
  std::int64_t size() const { return size_; }
  /// Rows appended so far.
  std::int32_t rows_done() const { return row_; }

  /// The matrix, once every row has been appended; the errors are empty (0 x 0) unless
  /// with_err. The storage keeps its reservation (untouched pages cost nothing).
  void finish(SparseF& F, SparseF& err);

 private:
  SparseF F_, err_;
  std::int32_t n_ = 0, row_ = 0;
  std::int64_t capacity_ = 0, size_ = 0;
  bool with_err_ = false;
};

/// Completes a matrix holding only the upper triangle (j > i) of a reciprocal F into the
/// full one, in place: on entry, entry (i, j) of `F` holds G_ij = A_i F_ij (and `var`, when
/// not empty, the variance of G_ij), and their storage has room for twice the entries; on
/// return F_ij = G_ij / A_i and F_ji = G_ij / A_j (var becomes the standard errors
/// sqrt(var) / A_i and sqrt(var) / A_j). O(nnz) time, O(n) extra memory.
void mirror_upper(SparseF& F, SparseF* var, const std::vector<double>& area);

}  // namespace lambert::ff
