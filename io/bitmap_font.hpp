#pragma once
// A small built-in bitmap font for the plot rasteriser (io/plot.cpp), so the PNG plots carry
// the same text as the SVG ones without a font file or a font library. Private to io/.
//
// Glyphs cover printable ASCII 32..126 on a 5 x 9 grid: rows 0..6 hold capitals and digits
// (cap height 7), lowercase letters sit on rows 2..6 (x-height 5), rows 7..8 are descenders.
// Characters advance by 6 px (one blank column) and are drawn at an integer scale.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

namespace lambert {

/// Glyph cell of the bitmap font, in unscaled pixels.
inline constexpr int kGlyphWidth = 5, kGlyphHeight = 9, kGlyphCapHeight = 7;
/// Horizontal advance per character (glyph width plus one blank column), unscaled.
inline constexpr int kGlyphAdvance = kGlyphWidth + 1;

namespace font_detail {

// The glyph sheet: 12 glyphs per sheet row, in ASCII order from ' ' (32) to '~' (126), each
// kGlyphWidth columns wide and separated by a space; '#' is ink, '.' is paper.
constexpr int kSheetColumns = 12;
constexpr int kFirst = 32, kLast = 126;
constexpr std::string_view kSheet[] = {
    //       !     "     #     $     %     &     '     (     )     *     +
    "..... ..#.. .#.#. .#.#. ..#.. ##... .##.. ..#.. ...#. .#... ..... .....",
    "..... ..#.. .#.#. .#.#. .#### ##..# #..#. ..#.. ..#.. ..#.. ..#.. ..#..",
    "..... ..#.. .#.#. ##### #.#.. ...#. #.#.. .#... .#... ...#. #.#.# ..#..",
    "..... ..#.. ..... .#.#. .###. ..#.. .#... ..... .#... ...#. .###. #####",
    "..... ..#.. ..... ##### ..#.# .#... #.#.# ..... .#... ...#. #.#.# ..#..",
    "..... ..... ..... .#.#. ####. #..## #..#. ..... ..#.. ..#.. ..#.. ..#..",
    "..... ..#.. ..... .#.#. ..#.. ...## .##.# ..... ...#. .#... ..... .....",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // ,     -     .     /     0     1     2     3     4     5     6     7
    "..... ..... ..... ....# .###. ..#.. .###. ##### ...#. ##### ..##. #####",
    "..... ..... ..... ....# #...# .##.. #...# ...#. ..##. #.... .#... ....#",
    "..... ..... ..... ...#. #..## ..#.. ....# ..#.. .#.#. ####. #.... ...#.",
    "..... .###. ..... ..#.. #.#.# ..#.. ...#. ...#. #..#. ....# ####. ..#..",
    "..... ..... ..... .#... ##..# ..#.. ..#.. ....# ##### ....# #...# .#...",
    ".##.. ..... .##.. #.... #...# ..#.. .#... #...# ...#. #...# #...# .#...",
    ".##.. ..... .##.. #.... .###. .###. ##### .###. ...#. .###. .###. .#...",
    "..#.. ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    ".#... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // 8     9     :     ;     <     =     >     ?     @     A     B     C
    ".###. .###. ..... ..... ...#. ..... .#... .###. .###. .###. ####. .###.",
    "#...# #...# .##.. .##.. ..#.. ..... ..#.. #...# #...# #...# #...# #...#",
    "#...# #...# .##.. .##.. .#... ##### ...#. ....# #.### #...# #...# #....",
    ".###. .#### ..... ..... #.... ..... ....# ...#. #.#.# ##### ####. #....",
    "#...# ....# .##.. .##.. .#... ##### ...#. ..#.. #.### #...# #...# #....",
    "#...# ...#. .##.. .##.. ..#.. ..... ..#.. ..... #.... #...# #...# #...#",
    ".###. .##.. ..... ..#.. ...#. ..... .#... ..#.. .###. #...# ####. .###.",
    "..... ..... ..... .#... ..... ..... ..... ..... ..... ..... ..... .....",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // D     E     F     G     H     I     J     K     L     M     N     O
    "###.. ##### ##### .###. #...# .###. ..### #...# #.... #...# #...# .###.",
    "#..#. #.... #.... #...# #...# ..#.. ...#. #..#. #.... ##.## #...# #...#",
    "#...# #.... #.... #.... #...# ..#.. ...#. #.#.. #.... #.#.# ##..# #...#",
    "#...# ####. ####. #.### ##### ..#.. ...#. ##... #.... #.#.# #.#.# #...#",
    "#...# #.... #.... #...# #...# ..#.. ...#. #.#.. #.... #...# #..## #...#",
    "#..#. #.... #.... #...# #...# ..#.. #..#. #..#. #.... #...# #...# #...#",
    "###.. ##### #.... .#### #...# .###. .##.. #...# ##### #...# #...# .###.",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // P     Q     R     S     T     U     V     W     X     Y     Z     [
    "####. .###. ####. .#### ##### #...# #...# #...# #...# #...# ##### .###.",
    "#...# #...# #...# #.... ..#.. #...# #...# #...# #...# #...# ....# .#...",
    "#...# #...# #...# #.... ..#.. #...# #...# #...# .#.#. .#.#. ...#. .#...",
    "####. #...# ####. .###. ..#.. #...# #...# #.#.# ..#.. ..#.. ..#.. .#...",
    "#.... #.#.# #.#.. ....# ..#.. #...# #...# #.#.# .#.#. ..#.. .#... .#...",
    "#.... #..#. #..#. ....# ..#.. #...# .#.#. #.#.# #...# ..#.. #.... .#...",
    "#.... .##.# #...# ####. ..#.. .###. ..#.. .#.#. #...# ..#.. ##### .###.",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // \     ]     ^     _     `     a     b     c     d     e     f     g
    "#.... .###. ..#.. ..... .#... ..... #.... ..... ....# ..... ..##. .....",
    "#.... ...#. .#.#. ..... ..#.. ..... #.... ..... ....# ..... .#..# .....",
    ".#... ...#. #...# ..... ...#. .###. ####. .###. .#### .###. .#... .####",
    "..#.. ...#. ..... ..... ..... ....# #...# #.... #...# #...# ###.. #...#",
    "...#. ...#. ..... ..... ..... .#### #...# #.... #...# ##### .#... #...#",
    "....# ...#. ..... ..... ..... #...# #...# #...# #...# #.... .#... #...#",
    "....# .###. ..... ..... ..... .#### ####. .###. .#### .###. .#... .####",
    "..... ..... ..... ##### ..... ..... ..... ..... ..... ..... ..... ....#",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .###.",
    // h     i     j     k     l     m     n     o     p     q     r     s
    "#.... ..#.. ...#. #.... .##.. ..... ..... ..... ..... ..... ..... .....",
    "#.... ..... ..... #.... ..#.. ..... ..... ..... ..... ..... ..... .....",
    "####. .##.. ..##. #..#. ..#.. ##.#. ####. .###. ####. .#### #.##. .####",
    "#...# ..#.. ...#. #.#.. ..#.. #.#.# #...# #...# #...# #...# ##..# #....",
    "#...# ..#.. ...#. ##... ..#.. #.#.# #...# #...# #...# #...# #.... .###.",
    "#...# ..#.. ...#. #.#.. ..#.. #.#.# #...# #...# #...# #...# #.... ....#",
    "#...# .###. ...#. #..#. .###. #.#.# #...# .###. ####. .#### #.... ####.",
    "..... ..... #..#. ..... ..... ..... ..... ..... #.... ....# ..... .....",
    "..... ..... .##.. ..... ..... ..... ..... ..... #.... ....# ..... .....",
    // t     u     v     w     x     y     z     {     |     }     ~
    ".#... ..... ..... ..... ..... ..... ..... ...## ..#.. ##... ..... .....",
    ".#... ..... ..... ..... ..... ..... ..... ..#.. ..#.. ..#.. ..... .....",
    "###.. #...# #...# #...# #...# #...# ##### ..#.. ..#.. ..#.. .#... .....",
    ".#... #...# #...# #...# .#.#. #...# ...#. .#... ..#.. ...#. #.#.# .....",
    ".#... #...# #...# #.#.# ..#.. #...# ..#.. ..#.. ..#.. ..#.. ...#. .....",
    ".#..# #..## .#.#. #.#.# .#.#. #...# .#... ..#.. ..#.. ..#.. ..... .....",
    "..##. .##.# ..#.. .#.#. #...# .#### ##### ...## ..#.. ##... ..... .....",
    "..... ..... ..... ..... ..... ....# ..... ..... ..#.. ..... ..... .....",
    "..... ..... ..... ..... ..... .###. ..... ..... ..#.. ..... ..... .....",
};

using GlyphRows = std::array<std::uint8_t, kGlyphHeight>;  // bit 4 = leftmost column

constexpr std::array<GlyphRows, kLast - kFirst + 1> parse_sheet() {
  std::array<GlyphRows, kLast - kFirst + 1> table{};
  for (int c = 0; c <= kLast - kFirst; ++c)
    for (int r = 0; r < kGlyphHeight; ++r) {
      const std::string_view line = kSheet[(c / kSheetColumns) * kGlyphHeight + r];
      for (int x = 0; x < kGlyphWidth; ++x)
        if (line[(c % kSheetColumns) * kGlyphAdvance + x] == '#')
          table[c][r] |= static_cast<std::uint8_t>(1u << (kGlyphWidth - 1 - x));
    }
  return table;
}

constexpr bool sheet_is_well_formed() {
  constexpr int rows = (kLast - kFirst + kSheetColumns) / kSheetColumns * kGlyphHeight;
  if (sizeof kSheet / sizeof kSheet[0] != rows) return false;
  for (std::string_view line : kSheet) {
    if (line.size() != kSheetColumns * kGlyphAdvance - 1) return false;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const bool gap = i % kGlyphAdvance == kGlyphWidth;
      if (gap ? line[i] != ' ' : line[i] != '#' && line[i] != '.') return false;
    }
  }
  return true;
}
static_assert(sheet_is_well_formed(), "glyph sheet: 8 rows of 12 glyphs, 5 x 9 each");

inline constexpr auto kGlyphs = parse_sheet();

}  // namespace font_detail

