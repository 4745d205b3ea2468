#include "viewer/loop_steps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include "viewer/json_field.h"

namespace doorbench::viewer {

namespace {


double number(const nlohmann::json& object, const char* name, const std::string& where) {
  const nlohmann::json& value = json_field(object, name, where);
  if (value.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (!value.is_number()) {
    throw std::runtime_error(
        std::string(where).append(": '").append(name).append("' is not a number"));
  }
  return value.get<double>();
}

}  // namespace

LoopSteps read_loop_steps(const std::filesystem::path& dir_or_file) {
  const std::filesystem::path path =
      std::filesystem::is_directory(dir_or_file) ? dir_or_file / "result.json" : dir_or_file;
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& error) {
    throw std::runtime_error(path.string() + ": not JSON (" + error.what() + ")");
  }
  LoopSteps result;
  result.path = path;
  const std::string file = path.string();
  if (json.contains("source") && json["source"].is_string()) result.source = json["source"];
  const nlohmann::json& steps = json_field(json, "steps", file);
  if (!steps.is_array()) throw std::runtime_error(file + ": 'steps' is not an array");
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::string where =
        std::string(file).append(": steps[").append(std::to_string(i)).append("]");
    const nlohmann::json& s = steps[i];
    LoopStep step;
    step.number = int(number(s, "step", where));
    step.effect = json_field(s, "effect", where).get<std::string>();
    const nlohmann::json& before = json_field(s, "before", where);
    const nlohmann::json& after = json_field(s, "after", where);
    step.fitted_before_rad_s = number(before, "fitted_rmse_rad_s", where + ".before");
    step.held_out_before_rad_s = number(before, "held_out_rmse_rad_s", where + ".before");
    step.fitted_after_rad_s = number(after, "fitted_rmse_rad_s", where + ".after");
    step.held_out_after_rad_s = number(after, "held_out_rmse_rad_s", where + ".after");
    step.held_out_improvement = number(s, "held_out_improvement", where);
    step.bic_change = number(s, "bic_change", where);
    if (s.contains("parameters") && s["parameters"].is_array()) {
      char text[200];
      for (const auto& p : s["parameters"]) {
        const double value = p.value("value", std::numeric_limits<double>::quiet_NaN());
        const auto& u = p.contains("standard_uncertainty") ? p["standard_uncertainty"] : nullptr;
        const std::string name = p.value("name", "?"), unit = p.value("unit", "");
        if (u.is_number()) {
          std::snprintf(text, sizeof text, "%s%s = %.4g ± %.2g %s",
                        step.parameters.empty() ? "" : ", ", name.c_str(), value, u.get<double>(),
                        unit.c_str());
        } else {
          std::snprintf(text, sizeof text, "%s%s = %.4g %s", step.parameters.empty() ? "" : ", ",
                        name.c_str(), value, unit.c_str());
        }
        step.parameters += text;
      }
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
