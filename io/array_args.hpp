#pragma once
// Arrays handed in by a caller (the Python module's numpy arguments), checked before any use:
// a compressed-row matrix from its three arrays and an (N, 3) table. Everything the caller
// may get wrong (shapes, an indptr that decreases or overshoots, indices out of range or out
// of order, non-finite values) is a UsageError naming the argument; nothing is read before
// the check that makes the read safe. Fuzzed by tests/fuzz/python_args_fuzz.cpp.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/sparse.hpp"

namespace lambert {

/// A read-only view of a caller's C-contiguous array: its data and shape.
template <typename T>
struct ArrayArg {
  const T* data = nullptr;
  std::vector<std::int64_t> shape;
  std::int64_t size() const {
    std::int64_t s = 1;
    for (const std::int64_t d : shape) s *= d;
    return s;
  }
};

/// The n x n matrix whose rows are indptr[i] .. indptr[i+1] of (indices, data), as scipy's
/// csr_matrix holds it. `what` names the matrix in messages.
SparseRowMatrix csr_from_arrays(std::int64_t n, const ArrayArg<std::int64_t>& indptr,
                                const ArrayArg<std::int64_t>& indices, const ArrayArg<double>& data,
                                const std::string& what);

/// An (n, 3) array of finite values as an Eigen matrix.
Eigen::MatrixX3d rows_of_three(const ArrayArg<double>& a, std::int64_t n, const std::string& what);

}  // namespace lambert
