#pragma once
// Thread pool-free parallel loops. Work is split into fixed chunks handed out dynamically;
// results must not depend on which thread runs a chunk (callers write to per-index slots).

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

}  // namespace lambert
