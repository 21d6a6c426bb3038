#pragma once
// Logging to stderr. stdout carries results only.

#include <cstdint>
#include <string>

namespace lambert {

/// Verbosity of stderr messages.
enum class LogLevel { Quiet = 0, Normal = 1, Verbose = 2 };

/// Sets the global verbosity (the CLI's --quiet / --verbose).
void set_log_level(LogLevel level);
/// Current global verbosity.
LogLevel log_level();

/// Informational message on stderr (hidden by --quiet).
void log_info(const std::string& msg);
/// Warning on stderr, prefixed "warning: " (hidden by --quiet).
void log_warn(const std::string& msg);
/// Detail on stderr shown only with --verbose.
void log_debug(const std::string& msg);

/// A count with thousands separators for log lines: 69938 -> "69,938".
std::string thousands(std::int64_t n);

}  // namespace lambert
