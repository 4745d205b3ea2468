#pragma once
// What the SVG plots of this stage share (svg_plot.cpp, svg_charts.cpp): a value range, round
// tick spacings, tick text and XML escaping. Internal to analysis/report.
// Pure functions: safe from any thread.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace doorbench::svg_axes {

struct Range {
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  void include(double value) {
    if (!std::isfinite(value)) return;
    low = std::min(low, value);
    high = std::max(high, value);
  }
  bool empty() const { return !(low <= high); }
};

// A tick spacing of 1, 2 or 5 times a power of ten giving about `wanted` ticks.
inline double tick_spacing(const Range& range, int wanted) {
  const double raw = (range.high - range.low) / wanted;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double step : {1.0, 2.0, 5.0}) {
    if (step * power >= raw) return step * power;
  }
  return 10.0 * power;
}

// The range widened by 3 % each side (by 0.5 each side when it is a point).
inline Range padded(Range range) {
  if (range.high - range.low < 1e-12 * std::max(1.0, std::abs(range.high))) {
    range.low -= 0.5;
    range.high += 0.5;
  }
  const double margin = 0.03 * (range.high - range.low);
  return {range.low - margin, range.high + margin};
}

// A tick's text with as many decimals as its spacing needs ("-0" written "0").
inline std::string number_text(double value, double spacing) {
  char text[32];
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(spacing) + 1e-9)));
  std::snprintf(text, sizeof text, "%.*f", decimals,
                std::abs(value) < 1e-12 * spacing ? 0.0 : value);
  return text;
}

}  // namespace doorbench::svg_axes
