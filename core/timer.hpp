#pragma once
// Wall-clock timer and the process's CPU time.

#include <time.h>

#include <chrono>

namespace lambert {

/// CPU seconds this process has used so far, over all its threads (user + system).
inline double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Measures elapsed wall time from construction or the last reset().
class Timer {
 public:
  Timer() : start_(Clock::now()) {}
  /// Restarts the timer.
  void reset() { start_ = Clock::now(); }
  /// Seconds since construction or reset().
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

}  // namespace lambert
