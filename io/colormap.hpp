#pragma once
// A colour map for scalar fields (temperature, heat flux) and the PNG of a colour-mapped
// rendering with a legend bar, drawn with the built-in bitmap font.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>

#include "geometry/render/render.hpp"

namespace lambert {

/// Colour of t in [0, 1] (clamped; NaN is grey) as 8-bit sRGB: viridis' hue path (dark
/// blue-violet, teal, green, yellow), linearly interpolated between 9 of its stops.
std::array<std::uint8_t, 3> colormap_srgb8(double t);

/// The linear value whose sRGB encoding is the byte colour c (inverse OETF): rendered as
/// radiance at EV 0, it comes back as c.
Eigen::Vector3d srgb8_to_linear(const std::array<std::uint8_t, 3>& c);

/// Writes `image` (colours already mapped, tone-mapped at EV 0, background black) with a
/// legend on its right: the colour bar from `lo` (bottom) to `hi` (top), 5 labelled ticks and
/// `title` (e.g. "T [K]") above it. Atomic; throws IoError.
void write_png_with_legend(const std::string& path, const Image& image, double lo, double hi,
                           const std::string& title);

}  // namespace lambert
