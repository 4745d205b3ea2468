#pragma once
// The plot widget of our own, drawn with ImDrawList from a PlotView (viewer/plot_view.h):
// series, legend with units, grid with ticks, wheel zoom (about the cursor; x only on time
// series unless Shift is held), drag pan (left), box zoom (right drag), double click to fit
// everything, and a crosshair with the nearest samples' readout.
#include <string>
#include <vector>

#include "viewer/plot_view.h"

namespace doorbench::viewer {

// Where a plot was drawn in the last frame, and what it showed (for the screenshot's
// companion file and the tests that check pixels against it).
struct PlotRecord {
  std::string title;
  Rect area;  // the data area in window pixels, y downwards
  Range x, y;
  std::vector<std::string> series;
  std::vector<Rgba> colours;
  // The header's texts as drawn: the title, each series' "name [unit]", "x: label [unit]".
  std::vector<std::string> labels;
  const PlotView* view = nullptr;
  Rect widget;            // the whole widget: header, axes and data area
  bool want_csv = false;  // its CSV or PNG button was pressed this frame
  bool want_png = false;
};

struct PlotWidgetState {
  bool box_active = false;
  double box_x0 = 0.0, box_y0 = 0.0;
  DrawData draw;  // reused frame after frame
  // What `draw` was built for: rebuilt only when the ranges, the area or the series change
  // (series are immutable once made), so a still plot costs nothing per frame.
  Range drawn_x, drawn_y;
  Rect drawn_area;
  std::size_t drawn_series = 0;
  std::uint64_t drawn_revision = 0;
  bool drawn = false;
};

// Draws `view` at the cursor in a box of width × height pixels (0: fill what remains).
// Returns where it went. With `controls`, CSV and PNG export buttons sit in the header.
PlotRecord plot_widget(const char* id, PlotView& view, PlotWidgetState& state, float width,
                       float height, bool controls = false);

// Series colour to ImGui's packed colour.
unsigned int to_imgui_colour(Rgba c);

}  // namespace doorbench::viewer
