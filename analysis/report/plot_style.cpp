#include "analysis/report/plot_style.h"

#include <cstdio>

namespace doorbench::plot_style {

LineStyle line_style(Meaning meaning) {
  LineStyle s;
  switch (meaning) {
    case Meaning::kMeasured:
      s = {31, 119, 214, 1.0, 1.5, 2.0, false, 1.0, 2};
      break;
    case Meaning::kSimulated:
      s = {230, 85, 13, 1.0, 1.6, 6.0, true, 0.45, 1};
      break;
    case Meaning::kTuned:
      s = {50, 175, 60, 1.0, 1.6, 4.0, true, 0.7, 1};
      break;
    case Meaning::kOpening:
      s = {235, 160, 20, 1.0, 1.4, 2.0, false, 1.0, 0};
      break;
    case Meaning::kClosing:
      s = {150, 90, 210, 1.0, 1.4, 2.0, false, 1.0, 0};
      break;
    case Meaning::kResidual:
      s = {20, 170, 160, 1.0, 1.4, 2.0, false, 1.0, 0};
      break;
    case Meaning::kOther:
      s = {150, 150, 150, 1.0, 1.4, 2.0, false, 1.0, 0};
      break;
  }
  return s;
}

std::string hex_colour(Meaning meaning) {
  const LineStyle s = line_style(meaning);
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", unsigned(s.r), unsigned(s.g), unsigned(s.b));
  return text;
}

std::string_view meaning_name(Meaning meaning) {
  switch (meaning) {
    case Meaning::kMeasured:
      return "measured";
    case Meaning::kSimulated:
      return "simulated";
    case Meaning::kTuned:
      return "tuned";
    case Meaning::kOpening:
      return "opening";
    case Meaning::kClosing:
      return "closing";
    case Meaning::kResidual:
      return "residual";
    case Meaning::kOther:
      break;
  }
  return "other";
}

std::string axis_label(std::string_view quantity, std::string_view unit) {
  std::string label(quantity);
  if (!unit.empty()) label.append(" [").append(unit).append("]");
  return label;
}

DisplayUnit display_unit(std::string_view stored_unit) {
  if (stored_unit == "rad") return {"deg", kDegPerRad};
  if (stored_unit == "rad/s") return {"deg/s", kDegPerRad};
  if (stored_unit == "rad/s^2") return {"deg/s^2", kDegPerRad};
  return {std::string(stored_unit), 1.0};
}

}  // namespace doorbench::plot_style
