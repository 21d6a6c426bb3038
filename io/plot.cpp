#include "io/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string_view>
#include <tuple>
#include <utility>

#include "core/atomic_file.hpp"
#include "io/bitmap_font.hpp"
#include "io/png.hpp"

namespace lambert {
namespace {

constexpr int kPanelW = 560, kPanelH = 420;
constexpr int kLeft = 72, kRight = 16, kTop = 36, kBottom = 52;  // plot-area margins
constexpr int kLegendRow = 16;                                   // px per legend entry

struct Frame {  // data -> pixel mapping of one panel; ranges in axis space (log10 if log)
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  bool log_x = false, log_y = true;
  int ox = 0;  // panel x offset in the image
  bool valid(double x, double y) const {
    return std::isfinite(x) && std::isfinite(y) && (!log_x || x > 0.0) && (!log_y || y > 0.0);
  }
  double left() const { return ox + kLeft; }              // plot-area edges, pixels
  double right() const { return ox + kPanelW - kRight; }
  double px(double x) const {
    const double v = log_x ? std::log10(x) : x;
    return ox + kLeft + (v - x0) / (x1 - x0) * (kPanelW - kLeft - kRight);
  }
  double py(double y) const {
    const double v = log_y ? std::log10(y) : y;
    return kTop + (y1 - v) / (y1 - y0) * (kPanelH - kTop - kBottom);
  }
};

// A "nice" step (1, 2 or 5 times a power of ten) giving about `count` ticks over `span`.
double nice_step(double span, int count) {
  const double raw = span / count;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (raw <= m * p) return m * p;
  return 10.0 * p;
}

// Axis range [lo, hi] (axis space) covering [vmin, vmax]: whole decades on a log axis;
// nice-step multiples on a linear one, from 0 when `from_zero` (iterations, seconds).
std::pair<double, double> axis_range(double vmin, double vmax, bool log, bool from_zero) {
  if (log) return {std::floor(vmin), std::max(std::ceil(vmax), std::floor(vmin) + 1.0)};
  const double lo0 = from_zero ? std::min(0.0, vmin) : vmin;
  const double step = nice_step(std::max(vmax - lo0, 1e-300), 6);
  const double lo = std::floor(lo0 / step) * step, hi = std::ceil(vmax / step) * step;
  return {lo, hi > lo ? hi : lo + 1.0};
}

Frame make_frame(const Plot& plot, int ox) {
  Frame f;
  f.log_x = plot.log_x;
  f.log_y = plot.log_y;
  f.ox = ox;
  double xmin = std::numeric_limits<double>::infinity(), xmax = -xmin;
  double ymin = xmin, ymax = -xmin;
  for (const auto& s : plot.series)
    for (size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      if (!f.valid(s.x[k], s.y[k])) continue;
      const double u = f.log_x ? std::log10(s.x[k]) : s.x[k];
      const double v = f.log_y ? std::log10(s.y[k]) : s.y[k];
      xmin = std::min(xmin, u);
      xmax = std::max(xmax, u);
      ymin = std::min(ymin, v);
      ymax = std::max(ymax, v);
    }
  if (!std::isfinite(xmin)) xmin = 0, xmax = 1, ymin = 0, ymax = 1;
  std::tie(f.x0, f.x1) = axis_range(xmin, xmax, f.log_x, true);
  std::tie(f.y0, f.y1) = axis_range(ymin, ymax, f.log_y, false);
  return f;
}

// Tick values (data space) over [lo, hi] (axis space): at most ~10 decades on a log axis,
// about 6 nice steps on a linear one.
std::vector<double> ticks(double lo, double hi, bool log) {
  std::vector<double> t;
  if (log) {
    const int every = std::max(1, static_cast<int>(hi - lo + 9) / 10);
    for (double e = lo; e <= hi + 1e-9; e += every) t.push_back(std::pow(10.0, e));
  } else {
    const double step = nice_step(hi - lo, 6);
    for (double v = lo; v <= hi + 1e-9 * step; v += step) t.push_back(v);
  }
  return t;
}

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '&')
      o += "&amp;";
    else if (c == '"')
      o += "&quot;";
    else
      o += c;
  }
  return o;
}

std::string hex(std::size_t k) {
  const auto c = plot_color(k);
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}

