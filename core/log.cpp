#include "core/log.hpp"

#include <atomic>
#include <iostream>
#include <mutex>

#include "core/error.hpp"

namespace lambert {
namespace {
std::atomic<int> g_level{static_cast<int>(LogLevel::Normal)};
std::mutex g_mutex;

void emit(const std::string& prefix, const std::string& msg) {
  std::lock_guard<std::mutex> lock(g_mutex);
  std::cerr << prefix << msg << '\n';
}
}  // namespace

void set_log_level(LogLevel level) { g_level = static_cast<int>(level); }
LogLevel log_level() { return static_cast<LogLevel>(g_level.load()); }

void log_info(const std::string& msg) {
  if (g_level >= static_cast<int>(LogLevel::Normal)) emit("", msg);
}
void log_warn(const std::string& msg) {
  if (g_level >= static_cast<int>(LogLevel::Normal)) emit("warning: ", msg);
}
void log_debug(const std::string& msg) {
  if (g_level >= static_cast<int>(LogLevel::Verbose)) emit("debug: ", msg);
}

void check_failed(const char* expr, const char* file, int line, const std::string& msg) {
  throw InternalError(std::string("internal error: ") + expr + " failed at " + file + ":" +
                      std::to_string(line) + ": " + msg);
}

std::string thousands(std::int64_t n) {
  const std::string digits = std::to_string(n);
  const std::size_t first = n < 0 ? 1 : 0;  // after the sign
  std::string out = digits.substr(0, first);
  for (std::size_t k = first; k < digits.size(); ++k) {
    if (k > first && (digits.size() - k) % 3 == 0) out += ',';
    out += digits[k];
  }
  return out;
}

}  // namespace lambert
