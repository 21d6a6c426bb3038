#pragma once
// One strict routine for the numbers of lambert's text formats.

#include <cstdint>
#include <string>
#include <string_view>

namespace lambert {

/// Parses a whole token as a finite decimal number: optional sign ('+' or '-'), digits
/// with an optional '.', an optional exponent (`1e5`, `2.5E-3`), nothing else. Refused
/// (returns a reason, empty on success): trailing or embedded text (`3.1+e2`, `1e`),
/// hexadecimal floats (`0x1p3`), `inf`/`nan` and values outside double's range (above
/// ~1.8e308 or nonzero below ~4.9e-324). Any number of digits is read correctly rounded.
std::string parse_finite(std::string_view token, double& out);

/// Parses a whole token as a decimal integer (optional sign) in [-2^63, 2^63); returns a
/// reason on failure, empty on success.
std::string parse_integer(std::string_view token, std::int64_t& out);

}  // namespace lambert
