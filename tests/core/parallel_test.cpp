#include "core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/error.hpp"
#include "core/sampling.hpp"

namespace lambert {

TEST(ParallelFor, VisitsEveryIndexExactlyOnce) {
  for (int threads : {1, 2, 7}) {
    std::vector<int> hits(1003, 0);
    parallel_for(static_cast<std::int64_t>(hits.size()), 17, threads,
                 [&](std::int64_t b, std::int64_t e) {
                   for (auto i = b; i < e; ++i) ++hits[i];
                 });
    for (int h : hits) ASSERT_EQ(h, 1) << "threads=" << threads;
  }
}

TEST(ParallelFor, RethrowsTheWorkersExceptionOnTheCaller) {
  EXPECT_THROW(parallel_for(100, 1, 4,
                            [](std::int64_t b, std::int64_t) {
                              if (b == 42) throw std::runtime_error("boom");
                            }),
               std::runtime_error);
}

TEST(ParallelFor, ACancelRequestSkipsTheRestAndThrowsCancelled) {
  // Python's Ctrl-C (issue 33, item 8) sets the request from a signal handler; every loop
  // stops claiming chunks and the call ends with Cancelled instead of running to the end.
  for (int threads : {1, 3}) {
    std::atomic<int> ran{0};
    clear_cancel();
    EXPECT_THROW(parallel_for(1000, 1, threads,
                              [&](std::int64_t b, std::int64_t) {
                                ++ran;
                                if (b == 0) request_cancel();
                                // Slow chunks: the request lands long before the end.
                                std::this_thread::sleep_for(std::chrono::microseconds(200));
                              }),
                 Cancelled);
    // One thread: chunk 0 asked and nothing more ran; more threads: the chunks they had
    // claimed still end (a few of the 1000).
    if (threads == 1) {
      EXPECT_EQ(ran.load(), 1);
    }
    EXPECT_LT(ran.load(), 100) << threads;
    EXPECT_TRUE(cancel_requested());
    clear_cancel();
    // Withdrawn, the next loop runs whole.
    std::atomic<int> all{0};
    parallel_for(1000, 1, threads, [&](std::int64_t, std::int64_t) { ++all; });
    EXPECT_EQ(all.load(), 1000);
  }
}

TEST(ParallelSort, IsStdSortWhateverTheThreadCount) {
  // Distinct keys in scrambled order, above the 2^15 elements where pieces start: every
  // thread count (including ones that are not powers of two) gives std::sort's order.
  std::vector<std::uint64_t> keys(300007);
  for (std::size_t k = 0; k < keys.size(); ++k) keys[k] = mix64(k);
  std::vector<std::uint64_t> expected = keys;
  std::sort(expected.begin(), expected.end());
  for (int threads : {1, 2, 3, 8}) {
    std::vector<std::uint64_t> v = keys, buffer(v.size());
    parallel_sort(v.data(), static_cast<std::int64_t>(v.size()), std::less<>(), threads,
                  buffer.data());
    EXPECT_EQ(v, expected) << "threads=" << threads;
  }
}

TEST(ParallelMerge, IsStdMergeWithTiesAndUnequalLengths) {
  // Keys with many ties (k / 7) and a payload telling the inputs apart: std::merge takes
  // a's elements first on ties, and so must every piece boundary of the merge path.
  using Item = std::pair<int, int>;  // (key, payload)
  const auto by_key = [](const Item& x, const Item& y) { return x.first < y.first; };
  std::vector<Item> a, b;
  for (int k = 0; k < 250000; ++k) a.emplace_back(k / 7, k);
  for (int k = 0; k < 70001; ++k) b.emplace_back(3 * k / 7 + 5, -k);
  std::vector<Item> expected(a.size() + b.size());
  std::merge(a.begin(), a.end(), b.begin(), b.end(), expected.begin(), by_key);
  for (int threads : {1, 2, 5}) {
    std::vector<Item> out(expected.size());
    parallel_merge(a.data(), static_cast<std::int64_t>(a.size()), b.data(),
                   static_cast<std::int64_t>(b.size()), out.data(), by_key, threads);
    EXPECT_EQ(out, expected) << "threads=" << threads;
  }
}

TEST(Sampling, KroneckerPointsAreEquidistributed) {
  // A shifted Kronecker lattice has star discrepancy O(log n / n); the count of n = 4096
  // points in any axis-aligned box of volume 1/16 must be within a few percent of n/16,
  // far tighter than the sqrt(n/16) = 16 points of random sampling. Allow 8 points (2 %).
  Kronecker4 seq(hash_keys(7, 1, 2));
  const int n = 4096;
  for (int d = 0; d < 4; ++d) {
    int inside = 0;
    for (int s = 0; s < n; ++s) inside += seq.get(s, d) < 1.0 / 16;
    EXPECT_NEAR(inside, n / 16, 8) << "dimension " << d;
  }
}

}  // namespace lambert
