#include "io/png.hpp"

#include <zlib.h>

#include <fstream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

void put_u32(std::string& s, std::uint32_t v) {
  for (int k = 3; k >= 0; --k) s.push_back(static_cast<char>((v >> (8 * k)) & 0xFF));
}

void chunk(std::ostream& out, const char* type, const std::string& data) {
  std::string c;
  put_u32(c, static_cast<std::uint32_t>(data.size()));
  c.append(type, 4);
  c += data;
  const auto crc = crc32(0L, reinterpret_cast<const Bytef*>(c.data() + 4),
                         static_cast<uInt>(c.size() - 4));
  put_u32(c, static_cast<std::uint32_t>(crc));
  out.write(c.data(), static_cast<std::streamsize>(c.size()));
}

}  // namespace

void write_png(const std::string& path, int width, int height,
               const std::vector<std::uint8_t>& rgb) {
  LAMBERT_CHECK(width > 0 && height > 0 &&
                    rgb.size() == static_cast<size_t>(width) * height * 3,
                "png: pixel buffer size does not match the image size");
  // Each row is prefixed with filter type 0 (none).
  std::string raw;
  raw.reserve(static_cast<size_t>(height) * (1 + 3 * width));
  for (int y = 0; y < height; ++y) {
    raw.push_back('\0');
    raw.append(reinterpret_cast<const char*>(rgb.data()) + static_cast<size_t>(y) * 3 * width,
               static_cast<size_t>(3 * width));
  }
  uLongf bound = compressBound(static_cast<uLong>(raw.size()));
  std::string z(bound, '\0');
  if (compress2(reinterpret_cast<Bytef*>(z.data()), &bound,
                reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()),
                6) != Z_OK)
    throw IoError(path + ": PNG compression failed");
  z.resize(bound);
  std::string ihdr;
  put_u32(ihdr, static_cast<std::uint32_t>(width));
  put_u32(ihdr, static_cast<std::uint32_t>(height));
  ihdr += std::string("\x08\x02\x00\x00\x00", 5);  // 8-bit, RGB, deflate, no filter, no interlace
  write_stream_atomically(
      path,
      [&](std::ostream& out) {
        out.write("\x89PNG\r\n\x1a\n", 8);
        chunk(out, "IHDR", ihdr);
        chunk(out, "IDAT", z);
        chunk(out, "IEND", "");
      },
      true);
}

}  // namespace lambert
