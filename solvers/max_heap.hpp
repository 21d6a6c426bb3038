#pragma once
// An indexed binary max-heap over the keys of items 0..N-1, for southwell's choice of the
// next shooter. Internal to solvers/.
//
// Order: larger key first; equal keys by lower index first; NaN ranks below every number
// (as -inf, and after it by index). So top() is exactly what the scan
//   best = -1; for j: if (key_j > best) best = key_j, i = j
// returns for keys >= 0 or NaN (the scan's first maximum; index 0 when every key is NaN).
// Cost: build O(N), top O(1), update O(log N). Not thread-safe (one solver owns it).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace lambert {

/// Indexed max-heap of N keys with changeable keys (see the header comment for the order).
class IndexedMaxHeap {
 public:
  /// Builds the heap over keys[0..N-1].
  explicit IndexedMaxHeap(const Eigen::VectorXd& keys) { reset(keys); }

  /// Rebuilds the heap over new keys (same or other N). O(N).
  void reset(const Eigen::VectorXd& keys) {
    const auto n = static_cast<std::int32_t>(keys.size());
    key_.resize(n);
    heap_.resize(n);
    pos_.resize(n);
    for (std::int32_t j = 0; j < n; ++j) {
      key_[j] = sanitize(keys[j]);
      heap_[j] = j;
      pos_[j] = j;
    }
    for (std::int32_t p = n / 2 - 1; p >= 0; --p) sift_down(p);
  }

  /// The item first in the order (requires N > 0).
  std::int32_t top() const { return heap_[0]; }

  /// Sets item j's key and restores the heap. O(log N).
  void update(std::int32_t j, double key) {
    const double k = sanitize(key);
    const double old = key_[j];
    key_[j] = k;
    if (k > old)
      sift_up(pos_[j]);
    else if (k < old)
      sift_down(pos_[j]);
  }

 private:
  static double sanitize(double k) {
    return std::isnan(k) ? -std::numeric_limits<double>::infinity() : k;
  }
  // Whether item a comes before item b.
  bool before(std::int32_t a, std::int32_t b) const {
    return key_[a] > key_[b] || (key_[a] == key_[b] && a < b);
  }
  void place(std::int32_t p, std::int32_t item) {
    heap_[p] = item;
    pos_[item] = p;
  }
  void sift_up(std::int32_t p) {
    const std::int32_t item = heap_[p];
    while (p > 0) {
      const std::int32_t parent = (p - 1) / 2;
      if (!before(item, heap_[parent])) break;
      place(p, heap_[parent]);
      p = parent;
    }
    place(p, item);
  }
  void sift_down(std::int32_t p) {
    const auto n = static_cast<std::int32_t>(heap_.size());
    const std::int32_t item = heap_[p];
    for (;;) {
      std::int32_t child = 2 * p + 1;
      if (child >= n) break;
      if (child + 1 < n && before(heap_[child + 1], heap_[child])) ++child;
      if (!before(heap_[child], item)) break;
      place(p, heap_[child]);
      p = child;
    }
    place(p, item);
  }

  std::vector<double> key_;         // key per item
  std::vector<std::int32_t> heap_;  // item at heap position
  std::vector<std::int32_t> pos_;   // heap position of item
};

}  // namespace lambert
