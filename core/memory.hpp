#pragma once
// The memory a job may use: what the machine has available, sizes as users write them.

#include <cstdint>
#include <optional>
#include <string>

namespace lambert {

/// MemAvailable from /proc/meminfo in bytes, or nullopt where it cannot be read.
std::optional<double> available_memory_bytes();

/// Parses a size: a decimal number (digits and one optional '.') followed by nothing (bytes)
/// or K, M, G, T (powers of 1024), optionally with B or iB after it, case-insensitive
/// ("512M", "8G", "1.5GiB"); nullopt for anything else or beyond 2^63 bytes.
std::optional<double> parse_size(const std::string& text);

/// Formats bytes with a binary suffix, e.g. "11.2 GiB".
std::string format_bytes(double bytes);

}  // namespace lambert
