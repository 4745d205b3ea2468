#include "viewer/loop_steps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "analysis/loop/loop_result_file.h"
#include "core/number_format.h"

namespace doorbench::viewer {

LoopSteps read_loop_steps(const std::filesystem::path& dir_or_file) {
  const LoopResultFile file = read_loop_result(dir_or_file);
  LoopSteps result;
  result.path = file.path;
  result.source = file.source;
  for (const LoopResultStep& read : file.steps) {
    LoopStep step;
    step.number = read.number;
    step.effect = read.effect;
    step.fitted_before_rad_s = read.fitted_before_rad_s;
    step.fitted_after_rad_s = read.fitted_after_rad_s;
    step.held_out_before_rad_s = read.held_out_before_rad_s;
    step.held_out_after_rad_s = read.held_out_after_rad_s;
    step.held_out_improvement = read.held_out_improvement;
    step.bic_change = read.bic_change;
    for (const LoopResultStep::Parameter& p : read.parameters) {
      const std::string separator = step.parameters.empty() ? "" : ", ";
      step.parameters +=
          std::isnan(p.standard_uncertainty)
              ? printf_text("%s%s = %.4g %s", separator.c_str(), p.name.c_str(), p.value,
                            p.unit.c_str())
              : printf_text("%s%s = %.4g ± %.2g %s", separator.c_str(), p.name.c_str(), p.value,
                            p.standard_uncertainty, p.unit.c_str());
    }
    result.steps.push_back(std::move(step));
  }
  return result;
}

PlotView loop_steps_plot(const LoopSteps& steps) {
  std::vector<double> x, fitted, held_out;
  if (!steps.steps.empty()) {
    x.push_back(0.0);
    fitted.push_back(steps.steps.front().fitted_before_rad_s);
    held_out.push_back(steps.steps.front().held_out_before_rad_s);
  }
  for (const LoopStep& s : steps.steps) {
    x.push_back(double(s.number));
    fitted.push_back(s.fitted_after_rad_s);
    held_out.push_back(s.held_out_after_rad_s);
  }
  auto fitted_series = std::make_shared<Series>(Series::xy("fitted", "", "rad/s", x, fitted));
  auto held_series = std::make_shared<Series>(Series::xy("held out", "", "rad/s", x, held_out));
  fitted_series->colour = {40, 140, 230, 255};
  held_series->colour = {230, 90, 40, 255};
  PlotView plot;
  plot.title = "window RMSE of the rate after each step (0: start model)";
  plot.x_label = "step";
  plot.integer_x = true;
  plot.y_label = "RMSE";
  plot.add(fitted_series);
  plot.add(held_series);
  plot.fit();
  plot.y.min = std::min(plot.y.min, 0.0);  // RMSE against zero, not a zoomed-in band
  return plot;
}

}  // namespace doorbench::viewer
