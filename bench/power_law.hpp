#pragma once
// Power laws y = c x^p fitted by least squares in log-log (benchmarks): growth exponents
// over problem sizes, and values between (or beyond) measured runs. Timings on a shared
// machine are noisy: a fit through all runs is steadier than interpolating between
// neighbours, and extrapolates with the overall slope.

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

/// A fitted y = c x^p over the x range [lo, hi] of its points.
struct PowerLaw {
  double log_c = 0.0, p = 0.0;
  double lo = 0.0, hi = 0.0;
  int points = 0;
  /// The law at x.
  double at(double x) const { return std::exp(log_c + p * std::log(x)); }
  /// The x where the law takes the value y (p != 0).
  double inverse(double y) const { return std::exp((std::log(y) - log_c) / p); }
  /// Whether x lies outside the points' range.
  bool extrapolates(double x) const { return x < lo || x > hi; }
};

/// Least squares of log y on log x over points with x, y > 0 (y floored at 1e-300); the
/// exponent is 0 with fewer than two distinct x.
inline PowerLaw fit_power_law(const std::vector<std::pair<double, double>>& pts) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  PowerLaw f;
  f.lo = 1e300;
  for (const auto& [px, py] : pts) {
    const double lx = std::log(px), ly = std::log(std::max(py, 1e-300));
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
    f.lo = std::min(f.lo, px), f.hi = std::max(f.hi, px);
  }
  f.points = static_cast<int>(pts.size());
  if (pts.empty()) return f;
  const double n = static_cast<double>(pts.size());
  const double den = n * sxx - sx * sx;
  f.p = den > 0 ? (n * sxy - sx * sy) / den : 0.0;
  f.log_c = (sy - f.p * sx) / n;
  return f;
}
