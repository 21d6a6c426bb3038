#pragma once
// Progress bar on stderr: fraction done, rate and ETA. Drawn only when stderr is a terminal
// and the log level is not Quiet; otherwise every call is a cheap no-op.

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "core/timer.hpp"

namespace lambert {

/// A thread-safe progress bar for one stage of work.
class Progress {
 public:
  /// `total` work units; `rate_unit` names what rate() counts (e.g. "rays").
  Progress(std::string label, std::int64_t total, std::string rate_unit = "");
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Adds `done` work units and `counted` rate units (e.g. rays traced); thread-safe.
  void advance(std::int64_t done, std::int64_t counted = 0);
  /// Draws the final state and ends the line.
  void finish();
  /// True when the bar is being drawn.
  bool active() const { return active_; }

 private:
  void draw(bool final_line);

  std::string label_;
  std::string unit_;
  std::int64_t total_;
  std::atomic<std::int64_t> done_{0};
  std::atomic<std::int64_t> counted_{0};
  bool active_ = false;
  bool finished_ = false;
  double last_draw_ = -1.0;
  std::mutex mutex_;
  Timer timer_;
};

/// Formats a count with an SI suffix, e.g. 12.3M.
std::string format_si(double value);
/// Formats seconds as e.g. 1m05s or 3.2s.
std::string format_duration(double seconds);

}  // namespace lambert
