#pragma once
// One plot's state and geometry (no GL, no ImGui): which series it shows, the visible
// ranges, zoom / pan / box zoom, time axes linked across plots, the crosshair readout, the
// axis ticks, and the draw data (polylines in pixels) the ImGui widget hands to ImDrawList.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "viewer/plot_series.h"

namespace doorbench::viewer {

struct Range {
  double min = 0.0;
  double max = 1.0;
  double span() const { return max - min; }
};

// A rectangle in pixels, y downwards (screen convention).
struct Rect {
  double x = 0.0, y = 0.0, width = 1.0, height = 1.0;
  bool contains(double px, double py) const {
    return px >= x && px < x + width && py >= y && py < y + height;
  }
};

struct Point {
  float x = 0.0f, y = 0.0f;
};

// Polylines of all series of a plot, flat so that a frame reuses the same memory.
struct DrawData {
  struct Strip {
    std::size_t begin = 0, end = 0;  // into points
    Rgba colour;
    float width_px = 2.0f;
    int layer = 0;  // the series' layer: strips are drawn in increasing layer order
  };
  std::vector<Point> points;
  std::vector<Strip> strips;
  std::vector<Column> columns;  // scratch
  std::size_t visible_samples = 0;
  void clear() {
    points.clear();
    strips.clear();
    visible_samples = 0;
  }
};

// What the crosshair shows for one series: its sample nearest to the cursor.
struct Readout {
  std::string series;
  std::string unit;
  std::string x_unit;
  std::size_t index = 0;
  double x = 0.0, y = 0.0;
};

// A vertical line at x (an event on a time axis), drawn behind the curves.
struct Marker {
  double x = 0.0;
  Rgba colour;
  std::string label;  // the tooltip: e.g. "stroke_start opening"
};

// A stretch of x shaded behind the curves over the data area's height (a channel at its
// sensor's limit), with a tooltip.
struct Shade {
  double x0 = 0.0, x1 = 0.0;  // x0 <= x1; drawn at least 1 px wide
  Rgba colour;
  std::string label;  // e.g. "inclinometer angle at its ±10 deg limit"
};

class PlotView {
 public:
  std::string title;
  std::string x_label;  // e.g. "time"
  std::string y_label;  // e.g. "force"
  std::vector<std::shared_ptr<const Series>> series;
  // Shared between plots whose time axes are linked (link_x_to).
  std::shared_ptr<Range> x = std::make_shared<Range>();
  Range y;
  std::vector<Marker> markers;
  std::vector<Shade> shades;
  bool integer_x = false;  // x takes whole numbers (e.g. steps): ticks 1 apart or more
  // Bumped by whoever replaces a series' data, so that cached draw data are rebuilt.
  std::uint64_t revision = 0;

  bool is_xy() const { return !series.empty() && series.front()->is_xy(); }
  // Adds a series; a plot holds time series or x–y series, not both (std::invalid_argument).
  void add(std::shared_ptr<const Series> s);
  // Makes this plot use `other`'s x-range: zoom and pan in either moves both.
  void link_x_to(const PlotView& other) { x = other.x; }

  // Ranges that show every sample, y with `margin` of its span on each side (a flat or
  // empty series gets a span of 1 around its value).
  void fit_x();
  void fit_y(double margin = 0.05);  // over the samples visible in x (time series)
  void fit(double margin = 0.05) {
    fit_x();
    fit_y(margin);
  }

  double to_px_x(double xv, const Rect& r) const;
  double to_px_y(double yv, const Rect& r) const;
  double from_px_x(double px, const Rect& r) const;
  double from_px_y(double py, const Rect& r) const;

  // Wheel zoom about the pixel (px, py): the data point under it stays under it. factor < 1
  // zooms in. x only when y_too is false.
  void zoom_about(double factor, double px, double py, const Rect& r, bool y_too);
  // Drag pan by (dx, dy) pixels: the content follows the mouse.
  void pan_px(double dx_px, double dy_px, const Rect& r);
  // Box zoom to the pixel rectangle with corners (px0, py0), (px1, py1); a box under 3
  // pixels on a side is ignored (a click, not a box). Returns whether it zoomed.
  bool box_zoom(double px0, double py0, double px1, double py1, const Rect& r);

  // The crosshair at pixel (px, py): each series' nearest sample (time series: nearest in
  // x; x–y: nearest on screen).
  std::vector<Readout> readout(double px, double py, const Rect& r) const;

  // Polylines in pixels of every series in rect r, decimated to its pixel columns. Reuses
  // out's memory. NaN samples break a line.
  void build_draw_data(const Rect& r, DrawData& out) const;
};

// The plot's visible data as CSV: a header `series,x,y,x_unit,y_unit`, then one row per
// sample: time series, every sample with x in the visible x-range; x–y series, every
// finite sample inside the visible box. Numbers with 17 significant digits.
std::string visible_csv(const PlotView& view);

// Tick values for an axis from min to max: steps of 1, 2 or 5 × 10^k, about `target` of
// them (at least two when a step of min_step or more allows), every tick inside [min, max],
// the step at least min_step (1 for an integer axis; 0: any).
std::vector<double> nice_ticks(double min, double max, int target = 6, double min_step = 0.0);
// A tick label: the value with as many decimals as the step needs; steps under 1e-3 or from
// 1e6 up: three significant digits with an exponent ("5e-06").
std::string tick_label(double value, double step);

}  // namespace doorbench::viewer
