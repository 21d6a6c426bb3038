#pragma once
// Thread pool-free parallel loops. Work is split into fixed chunks handed out dynamically;
// results must not depend on which thread runs a chunk (callers write to per-index slots).

#include <algorithm>
#include <cstdint>
#include <functional>

namespace lambert {

/// Number of threads to use: `requested` if > 0, else the hardware concurrency (at least 1).
int resolve_threads(int requested);

/// Asks every parallel_for to stop: no further chunk is claimed, and once the running ones
/// end it throws Cancelled. Async-signal-safe (a SIGINT handler may call it: the Python
/// bindings do while the GIL is released).
void request_cancel();
/// Withdraws the request (before new work starts).
void clear_cancel();
/// True while a stop is requested.
bool cancel_requested();

/// Calls body(begin, end) over [0, n) in chunks of `chunk` indices on `threads` threads.
/// Chunks are claimed dynamically (good load balance for uneven work). The first exception
/// thrown by any body is captured, remaining chunks are skipped, and it is rethrown here;
/// a request_cancel skips the remaining chunks too and throws Cancelled.
/// Thread safety: body must only write to state owned by its index range.
void parallel_for(std::int64_t n, std::int64_t chunk, int threads,
                  const std::function<void(std::int64_t begin, std::int64_t end)>& body);

/// Merges the sorted ranges a[0, na) and b[0, nb) into out[0, na + nb) (std::merge's result:
/// on ties a's elements first) in `threads` pieces split along the merge path, so the result
/// does not depend on the thread count.
template <class T, class Less>
void parallel_merge(const T* a, std::int64_t na, const T* b, std::int64_t nb, T* out, Less less,
                    int threads) {
  const std::int64_t n = na + nb;
  // Pieces of at least 2^15 elements: a smaller merge is not worth a thread.
  const std::int64_t pieces =
      std::max<std::int64_t>(1, std::min<std::int64_t>(resolve_threads(threads), n >> 15));
  // The number of a's elements among the first k of the merge: the first i such that b's
  // element k - i - 1 precedes a's element i (binary search along the merge path).
  const auto split = [&](std::int64_t k) {
    std::int64_t lo = std::max<std::int64_t>(0, k - nb), hi = std::min(k, na);
    while (lo < hi) {
      const std::int64_t mid = lo + (hi - lo) / 2;
      if (less(b[k - mid - 1], a[mid]))
        hi = mid;
      else
        lo = mid + 1;
    }
    return lo;
  };
  parallel_for(pieces, 1, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t piece = begin; piece < end; ++piece) {
      const std::int64_t k0 = n * piece / pieces, k1 = n * (piece + 1) / pieces;
      const std::int64_t i0 = split(k0), i1 = split(k1);
      std::merge(a + i0, a + i1, b + (k0 - i0), b + (k1 - i1), out + k0, less);
    }
  });
}

/// Sorts data[0, n) by `less` on `threads` threads: pieces sorted in parallel, then merged
/// pairwise by parallel_merge through `buffer` (room for n elements). When `less` orders
/// every two distinct elements (no ties), the result is std::sort's whatever the thread count.
template <class T, class Less>
void parallel_sort(T* data, std::int64_t n, Less less, int threads, T* buffer) {
  const int t = resolve_threads(threads);
  if (t <= 1 || n < (std::int64_t{1} << 15)) {
    std::sort(data, data + n, less);
    return;
  }
  std::int64_t pieces = 1;
  while (pieces < t) pieces *= 2;  // a power of two: every merge round pairs all pieces
  const auto bound = [&](std::int64_t piece) { return n * piece / pieces; };
  parallel_for(pieces, 1, t, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t piece = begin; piece < end; ++piece)
      std::sort(data + bound(piece), data + bound(piece + 1), less);
  });
  T* from = data;
  T* to = buffer;
  for (std::int64_t width = 1; width < pieces; width *= 2) {
    for (std::int64_t piece = 0; piece < pieces; piece += 2 * width) {
      const std::int64_t lo = bound(piece), mid = bound(piece + width),
                         hi = bound(piece + 2 * width);
      parallel_merge(from + lo, mid - lo, from + mid, hi - mid, to + lo, less, t);
    }
    std::swap(from, to);
  }
  if (from != data) std::copy(from, from + n, data);
}

}  // namespace lambert
