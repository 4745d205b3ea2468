#pragma once
// Line plots as standalone SVG files (any browser shows them): several series with a
// legend to the right of the data (never over a curve), axes with round-number ticks,
// labels with units. Each series is drawn as its meaning says (analysis/report/plot_style.h, the
// vocabulary the viewer uses too): measured on top, simulated dashed under it, so both stay
// visible when they coincide. Long series are reduced to each pixel column's first,
// smallest, largest and last point, which draws the same.
#include <span>
#include <string>
#include <vector>

#include "analysis/report/plot_style.h"

namespace doorbench {

struct PlotSeries {
  std::string label;
  std::span<const double> x;
  std::span<const double> y;
  std::string color;  // any SVG colour; empty: the meaning's (a palette's for kOther)
  plot_style::Meaning meaning = plot_style::Meaning::kOther;  // style and stacking
};

struct PlotOptions {
  std::string title;
  std::string x_label;  // with its unit, e.g. "angle [deg]" (plot_style::axis_label)
  std::string y_label;
  int width_px = 760;
  int height_px = 440;
};

// Throws std::invalid_argument when a series' x and y differ in length or no series has
// a finite point.
std::string render_svg_plot(const PlotOptions& options, std::span<const PlotSeries> series);

// Writes the plot whole or not at all (acquisition/session/output_file.h); throws OutputError
// "PATH: cannot write: SYSTEM ERROR" when it cannot.
void write_svg_plot(const std::string& path, const PlotOptions& options,
                    std::span<const PlotSeries> series);

}  // namespace doorbench
