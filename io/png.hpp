#pragma once
// PNG output (8-bit RGB), zlib-compressed, written atomically.

#include <cstdint>
#include <string>
#include <vector>

namespace lambert {

/// Writes an 8-bit sRGB image, rows top to bottom, 3 bytes per pixel. Throws IoError.
void write_png(const std::string& path, int width, int height,
               const std::vector<std::uint8_t>& rgb);

}  // namespace lambert