std::string tick_label(double v, bool log) {
  char buf[32];
  if (log)
    std::snprintf(buf, sizeof buf, "1e%d", static_cast<int>(std::lround(std::log10(v))));
  else
    std::snprintf(buf, sizeof buf, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

// SVG legend position: top-right of the plot area (the PNG picks the emptiest corner).
int legend_x(const Frame& f) { return f.ox + kPanelW - kRight - 150; }
int legend_y(int k) { return kTop + 8 + k * kLegendRow; }

constexpr std::array<std::uint8_t, 3> kBlack{0, 0, 0}, kGrid{224, 224, 224},
    kLegendEdge{176, 176, 176}, kWhite{255, 255, 255};

// RGB raster with thick anti-alias-free lines.
struct Raster : RgbImage {
  using RgbImage::RgbImage;
  void dot(int x, int y, std::array<std::uint8_t, 3> c, int r) {
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) set(x + dx, y + dy, c);
  }
  void line(double x0, double y0, double x1, double y1, std::array<std::uint8_t, 3> c, int r) {
    const int n = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
    for (int k = 0; k <= n; ++k) {
      const double t = static_cast<double>(k) / n;
      dot(static_cast<int>(std::lround(x0 + t * (x1 - x0))),
          static_cast<int>(std::lround(y0 + t * (y1 - y0))), c, r);
    }
  }
  void outline(double x0, double y0, double x1, double y1, std::array<std::uint8_t, 3> c) {
    line(x0, y0, x1, y0, c, 0);
    line(x0, y1, x1, y1, c, 0);
    line(x0, y0, x0, y1, c, 0);
    line(x1, y0, x1, y1, c, 0);
  }
  void fill(int x0, int y0, int x1, int y1, std::array<std::uint8_t, 3> c) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) set(x, y, c);
  }
  // Pixels in [x0, x1] x [y0, y1] that are neither background nor grid: what a box there hides.
  long ink(int x0, int y0, int x1, int y1) const {
    long n = 0;
    for (int y = std::max(y0, 0); y <= std::min(y1, height - 1); ++y)
      for (int x = std::max(x0, 0); x <= std::min(x1, width - 1); ++x) {
        const std::uint8_t* p = &rgb[3 * (static_cast<size_t>(y) * width + x)];
        const std::array<std::uint8_t, 3> c{p[0], p[1], p[2]};
        n += c != kWhite && c != kGrid;
      }
    return n;
  }
};

enum class Anchor { kStart, kMiddle, kEnd };  // as SVG's text-anchor

// Draws text in the bitmap font with the middle of its capitals on row y and its left edge,
// centre or right edge (per anchor) on column x.
void put_text(Raster& img, double x, double y, std::string_view text, Anchor anchor) {
  const int w = text_width(text, 1);
  const int left = static_cast<int>(std::lround(anchor == Anchor::kStart    ? x
                                                : anchor == Anchor::kMiddle ? x - w / 2.0
                                                                            : x - w));
  const int top = static_cast<int>(std::lround(y)) - kGlyphCapHeight / 2;
  draw_text(img, left, top, text, kBlack, 1);
}

// Draws text in a bold cut of the bitmap font (each glyph twice, one pixel apart, and one
// more blank column between glyphs), centred on column x with its capitals' middle on row y.
void put_bold_text(Raster& img, double x, double y, std::string_view text) {
  constexpr int kAdvance = kGlyphAdvance + 1;
  const int w = static_cast<int>(text.size()) * kAdvance - 1;
  const int left = static_cast<int>(std::lround(x - w / 2.0));
  const int top = static_cast<int>(std::lround(y)) - kGlyphCapHeight / 2;
  for (size_t k = 0; k < text.size(); ++k)
    for (int dx : {0, 1})
      draw_text(img, left + static_cast<int>(k) * kAdvance + dx, top, text.substr(k, 1), kBlack, 1);
}

// Pixel bounds of a panel's plot area, and the panel's x offset in the image.
struct Area {
  double l, r, t, b;
  int ox;
};

// The panel's title (bold, above the plot area), x-axis title (below the tick labels) and
// y-axis title (turned, along the panel's left edge): where the SVG puts them.
void draw_titles(Raster& img, const Plot& plot, const Area& a) {
  put_bold_text(img, (a.l + a.r) / 2, 18, plot.title);
  put_text(img, (a.l + a.r) / 2, a.b + 34, plot.x_label, Anchor::kMiddle);
  const int y = static_cast<int>(std::lround((a.t + a.b) / 2 + text_width(plot.y_label, 1) / 2.0));
  draw_text_up(img, a.ox + 16 - kGlyphCapHeight / 2, y, plot.y_label, kBlack, 1);
}

