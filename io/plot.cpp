#include "io/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <tuple>
#include <utility>

#include "core/atomic_file.hpp"

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

// Legend position: top-right of the plot area.
int legend_x(const Frame& f) { return f.ox + kPanelW - kRight - 150; }
int legend_y(int k) { return kTop + 8 + k * kLegendRow; }

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

}  // namespace lambert
