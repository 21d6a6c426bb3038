#include "io/plot.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include "common/temp_dir.hpp"
#include "io/bitmap_font.hpp"

namespace lambert {
namespace {

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

Plot residual_plot(const std::string& title, const std::string& name) {
  Plot p;
  p.title = title;
  p.x_label = "iteration";
  p.y_label = "||E - K B|| / ||E||";
  p.series.push_back({name, {0, 1, 2, 3}, {1.0, 1e-2, 1e-5, 1e-9}});
  p.series.push_back({"direct", {0, 1}, {1.0, 1e-16}});
  return p;
}

// Pixels of the image that are not white.
int inked(const RgbImage& img) {
  int n = 0;
  for (size_t i = 0; i < img.rgb.size(); i += 3)
    n += img.rgb[i] != 255 || img.rgb[i + 1] != 255 || img.rgb[i + 2] != 255;
  return n;
}

constexpr std::array<std::uint8_t, 3> kInk{0, 0, 0};

// The SVG is the CLI's one plot format (PNGs come from `python3 -m lambert.plot`): panels
// side by side, 560 px each, every title and legend name in the text.
TEST(PlotSvg, PanelsTitlesAndLegendNames) {
  testing::TempDir dir;
  const std::string path = dir.file("plot.svg");
  write_plots_svg(path, {residual_plot("residual", "jacobi"), residual_plot("by time", "gmres")});
  const std::string svg = read_all(path);
  EXPECT_NE(svg.find("width=\"1120\" height=\"420\""), std::string::npos);
  for (const char* text : {"residual", "by time", "jacobi", "gmres", "direct"})
    EXPECT_NE(svg.find(text), std::string::npos) << text;
  EXPECT_EQ(svg,
            plots_svg({residual_plot("residual", "jacobi"), residual_plot("by time", "gmres")}));
}

// The bitmap font stays for image legends (the thermal colour bar); its own tests follow.
TEST(BitmapFont, LetterAInksPixelsSpaceInksNone) {
  RgbImage a(16, 16), space(16, 16);
  draw_text(a, 2, 2, "A", kInk, 1);
  draw_text(space, 2, 2, " ", kInk, 1);
  EXPECT_GT(inked(a), 0);
  EXPECT_EQ(inked(space), 0);
}

TEST(BitmapFont, EveryPrintableGlyphExceptSpaceHasInk) {
  for (int c = 33; c <= 126; ++c) {
    const auto rows = glyph_rows(static_cast<char>(c));
    EXPECT_TRUE(std::any_of(rows.begin(), rows.end(), [](std::uint8_t r) { return r != 0; }))
        << "glyph '" << static_cast<char>(c) << "' is blank";
  }
}

// Two characters drawn alike cannot be told apart: every printable glyph is unique.
TEST(BitmapFont, PrintableGlyphsAreDistinct) {
  std::set<std::array<std::uint8_t, kGlyphHeight>> seen;
  for (int c = 32; c <= 126; ++c)
    EXPECT_TRUE(seen.insert(glyph_rows(static_cast<char>(c))).second)
        << "glyph '" << static_cast<char>(c) << "' duplicates an earlier one";
}

TEST(BitmapFont, TextStaysInItsBoxAndScalesByBlocks) {
  const std::string text = "1e-8 gauss-seidel |E|";
  const int w = text_width(text, 1);
  EXPECT_EQ(w, static_cast<int>(text.size()) * kGlyphAdvance - 1);
  RgbImage one(w, kGlyphHeight), two(2 * w, 2 * kGlyphHeight), big(2 * w + 8, 40);
  draw_text(one, 0, 0, text, kInk, 1);
  draw_text(two, 0, 0, text, kInk, 2);
  draw_text(big, 4, 4, text, kInk, 2);
  // Each font pixel becomes a 2 x 2 block, and nothing falls outside the text's box: the
  // exactly-sized image holds every pixel the larger one receives.
  EXPECT_GT(inked(one), 0);
  EXPECT_EQ(inked(two), 4 * inked(one));
  EXPECT_EQ(inked(big), inked(two));
}

}  // namespace
}  // namespace lambert