/// Rows of the glyph of c, top to bottom, bit (kGlyphWidth-1-x) set where column x is ink.
/// Characters outside printable ASCII are drawn as '?'.
constexpr std::array<std::uint8_t, kGlyphHeight> glyph_rows(char c) {
  const int i = static_cast<unsigned char>(c);
  const bool printable = i >= font_detail::kFirst && i <= font_detail::kLast;
  return font_detail::kGlyphs[(printable ? i : '?') - font_detail::kFirst];
}

/// Width in pixels of text drawn at `scale` (no trailing blank column); 0 for empty text.
constexpr int text_width(std::string_view text, int scale) {
  return text.empty() ? 0 : (static_cast<int>(text.size()) * kGlyphAdvance - 1) * scale;
}

/// An 8-bit sRGB raster, rows top to bottom, 3 bytes per pixel (the layout write_png takes).
struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;

  /// A white image.
  RgbImage(int w, int h) : width(w), height(h), rgb(3 * static_cast<std::size_t>(w) * h, 255) {}

  /// Sets pixel (x, y) to c; pixels outside the image are ignored.
  void set(int x, int y, std::array<std::uint8_t, 3> c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
    rgb[i] = c[0], rgb[i + 1] = c[1], rgb[i + 2] = c[2];
  }
};

