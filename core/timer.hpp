#pragma once
// Wall-clock timer.

#include <chrono>

namespace lambert {

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
