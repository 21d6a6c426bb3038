#pragma once
// Line plots (e.g. solver convergence: residual vs iteration and vs time) written as SVG
// (axes, ticks, labels, legend) and as PNG (the same plot rasterised, its text drawn in a small
// built-in bitmap font).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace lambert {

/// One curve: points (x_k, y_k); points with y <= 0 or non-finite are skipped on a log axis.
struct PlotSeries {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;
};

/// One panel: axes with a title and labels, and its curves.
struct Plot {
  std::string title;
  std::string x_label;
  std::string y_label;
  bool log_y = true;  ///< base-10 logarithmic y axis
  std::vector<PlotSeries> series;
};

/// Colour (sRGB 8-bit) of series k; the same palette in SVG and PNG.
std::array<std::uint8_t, 3> plot_color(std::size_t k);

/// The panels side by side as an SVG document (each panel 560 x 420 px).
std::string plots_svg(const std::vector<Plot>& panels);

/// Writes plots_svg atomically. Throws IoError.
void write_plots_svg(const std::string& path, const std::vector<Plot>& panels);

/// Writes the panels side by side as an RGB PNG with the same layout and text as the SVG
/// (curves, axes, grid, tick labels, titles, a legend box naming each colour), atomically.
/// Throws IoError.
void write_plots_png(const std::string& path, const std::vector<Plot>& panels);

// Log-log scatter plots (e.g. error vs time of several estimators): both axes base-10
// logarithmic, a marker at every point, the points of a series joined in the order given.
// Plot::log_y is ignored; points with x <= 0, y <= 0 or non-finite are skipped.

/// The panels side by side as an SVG document, log-log (each panel 560 x 420 px).
std::string loglog_svg(const std::vector<Plot>& panels);

/// Writes loglog_svg atomically. Throws IoError.
void write_loglog_svg(const std::string& path, const std::vector<Plot>& panels);

/// Writes the log-log panels as an RGB PNG with the SVG's layout and text, atomically.
/// Throws IoError.
void write_loglog_png(const std::string& path, const std::vector<Plot>& panels);

}  // namespace lambert