namespace font_detail {

// Calls ink(u, v) for every pixel text covers when drawn at `scale`, (u, v) measured from the
// top-left corner of the first glyph cell, u to the right and v down.
template <typename Ink>
void for_each_ink(std::string_view text, int scale, Ink ink) {
  for (std::size_t k = 0; k < text.size(); ++k) {
    const auto rows = glyph_rows(text[k]);
    const int u0 = static_cast<int>(k) * kGlyphAdvance * scale;
    for (int r = 0; r < kGlyphHeight; ++r)
      for (int c = 0; c < kGlyphWidth; ++c)
        if ((rows[r] >> (kGlyphWidth - 1 - c)) & 1u)
          for (int dv = 0; dv < scale; ++dv)
            for (int du = 0; du < scale; ++du) ink(u0 + c * scale + du, r * scale + dv);
  }
}

}  // namespace font_detail

/// Draws text left to right with its first glyph cell's top-left corner at (x, y); each font
/// pixel becomes a scale x scale block. Pixels outside the image are clipped.
inline void draw_text(RgbImage& image, int x, int y, std::string_view text,
                      std::array<std::uint8_t, 3> colour, int scale) {
  font_detail::for_each_ink(text, scale, [&](int u, int v) { image.set(x + u, y + v, colour); });
}

/// Draws text turned 90 degrees counter-clockwise (reading bottom to top), as draw_text would
/// draw it and then rotated about (x, y): the cell tops lie on column x, the text runs up from
/// row y. Used for y-axis titles.
inline void draw_text_up(RgbImage& image, int x, int y, std::string_view text,
                         std::array<std::uint8_t, 3> colour, int scale) {
  font_detail::for_each_ink(text, scale, [&](int u, int v) { image.set(x + v, y - u, colour); });
}

}  // namespace lambert
