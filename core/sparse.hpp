#pragma once
// The sparse matrix type shared by the form-factor engine and the solvers.

#include <Eigen/SparseCore>
#include <cstdint>

namespace lambert {

/// Row-major sparse matrix with 32-bit indices (Eigen's default storage index).
using SparseRowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, std::int32_t>;

}  // namespace lambert