// The legend: a white box holding, per series, a swatch of its colour and its name. Drawn
// after the curves, in the corner of the plot area where it hides the fewest curve pixels
// (top-right, the SVG's place, on a tie).
void draw_legend(Raster& img, const Plot& plot, const Area& a) {
  if (plot.series.empty()) return;
  constexpr int kPad = 6, kSwatch = 24;
  int text_w = 0;
  for (const auto& s : plot.series) text_w = std::max(text_w, text_width(s.name, 1));
  const int w = 3 * kPad + kSwatch + text_w;
  // Rows kLegendRow apart, the first and last 10 px from the box's edges.
  const int h = static_cast<int>(plot.series.size()) * kLegendRow + 4;
  const int left = static_cast<int>(a.l) + kPad, right = static_cast<int>(a.r) - kPad - w;
  const int top = static_cast<int>(a.t) + kPad, bottom = static_cast<int>(a.b) - kPad - h;
  int x0 = right, y0 = top;
  long hidden = img.ink(x0, y0, x0 + w, y0 + h);
  for (auto [x, y] : {std::pair{left, top}, {right, bottom}, {left, bottom}}) {
    const long n = img.ink(x, y, x + w, y + h);
    if (n < hidden) x0 = x, y0 = y, hidden = n;
  }
  img.fill(x0, y0, x0 + w, y0 + h, kWhite);
  img.outline(x0, y0, x0 + w, y0 + h, kLegendEdge);
  for (size_t k = 0; k < plot.series.size(); ++k) {
    const int y = y0 + 10 + static_cast<int>(k) * kLegendRow;
    img.line(x0 + kPad + 2, y, x0 + kPad + kSwatch - 2, y, plot_color(k), 2);  // 5 px thick
    put_text(img, x0 + 2 * kPad + kSwatch, y, plot.series[k].name, Anchor::kStart);
  }
}

// Calls seg(x0, y0, x1, y1) for every drawable segment of a series (pixel coordinates).
template <typename Seg>
void for_segments(const Frame& f, const PlotSeries& s, Seg seg) {
  bool have = false;
  double px = 0, py = 0;
  for (size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
    if (!f.valid(s.x[k], s.y[k])) continue;
    const double x = f.px(s.x[k]), y = f.py(s.y[k]);
    if (have)
      seg(px, py, x, y);
    else
      seg(x, y, x, y);
    px = x, py = y, have = true;
  }
}

}  // namespace

