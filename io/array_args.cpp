#include "io/array_args.hpp"

#include <cmath>
#include <sstream>

#include "core/error.hpp"

namespace lambert {
namespace {

std::string shape_text(const std::vector<std::int64_t>& shape) {
  std::ostringstream ss;
  ss << '(';
  for (std::size_t d = 0; d < shape.size(); ++d) ss << (d ? ", " : "") << shape[d];
  ss << (shape.size() == 1 ? ",)" : ")");
  return ss.str();
}

}  // namespace

SparseRowMatrix csr_from_arrays(std::int64_t n, const ArrayArg<std::int64_t>& indptr,
                                const ArrayArg<std::int64_t>& indices, const ArrayArg<double>& data,
                                const std::string& what) {
  if (indptr.shape.size() != 1 || indices.shape.size() != 1 || data.shape.size() != 1)
    throw UsageError(what + ": indptr, indices and data must be one-dimensional");
  if (n < 0 || indptr.shape[0] != n + 1)
    throw UsageError(what + ": indptr has " + std::to_string(indptr.shape[0]) + " entries, " +
                     std::to_string(n + 1) + " expected for " + std::to_string(n) + " rows");
  const std::int64_t nnz = indices.shape[0];
  if (data.shape[0] != nnz) throw UsageError(what + ": indices and data differ in length");
  const std::int64_t* p = indptr.data;
  const std::int64_t* c = indices.data;
  const double* v = data.data;
  if (p[0] != 0 || p[n] != nnz) throw UsageError(what + ": indptr must run from 0 to nnz");
  // indptr whole before any use of it (a reserve or a row's range): a decreasing or
  // overshooting entry would size rows negative or read past indices and data.
  for (std::int64_t i = 0; i < n; ++i)
    if (p[i + 1] < p[i] || p[i + 1] > nnz)
      throw UsageError(what + ": indptr decreases or passes nnz at row " + std::to_string(i));
  SparseRowMatrix F(n, n);
  if (n == 0) return F;  // Eigen's reserve + makeCompressed read past a 0-row matrix
  F.reserve(Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>::Map(p, n + 1).tail(n) -
            Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>::Map(p, n + 1).head(n));
  for (std::int64_t i = 0; i < n; ++i) {
    for (std::int64_t k = p[i]; k < p[i + 1]; ++k) {
      if (c[k] < 0 || c[k] >= n || (k > p[i] && c[k] <= c[k - 1]))
        throw UsageError(what + ": row " + std::to_string(i) +
                         " has a column index out of range or out of order");
      if (!std::isfinite(v[k]))
        throw UsageError(what + ": entry (" + std::to_string(i) + ", " + std::to_string(c[k]) +
                         ") is not finite");
      F.insert(i, c[k]) = v[k];
    }
  }
  F.makeCompressed();
  return F;
}

Eigen::MatrixX3d rows_of_three(const ArrayArg<double>& a, std::int64_t n, const std::string& what) {
  if (a.shape.size() != 2 || a.shape[1] != 3 || a.shape[0] != n)
    throw UsageError(what + " must have shape (" + std::to_string(n) + ", 3), got " +
                     shape_text(a.shape));
  Eigen::MatrixX3d m(n, 3);
  for (std::int64_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(a.data[3 * i + c]))
        throw UsageError(what + " holds a non-finite value at row " + std::to_string(i));
      m(i, c) = a.data[3 * i + c];
    }
  return m;
}

}  // namespace lambert
