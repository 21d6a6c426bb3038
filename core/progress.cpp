#include "core/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "core/log.hpp"

namespace lambert {

std::string format_si(double value) {
  const char* suffix[] = {"", "k", "M", "G", "T"};
  int s = 0;
  while (std::abs(value) >= 1000.0 && s < 4) {
    value /= 1000.0;
    ++s;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, s == 0 ? "%.0f%s" : "%.1f%s", value, suffix[s]);
  return buf;
}

std::string format_duration(double seconds) {
  char buf[32];
  if (!std::isfinite(seconds) || seconds < 0) return "--";
  if (seconds < 60) {
    std::snprintf(buf, sizeof buf, "%.1fs", seconds);
  } else if (seconds < 3600) {
    std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(seconds) / 60,
                  static_cast<int>(seconds) % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(seconds) / 3600,
                  (static_cast<int>(seconds) / 60) % 60);
  }
  return buf;
}

Progress::Progress(std::string label, std::int64_t total, std::string rate_unit)
    : label_(std::move(label)), unit_(std::move(rate_unit)), total_(total) {
  active_ = log_level() != LogLevel::Quiet && isatty(STDERR_FILENO) == 1 && total_ > 0;
}

Progress::~Progress() { finish(); }

void Progress::advance(std::int64_t done, std::int64_t counted) {
  done_ += done;
  counted_ += counted;
  if (!active_) return;
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  // Redraw at most 10 times per second: drawing must not cost measurable time.
  const double now = timer_.seconds();
  if (now - last_draw_ < 0.1) return;
  last_draw_ = now;
  draw(false);
}

void Progress::finish() {
  if (!active_ || finished_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  finished_ = true;
  draw(true);
}

void Progress::draw(bool final_line) {
  const double t = timer_.seconds();
  const double frac = total_ > 0 ? std::min(1.0, static_cast<double>(done_) / total_) : 1.0;
  constexpr int kWidth = 30;
  std::string bar(static_cast<size_t>(frac * kWidth), '#');
  bar.resize(kWidth, '.');
  std::string rate;
  if (!unit_.empty() && t > 0) rate = "  " + format_si(counted_ / t) + " " + unit_ + "/s";
  const double eta = frac > 0 ? t * (1.0 - frac) / frac : NAN;
  std::fprintf(stderr, "\r%-14s [%s] %5.1f%%%s  %s %s\033[K", label_.c_str(), bar.c_str(),
               100.0 * frac, rate.c_str(), final_line ? "time" : "ETA",
               format_duration(final_line ? t : eta).c_str());
  if (final_line) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace lambert
