#include "io/strict_number.hpp"

#include <charconv>
#include <cmath>

namespace lambert {
namespace {
// from_chars accepts no '+' sign; strip one in front of a digit or a point.
std::string_view strip_plus(std::string_view t) {
  if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
  return t;
}
}  // namespace

std::string parse_finite(std::string_view token, double& out) {
  const std::string_view t = strip_plus(token);
  if (t.empty()) return "empty number";
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), out,
                                         std::chars_format::general);
  if (ec == std::errc::result_out_of_range) return "out of the range of a double";
  if (ec != std::errc() || ptr != t.data() + t.size()) return "not a number";
  if (!std::isfinite(out)) return "not finite";
  return "";
}

std::string parse_integer(std::string_view token, std::int64_t& out) {
  const std::string_view t = strip_plus(token);
  if (t.empty()) return "empty index";
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  if (ec == std::errc::result_out_of_range) return "out of range";
  if (ec != std::errc() || ptr != t.data() + t.size()) return "not an integer";
  return "";
}

}  // namespace lambert
