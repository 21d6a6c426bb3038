#pragma once
// Line plots (e.g. solver convergence: residual vs iteration and vs time) written as SVG
// (axes, ticks, labels, legend) and as PNG (the same plot rasterised, its text drawn in a small
// built-in bitmap font).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace lambert {

/// One curve: points (x_k, y_k), joined in order; non-finite points, and points <= 0 on a
/// log axis, are skipped.
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
  bool log_x = false;   ///< base-10 logarithmic x axis (else linear from 0)
  bool log_y = true;    ///< base-10 logarithmic y axis
  bool markers = false;  ///< a dot at every point (scatter-like plots such as error vs time)
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

}  // namespace lambert
