#include "io/colormap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "io/bitmap_font.hpp"
#include "io/png.hpp"
#include "io/tonemap.hpp"

namespace lambert {
namespace {

// viridis at t = 0, 1/8, ..., 1 (matplotlib's table, sRGB bytes).
constexpr std::array<std::array<std::uint8_t, 3>, 9> kStops = {{{68, 1, 84},
                                                                {71, 44, 122},
                                                                {59, 81, 139},
                                                                {44, 113, 142},
                                                                {33, 144, 141},
                                                                {39, 173, 129},
                                                                {92, 200, 99},
                                                                {170, 220, 50},
                                                                {253, 231, 37}}};

std::string label(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

}  // namespace

std::array<std::uint8_t, 3> colormap_srgb8(double t) {
  if (std::isnan(t)) return {128, 128, 128};
  t = std::clamp(t, 0.0, 1.0) * (kStops.size() - 1);
  const size_t k = std::min(static_cast<size_t>(t), kStops.size() - 2);
  const double f = t - static_cast<double>(k);
  std::array<std::uint8_t, 3> c{};
  for (int i = 0; i < 3; ++i)
    c[i] = static_cast<std::uint8_t>(std::lround((1.0 - f) * kStops[k][i] + f * kStops[k + 1][i]));
  return c;
}

Eigen::Vector3d srgb8_to_linear(const std::array<std::uint8_t, 3>& c) {
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i) {
    const double v = c[i] / 255.0;
    out[i] = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
  }
  return out;
}

void write_png_with_legend(const std::string& path, const Image& image, double lo, double hi,
                           const std::string& title) {
  const int scale = image.height >= 400 ? 2 : 1;
  const int bar_w = 16 * scale, margin = 10 * scale, ticks = 5;
  std::vector<std::string> labels;
  int label_w = text_width(title, scale);
  for (int k = 0; k < ticks; ++k) {
    labels.push_back(label(lo + (hi - lo) * k / (ticks - 1)));
    label_w = std::max(label_w, text_width(labels.back(), scale) + bar_w + 6 * scale);
  }
  const int legend_w = label_w + 2 * margin;
  RgbImage out(image.width + legend_w, image.height);
  const auto pixels = tonemap_srgb(image, 0.0);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const size_t k = 3 * (static_cast<size_t>(y) * image.width + x);
      out.set(x, y, {pixels[k], pixels[k + 1], pixels[k + 2]});
    }
  const int x0 = image.width + margin;
  const int top = margin + (kGlyphHeight + 4) * scale, bottom = image.height - margin;
  draw_text(out, x0, margin, title, {0, 0, 0}, scale);
  for (int y = top; y <= bottom; ++y) {
    const double t = bottom > top ? static_cast<double>(bottom - y) / (bottom - top) : 0.0;
    for (int x = x0; x < x0 + bar_w; ++x) out.set(x, y, colormap_srgb8(t));
  }
  for (int k = 0; k < ticks; ++k) {
    const int y = bottom - (bottom - top) * k / (ticks - 1);
    for (int x = x0 + bar_w; x < x0 + bar_w + 3 * scale; ++x) out.set(x, y, {0, 0, 0});
    draw_text(out, x0 + bar_w + 6 * scale, y - kGlyphCapHeight * scale / 2, labels[k], {0, 0, 0},
              scale);
  }
  write_png(path, out.width, out.height, out.rgb);
}

}  // namespace lambert
