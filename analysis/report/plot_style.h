#pragma once
// One plotting vocabulary for everything doorbench draws: the viewer (viewer/) and the SVG
// reports (analysis/report/svg_plot.h) take a curve's colour, width, opacity, dashes and stacking
// from what it means, here, so that "measured" or "closing" looks the same in both:
//   measured   blue, opaque, on top of every other curve (never hidden by a model)
//   simulated  vermilion, under measured: dashed in SVG, wide and translucent in the viewer,
//              so a perfect fit shows the measured line inside a halo
//   tuned      green (the viewer's tuning layout), like simulated otherwise
//   opening    amber; closing: purple (loops, residuals by direction, stroke markers)
//   residual   teal
//   other      grey (anything else; callers may pick their own colour)
//   at limit   a translucent red band behind a channel where its sensor is at its limit
// Angles are shown in degrees where people read them (kDegPerRad); every axis label carries
// its unit, written "quantity [unit]" (axis_label).
//
// Pure data, no state: safe from any thread.
#include <cstdint>
#include <numbers>
#include <string>
#include <string_view>

#include "core/units.h"

namespace doorbench::plot_style {

enum class Meaning { kOther, kMeasured, kSimulated, kTuned, kOpening, kClosing, kResidual };

struct LineStyle {
  std::uint8_t r = 0, g = 0, b = 0;
  double opacity = 1.0;   // 0..1
  double width_px = 1.5;  // SVG stroke width; the viewer uses viewer_width_px
  double viewer_width_px = 2.0;
  bool dashed = false;  // SVG only (ImGui has no dashes: the viewer uses opacity)
  double viewer_opacity = 1.0;
  int layer = 0;  // drawn in increasing layer order: higher is on top
};

LineStyle line_style(Meaning meaning);
// "#rrggbb" of the meaning's colour.
std::string hex_colour(Meaning meaning);
// Lower-case name: "measured", "simulated", "tuned", "opening", "closing", "residual", "other".
std::string_view meaning_name(Meaning meaning);

// The shade behind a channel's stretches at its sensor's limit (the viewer's channels
// layout; sensors/channel_limits.h): red, translucent, so the curve stays readable.
struct ShadeStyle {
  std::uint8_t r = 0, g = 0, b = 0;
  double opacity = 1.0;
};
inline constexpr ShadeStyle kAtLimitShade{230, 40, 40, 0.3};

// "angle [deg]"; just the quantity when the unit is empty.
std::string axis_label(std::string_view quantity, std::string_view unit);

// Units shown for a stored unit: "rad" -> "deg", "rad/s" -> "deg/s", "rad/s^2" -> "deg/s^2"
// (scale kDegPerRad); anything else unchanged (scale 1).
struct DisplayUnit {
  std::string unit;
  double scale = 1.0;
};
DisplayUnit display_unit(std::string_view stored_unit);

}  // namespace doorbench::plot_style
