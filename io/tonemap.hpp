#pragma once
// Tone mapping of linear radiance to 8-bit sRGB for previews (PNG, PLY vertex colours).
//
// The mapping is a pure exposure followed by the sRGB opto-electronic transfer function:
//   v = 2^EV · L  (L linear radiance, W m^-2 sr^-1),  c = OETF(clamp(v, 0, 1)),  byte = round(255
//   c)
// with OETF(x) = 12.92 x for x <= 0.0031308, else 1.055 x^(1/2.4) − 0.055 (IEC 61966-2-1).
// No curve beyond the clip: colours stay proportional to radiance below white, so colour
// bleeding and shadow gradients read as they are; emitters (far brighter) clip to white.
// Automatic exposure (Reinhard et al. 2002, "key value"): EV = log2(kKey / L̄), L̄ the
// geometric mean of the Rec.709 luminance over the pixels that see a lit surface.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/render/render.hpp"

namespace lambert {

/// Key value of the automatic exposure: the log-average luminance maps to this linear value.
/// 0.18 is photographic middle grey; the Cornell box is a bright (white-walled) scene, for
/// which Reinhard recommends a higher key: 0.36 puts its white walls near sRGB 160/255
/// and leaves head room for the brightest (directly lit) regions.
constexpr double kKey = 0.36;

/// sRGB OETF (IEC 61966-2-1) of a linear value in [0, 1].
double srgb_oetf(double linear);

/// Automatic exposure (stops) of an image by the key-value rule; 0 for a black image.
/// `surfaces_only`: from the pixels that hit a surface (alpha > 0) alone, so that a sky
/// behind the scene does not set the exposure of the scene in front of it.
double auto_exposure(const Image& image, bool surfaces_only = false);

/// Linear RGB times 2^ev, clipped and sRGB-encoded to bytes.
std::array<std::uint8_t, 3> to_srgb8(const Eigen::Vector3d& linear, double ev);

/// The whole image as 8-bit sRGB (3 bytes per pixel, rows top to bottom).
std::vector<std::uint8_t> tonemap_srgb(const Image& image, double ev);

/// Writes the tone-mapped preview of `image` as a PNG, atomically. Throws IoError.
void write_png_preview(const std::string& path, const Image& image, double ev);

}  // namespace lambert
