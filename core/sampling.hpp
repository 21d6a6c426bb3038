#pragma once
// Deterministic random numbers and low-discrepancy sequences. Every stream is a pure
// function of (seed, keys), so results never depend on thread scheduling.

#include <cmath>
#include <cstdint>

namespace lambert {

/// SplitMix64 finaliser: a bijective 64-bit mixer (Steele et al. 2014).
inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Hash of a seed and two keys (e.g. a patch pair), for per-item streams.
inline std::uint64_t hash_keys(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0) {
  return mix64(mix64(mix64(seed) ^ a) ^ (b * 0xD6E8FEB86659FD93ull));
}

/// Maps 64 random bits to a double uniform in [0, 1) (53 bits of mantissa).
inline double to_unit(std::uint64_t bits) { return (bits >> 11) * 0x1.0p-53; }

/// Small fast PRNG (PCG-free SplitMix64 stream); deterministic per seed.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  /// Next 64 random bits.
  std::uint64_t next_u64() {
    state_ += 0x9E3779B97F4A7C15ull;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform double in [0, 1).
  double uniform() { return to_unit(next_u64()); }

 private:
  std::uint64_t state_;
};

/// Randomly shifted Kronecker (R_d) lattice in [0,1)^4 (Roberts 2018): point s has
/// coordinates frac(shift_d + s * alpha_d), alpha_d = phi_4^-d, phi_4 the real root of
/// x^5 = x + 1. Low discrepancy for any count, and a random shift (Cranley-Patterson) makes
/// each point uniformly distributed, so the estimators stay unbiased.
class Kronecker4 {
 public:
  /// Shift drawn from `rng_bits` (a hash of seed and keys).
  explicit Kronecker4(std::uint64_t rng_bits) {
    Rng rng(rng_bits);
    for (double& s : shift_) s = rng.uniform();
  }
  /// Coordinate d (0..3) of point s (s >= 0).
  double get(std::int64_t s, int d) const {
    const double v = shift_[d] + static_cast<double>(s) * kAlpha[d];
    // v >= 0 (far below 2^63), so truncation is floor: two conversions instead of SSE2's
    // masked floor sequence (a tenth of the hybrid kernel's own time), bitwise the same.
    return v - static_cast<double>(static_cast<std::int64_t>(v));
  }

 private:
  // phi_4 = 1.1673039782614187 (root of x^5 = x + 1); alpha_d = phi_4^{-(d+1)}.
  static constexpr double kAlpha[4] = {0.8566748838545029, 0.7338918566271260,
                                       0.6287067210378086, 0.5385972572236101};
  double shift_[4];
};

}  // namespace lambert
