#pragma once
// Two charts beside the line plot (analysis/report/svg_plot.h), as standalone SVG:
//
// - The forest plot: one row per estimate, its name on the axis at the left, the estimate
//   as a diamond with its interval (caps at the ends, an arrow where an end is infinite),
//   optionally a second, thicker interval inside it (a comparison interval), a vertical
//   reference line and a shaded band (an equivalence margin). A row without an interval
//   carries a note in words ("no interval: nobody preferred A"). Rows are drawn top to
//   bottom in the order given.
// - The dose-response plot: data as points whose area is proportional to their weight (a
//   level's trials), a fitted curve and its interval band.
//
// Both keep svg_plot's conventions: a title, axis labels with units, round ticks, the legend
// right of the data area, each legend key in its series' colour (tests/support/check_svg.py).
// Throws std::invalid_argument when nothing is finite to draw or the series' lengths differ.
// Pure functions: safe from any thread.
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace doorbench {

struct ForestRow {
  std::string label;  // on the axis
  double estimate = std::numeric_limits<double>::quiet_NaN();
  double low = std::numeric_limits<double>::quiet_NaN();  // ±infinity: open on that side
  double high = std::numeric_limits<double>::quiet_NaN();
  double inner_low = std::numeric_limits<double>::quiet_NaN();  // NaN: no inner interval
  double inner_high = std::numeric_limits<double>::quiet_NaN();
  std::string note;  // written in the row, e.g. why it has no interval
};

struct ForestOptions {
  std::string title;
  std::string x_label;  // with its unit, "worth (log odds) [-]"
  std::string interval_label = "95 % interval";
  std::string inner_label;  // the inner interval's legend entry (when some row has one)
  std::string estimate_label = "estimate";
  double reference_line = 0.0;                                 // NaN: none
  double band_low = std::numeric_limits<double>::quiet_NaN();  // NaN: no band
  double band_high = std::numeric_limits<double>::quiet_NaN();
  std::string band_label;
  int width_px = 760;
};

std::string render_svg_forest(const ForestOptions& options, std::span<const ForestRow> rows);

struct DoseResponsePlot {
  std::string title, x_label, y_label;
  std::vector<double> x, y, weight;  // the data points
  std::string points_label;
  std::vector<double> curve_x, curve_y, band_low, band_high;  // band: empty for none
  std::string curve_label, band_label;
  double y_min = 0.0, y_max = 1.0;  // the y axis' range
  int width_px = 760, height_px = 440;
};

std::string render_svg_dose_response(const DoseResponsePlot& plot);

}  // namespace doorbench
