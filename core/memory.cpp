#include "core/memory.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace lambert {

std::optional<double> available_memory_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string key, unit;
    double kib = 0;
    if (ss >> key >> kib >> unit && key == "MemAvailable:" && unit == "kB") return kib * 1024.0;
  }
  return std::nullopt;
}

std::optional<double> parse_size(const std::string& text) {
  const auto digits = text.find_first_not_of("0123456789.");
  const std::string number = text.substr(0, digits);
  if (number.empty() || number == "." || number.find('.') != number.rfind('.')) return std::nullopt;
  const double n = std::strtod(number.c_str(), nullptr);
  std::string suffix = digits == std::string::npos ? "" : text.substr(digits);
  for (char& c : suffix) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (!suffix.empty() && suffix.back() == 'B') suffix.pop_back();  // 512B, 2GB, 2GiB
  if (suffix.size() == 2 && suffix[1] == 'I') suffix.pop_back();  // KiB, MiB, ...
  static const std::string kUnits = "KMGT";
  double scale = 1.0;
  if (!suffix.empty()) {
    const auto k = kUnits.find(suffix);
    if (suffix.size() != 1 || k == std::string::npos) return std::nullopt;
    scale = std::pow(1024.0, static_cast<double>(k + 1));
  }
  const double bytes = n * scale;
  if (!std::isfinite(bytes) || bytes < 0 || bytes > 9.2e18) return std::nullopt;
  return bytes;
}

std::string format_bytes(double bytes) {
  const char* suffix[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int s = 0;
  while (bytes >= 1024.0 && s < 6) {
    bytes /= 1024.0;
    ++s;
  }
  char buf[48];
  std::snprintf(buf, sizeof buf, s == 0 ? "%.0f %s" : "%.1f %s", bytes, suffix[s]);
  return buf;
}

}  // namespace lambert
