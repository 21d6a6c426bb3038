#pragma once
// The transport operator F as the solvers see it: y = F x, rows for gathering sweeps, columns
// through reciprocity for shooting, the diagonal and row sums. Solvers never see how F is
// stored; CsrOperator (an assembled row-major F) is the one implementation today.
//
// Why virtual and not a template: solvers are a table of plain functions chosen by name
// (radiosity.cpp) and RadiosityProblem is a value type the apps build; a template parameter
// would turn every solver and the problem into templates instantiated per operator. The
// calls are coarse: apply() is one call per product, row() one call per row returning a span
// the solver loops over without further calls, so the indirection costs one call per row
// (a row holds hundreds to thousands of entries), never one per entry.

#include <Eigen/Core>
#include <cstdint>

#include "core/sparse.hpp"

namespace lambert {

/// F as an operator on per-patch vectors (N x N, row i holds F_ij for the patches j that
/// patch i sees). Implementations are immutable after construction and thread-safe to read.
class TransportOperator {
 public:
  /// Column index of an entry (the storage index of SparseRowMatrix, whatever its width).
  using ColumnIndex = SparseRowMatrix::StorageIndex;

  /// The entries (cols[k], values[k]), k < count, of one row; valid while the operator lives.
  struct RowSpan {
    const ColumnIndex* cols = nullptr;
    const double* values = nullptr;
    std::int64_t count = 0;
  };

  virtual ~TransportOperator() = default;

  /// N, the number of patches.
  virtual std::int32_t size() const = 0;
  /// Stored entries (for work accounting: one product reads this many).
  virtual std::int64_t entries() const = 0;
  /// y = F x with rows split over `threads` (1 = serial, 0 = all cores). Every y_i is summed
  /// serially in storage order, so y is bitwise independent of the thread count.
  virtual void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y, int threads) const = 0;
  /// Row i of F (gathering: B_i needs sum_j F_ij B_j).
  virtual RowSpan row(std::int32_t i) const = 0;
  /// F_ii per patch (0 for planar patches).
  virtual Eigen::VectorXd diagonal() const = 0;
  /// sum_j F_ij per patch (1 for a patch inside a closed enclosure).
  virtual Eigen::VectorXd row_sums() const = 0;
  /// The assembled matrix, for methods that factorise it (direct, ILUT); null when the
  /// operator is matrix-free.
  virtual const SparseRowMatrix* matrix() const { return nullptr; }
};

/// Column i of F through reciprocity, F_ji = A_i F_ij / A_j, from row i: calls
/// visit(j, F_ji) for every stored entry of row i (the self term j = i included). Exact for a
/// reciprocal F (A_i F_ij = A_j F_ji); for any other F it is the column of the reciprocal F'
/// built from F's rows (southwell corrects for the difference by refinement). O(row nnz).
template <class Visit>
void visit_column_by_reciprocity(const TransportOperator& F, const Eigen::VectorXd& area,
                                 std::int32_t i, Visit&& visit) {
  const TransportOperator::RowSpan r = F.row(i);
  for (std::int64_t k = 0; k < r.count; ++k) {
    const auto j = static_cast<std::int32_t>(r.cols[k]);
    visit(j, r.values[k] * area[i] / area[j]);
  }
}

/// TransportOperator over an assembled row-major F (which must outlive it; it is read at
/// every call, never copied).
class CsrOperator final : public TransportOperator {
 public:
  /// Wraps F (square; the caller checks sizes against the problem). F must be compressed
  /// (every F the engine builds or reads is); throws UsageError otherwise.
  explicit CsrOperator(const SparseRowMatrix& F);

  std::int32_t size() const override { return static_cast<std::int32_t>(F_.rows()); }
  std::int64_t entries() const override { return static_cast<std::int64_t>(F_.nonZeros()); }
  /// Cost O(nnz); bandwidth-bound (value + index per entry plus gathers of x).
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y, int threads) const override;
  RowSpan row(std::int32_t i) const override;
  Eigen::VectorXd diagonal() const override { return F_.diagonal(); }
  Eigen::VectorXd row_sums() const override;
  const SparseRowMatrix* matrix() const override { return &F_; }

 private:
  const SparseRowMatrix& F_;
};

}  // namespace lambert
