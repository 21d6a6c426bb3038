#pragma once
// Line plots (e.g. solver convergence: residual vs iteration and vs time) written as SVG
// (axes, ticks, labels, legend). PNG figures come from the CSVs through matplotlib
// (`python3 -m lambert.plot`, python/lambert/plot.py).

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

/// Colour (sRGB 8-bit) of series k (Tableau 10, as matplotlib's default cycle).
std::array<std::uint8_t, 3> plot_color(std::size_t k);

/// The panels side by side as an SVG document (each panel 560 x 420 px).
std::string plots_svg(const std::vector<Plot>& panels);

/// Writes plots_svg atomically. Throws IoError.
void write_plots_svg(const std::string& path, const std::vector<Plot>& panels);

}  // namespace lambert
