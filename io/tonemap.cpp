#include "io/tonemap.hpp"

#include <algorithm>
#include <cmath>

#include "io/png.hpp"

namespace lambert {

double srgb_oetf(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
}

double auto_exposure(const Image& image, bool surfaces_only) {
  double log_sum = 0.0;
  std::int64_t n = 0;
  const size_t count = image.alpha.size();
  for (size_t k = 0; k < count; ++k) {
    const double lum =
        0.2126 * image.rgb[3 * k] + 0.7152 * image.rgb[3 * k + 1] + 0.0722 * image.rgb[3 * k + 2];
    // Pixels that see nothing lit (misses, back faces, unlit surfaces) carry no exposure
    // information; a log of 0 would drive the mean to -inf.
    if (!(lum > 0.0) || !std::isfinite(lum)) continue;
    if (surfaces_only && !(image.alpha[k] > 0.0f)) continue;
    log_sum += std::log(lum);
    ++n;
  }
  if (n == 0) return 0.0;
  return std::log2(kKey) - log_sum / static_cast<double>(n) / std::log(2.0);
}

std::array<std::uint8_t, 3> to_srgb8(const Eigen::Vector3d& linear, double ev) {
  const double scale = std::exp2(ev);
  std::array<std::uint8_t, 3> out{};
  for (int c = 0; c < 3; ++c) {
    const double v = std::isfinite(linear[c]) ? linear[c] * scale : 0.0;
    out[c] = static_cast<std::uint8_t>(std::lround(255.0 * srgb_oetf(v)));
  }
  return out;
}

std::vector<std::uint8_t> tonemap_srgb(const Image& image, double ev) {
  const size_t count = static_cast<size_t>(image.width) * static_cast<size_t>(image.height);
  std::vector<std::uint8_t> out(3 * count);
  for (size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d L(image.rgb[3 * k], image.rgb[3 * k + 1], image.rgb[3 * k + 2]);
    const auto px = to_srgb8(L, ev);
    std::copy(px.begin(), px.end(), out.begin() + static_cast<std::ptrdiff_t>(3 * k));
  }
  return out;
}

void write_png_preview(const std::string& path, const Image& image, double ev) {
  write_png(path, image.width, image.height, tonemap_srgb(image, ev));
}

}  // namespace lambert
