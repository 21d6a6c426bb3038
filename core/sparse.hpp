#pragma once
// The sparse matrix type shared by the form-factor engine and the solvers.

#include <Eigen/SparseCore>
#include <cstdint>

namespace lambert {

/// Row-major sparse matrix with 64-bit indices: a form-factor matrix of 10^5 patches holds
/// more than 2^31 entries. (Row and column numbers are patch indices and fit 32 bits; Eigen
/// has one StorageIndex for offsets and columns, so columns take 8 bytes too: 16 bytes per
/// entry.)
using SparseRowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, std::int64_t>;

}  // namespace lambert
