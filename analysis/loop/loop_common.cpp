// The residual loop's shared text (internal/loop_common.h).
#include "analysis/loop/internal/loop_common.h"

#include <cmath>

#include "core/number_format.h"

namespace doorbench::loop_detail {

// Four significant digits: the loop's tables and its reasons.
std::string number(double value) {
  return format_significant(value, 4);
}

std::string describe_figures(const ModelFigures& figures) {
  return "window RMSE of omega " + number(figures.fitted_rmse_rad_s) + " rad/s fitted, " +
         number(figures.held_out_rmse_rad_s) + " held out";
}

std::string parameter_text(const FittedParameter& parameter) {
  std::string text = parameter.name + " = " + number(parameter.value);
  if (parameter.free) {
    text += " +- " + number(parameter.uncertainty);
  } else {
    text += " (fixed)";
  }
  if (!parameter.unit.empty()) text += " " + parameter.unit;
  if (parameter.at_bound) text += " [at a bound]";
  if (parameter.free && !parameter.determined) text += " [undetermined]";
  return text;
}

}  // namespace doorbench::loop_detail