std::array<std::uint8_t, 3> plot_color(std::size_t k) {
  // Tableau 10: distinguishable, colour-blind friendly enough for 8 solvers.
  static const std::array<std::uint8_t, 3> kPalette[] = {
      {31, 119, 180}, {255, 127, 14},  {44, 160, 44},   {214, 39, 40},  {148, 103, 189},
      {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
  return kPalette[k % (sizeof kPalette / sizeof kPalette[0])];
}

std::string plots_svg(const std::vector<Plot>& panels) {
  std::ostringstream o;
  const int width = kPanelW * static_cast<int>(std::max<size_t>(1, panels.size()));
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << kPanelH
    << "\" viewBox=\"0 0 " << width << ' ' << kPanelH
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (size_t p = 0; p < panels.size(); ++p) {
    const Plot& plot = panels[p];
    const Frame f = make_frame(plot, static_cast<int>(p) * kPanelW);
    const double l = f.left(), r = f.right(), t = kTop, b = kPanelH - kBottom;
    for (double v : ticks(f.y0, f.y1, f.log_y)) {
      const double y = f.py(v);
      o << "<line x1=\"" << l << "\" y1=\"" << y << "\" x2=\"" << r << "\" y2=\"" << y
        << "\" stroke=\"#e0e0e0\"/>\n<text x=\"" << l - 6 << "\" y=\"" << y + 4
        << "\" text-anchor=\"end\">" << tick_label(v, f.log_y) << "</text>\n";
    }
    for (double v : ticks(f.x0, f.x1, f.log_x)) {
      const double x = f.px(v);
      o << "<line x1=\"" << x << "\" y1=\"" << t << "\" x2=\"" << x << "\" y2=\"" << b
        << "\" stroke=\"#e0e0e0\"/>\n<text x=\"" << x << "\" y=\"" << b + 16
        << "\" text-anchor=\"middle\">" << tick_label(v, f.log_x) << "</text>\n";
    }
    o << "<rect x=\"" << l << "\" y=\"" << t << "\" width=\"" << r - l << "\" height=\"" << b - t
      << "\" fill=\"none\" stroke=\"black\"/>\n"
      << "<text x=\"" << (l + r) / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">"
      << escape(plot.title) << "</text>\n<text x=\"" << (l + r) / 2 << "\" y=\"" << b + 38
      << "\" text-anchor=\"middle\">" << escape(plot.x_label) << "</text>\n"
      << "<text transform=\"translate(" << f.ox + 16 << ',' << (t + b) / 2
      << ") rotate(-90)\" text-anchor=\"middle\">" << escape(plot.y_label) << "</text>\n";
    for (size_t k = 0; k < plot.series.size(); ++k) {
      o << "<polyline fill=\"none\" stroke-width=\"2\" stroke=\"" << hex(k) << "\" points=\"";
      std::ostringstream marks;
      for_segments(f, plot.series[k], [&](double, double, double x1, double y1) {
        o << x1 << ',' << y1 << ' ';
        if (plot.markers)
          marks << "<circle cx=\"" << x1 << "\" cy=\"" << y1 << "\" r=\"3.5\" fill=\"" << hex(k)
                << "\"/>\n";
      });
      o << "\"/>\n" << marks.str();
      const int lx = legend_x(f), ly = legend_y(static_cast<int>(k));
      o << "<line x1=\"" << lx << "\" y1=\"" << ly << "\" x2=\"" << lx + 24 << "\" y2=\"" << ly
        << "\" stroke-width=\"4\" stroke=\"" << hex(k) << "\"/>\n<text x=\"" << lx + 30 << "\" y=\""
        << ly + 4 << "\">" << escape(plot.series[k].name) << " (" << hex(k) << ")</text>\n";
    }
  }
  o << "</svg>\n";
  return o.str();
}

void write_plots_svg(const std::string& path, const std::vector<Plot>& panels) {
  const std::string svg = plots_svg(panels);
  write_stream_atomically(path, [&](std::ostream& out) { out << svg; });
}

void write_plots_png(const std::string& path, const std::vector<Plot>& panels) {
  Raster img(kPanelW * static_cast<int>(std::max<size_t>(1, panels.size())), kPanelH);
  for (size_t p = 0; p < panels.size(); ++p) {
    const Plot& plot = panels[p];
    const Frame f = make_frame(plot, static_cast<int>(p) * kPanelW);
    const Area a{f.left(), f.right(), kTop, kPanelH - kBottom, f.ox};
    for (double v : ticks(f.y0, f.y1, f.log_y)) {
      img.line(a.l, f.py(v), a.r, f.py(v), kGrid, 0);
      img.line(a.l - 5, f.py(v), a.l, f.py(v), kBlack, 0);
      put_text(img, a.l - 8, f.py(v), tick_label(v, f.log_y), Anchor::kEnd);
    }
    for (double v : ticks(f.x0, f.x1, f.log_x)) {
      img.line(f.px(v), a.t, f.px(v), a.b, kGrid, 0);
      img.line(f.px(v), a.b, f.px(v), a.b + 5, kBlack, 0);
      put_text(img, f.px(v), a.b + 13, tick_label(v, f.log_x), Anchor::kMiddle);
    }
    img.outline(a.l, a.t, a.r, a.b, kBlack);
    for (size_t k = 0; k < plot.series.size(); ++k) {
      const auto c = plot_color(k);
      for_segments(f, plot.series[k], [&](double x0, double y0, double x1, double y1) {
        img.line(x0, y0, x1, y1, c, 1);
        if (plot.markers)
          img.dot(static_cast<int>(std::lround(x1)), static_cast<int>(std::lround(y1)), c, 3);
      });
    }
    draw_legend(img, plot, a);
    draw_titles(img, plot, a);
  }
  write_png(path, img.width, img.height, img.rgb);
}

}  // namespace lambert
