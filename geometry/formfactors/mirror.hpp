#pragma once
// Finding the mirror F_ji of each entry F_ij of a row-major sparse F.

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

namespace lambert::ff {

/// Finds mirrors for rows visited in increasing order (parallel_for hands each thread its
/// chunks in increasing order; one cursor per thread): the lookup of column i in row j starts
/// where this cursor's last lookup in row j ended (the lower bound of a smaller column), so
/// rows near each other, which see mostly the same patches, take a few steps instead of a
/// binary search. The position found is that of column i in row j (or -1) whatever the
/// cursor held. `call` (next_call(), one per pass over an F) tells one pass's cursors from
/// an earlier pass's.
class MirrorCursor {
 public:
  static std::uint64_t next_call() {
    static std::atomic<std::uint64_t> calls{0};
    return ++calls;  // never 0, the tag of a row not yet looked up
  }
  /// Makes room for n rows.
  void rows(std::int64_t n) {
    if (static_cast<std::int64_t>(tag_.size()) < n) {
      tag_.resize(static_cast<std::size_t>(n), 0);
      at_.resize(static_cast<std::size_t>(n), 0);
    }
  }
  /// Position of column i in row j of the CSR arrays (col, outer), or -1.
  template <class Index>
  std::int64_t find(const Index* col, const Index* outer, Index j, Index i, std::uint64_t call) {
    const auto row = static_cast<std::size_t>(j);
    std::int64_t p = tag_[row] == call ? at_[row] : outer[j];
    const std::int64_t end = outer[j + 1];
    for (int step = 0; step < kSteps && p < end && col[p] < i; ++step) ++p;
    if (p < end && col[p] < i) p = std::lower_bound(col + p, col + end, i) - col;
    tag_[row] = call;
    at_[row] = p;
    return p < end && col[p] == i ? p : -1;
  }

 private:
  static constexpr int kSteps = 8;  // then a binary search over the rest of the row
  std::vector<std::uint64_t> tag_;
  std::vector<std::int64_t> at_;
};

}  // namespace lambert::ff
