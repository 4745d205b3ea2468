// What `doorbench loop` and the demo write for a residual loop (app/loop_output.h).
#include "app/loop_output.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "acquisition/session/output_file.h"
#include "analysis/model/parameter_file.h"
#include "app/fit_inputs.h"
#include "app/fit_output.h"

namespace doorbench::app {
namespace {

nlohmann::ordered_json figures_json(const ModelFigures& f) {
  return {{"fitted_rmse_rad_s", f.fitted_rmse_rad_s},
          {"fitted_fit_percent", f.fitted_fit_percent},
          {"held_out_rmse_rad_s", f.held_out_rmse_rad_s},
          {"held_out_fit_percent", f.held_out_fit_percent},
          {"bic", f.bic}};
}

nlohmann::ordered_json loop_json(const LoopResult& result, const PreparedData& data) {
  nlohmann::ordered_json steps = nlohmann::ordered_json::array();
  for (const LoopStep& step : result.steps) {
    nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
    for (const FittedParameter& p : step.parameters) {
      parameters.push_back({{"name", p.name},
                            {"unit", p.unit},
                            {"value", p.value},
                            {"standard_uncertainty", std::isfinite(p.uncertainty)
                                                         ? nlohmann::ordered_json(p.uncertainty)
                                                         : nlohmann::ordered_json(nullptr)}});
    }
    steps.push_back({{"step", step.number},
                     {"effect", step.effect_name},
                     {"evidence",
                      {{"explained_fraction", step.explained_fraction},
                       {"score_z", step.score_z},
                       {"rank", step.rank}}},
                     {"parameters", parameters},
                     {"before", figures_json(step.before)},
                     {"after", figures_json(step.after)},
                     {"held_out_improvement", step.held_out_improvement},
                     {"bic_change", step.bic_change}});
  }
  const StructureCheck& check = result.structure;
  nlohmann::ordered_json structure = {
      {"ran", check.ran}, {"reason", check.reason}, {"noise_floor_rad_s", check.noise_floor_rad_s}};
  if (check.ran && check.other_fit) {
    structure["current_model"] = std::string(to_string(check.current_kind));
    structure["other_model"] = std::string(to_string(check.other_kind));
    structure["current"] = figures_json(check.current);
    structure["other"] = figures_json(check.other);
    structure["other_free_parameters"] = check.other_free;
    structure["other_is_better"] = check.other_better;
    structure["verdict"] = check.verdict;
  }
  return {{"source", data.source},
          {"interrupted", result.interrupted},
          {"stop_reason", result.stop_reason},
          {"steps", steps},
          {"structure_check", structure},
          {"start_fit", fit_result_json(result.start_fit, data)},
          {"final_fit", fit_result_json(result.final_fit, data)}};
}

}  // namespace

std::string steps_table(const LoopResult& result) {
  std::string table =
      "| step | effect | parameters | window RMSE fitted (rad/s) | held out (rad/s) |\n"
      "|---|---|---|---|---|\n";
  char row[512];
  const ModelFigures start = model_figures(result.start_fit.summary);
  std::snprintf(row, sizeof row, "| 0 | (start model) | | %.4g | %.4g |\n", start.fitted_rmse_rad_s,
                start.held_out_rmse_rad_s);
  table += row;
  for (const LoopStep& step : result.steps) {
    std::string parameters;
    for (const FittedParameter& p : step.parameters) {
      char text[128];
      std::snprintf(text, sizeof text, "%s%s = %.4g ± %.2g %s", parameters.empty() ? "" : ", ",
                    p.name.c_str(), p.value, p.uncertainty, p.unit.c_str());
      parameters += text;
    }
    std::snprintf(row, sizeof row, "| %d | %s | %s | %.4g → %.4g | %.4g → %.4g |\n", step.number,
                  step.effect_name.c_str(), parameters.c_str(), step.before.fitted_rmse_rad_s,
                  step.after.fitted_rmse_rad_s, step.before.held_out_rmse_rad_s,
                  step.after.held_out_rmse_rad_s);
    table += row;
  }
  const StructureCheck& check = result.structure;
  if (check.ran && check.other_fit) {
    const std::string other(to_string(check.other_kind));
    const std::string current(to_string(check.current_kind));
    std::snprintf(row, sizeof row,
                  "| %zu | structure: %s model is better | held out: %s %.4g, %s %.4g rad/s; BIC "
                  "%+.4g | %.4g → %.4g | %.4g → %.4g |\n",
                  result.steps.size() + 1, check.other_better ? other.c_str() : current.c_str(),
                  current.c_str(), check.current.held_out_rmse_rad_s, other.c_str(),
                  check.other.held_out_rmse_rad_s, check.bic_change,
                  check.current.fitted_rmse_rad_s, check.other.fitted_rmse_rad_s,
                  check.current.held_out_rmse_rad_s, check.other.held_out_rmse_rad_s);
    table += row;
  }
  return table;
}

std::string write_loop_outputs(const std::filesystem::path& dir, const LoopResult& result,
                               const PreparedData& data, const std::string& model_name,
                               const FitOptions& fit_options,
                               const std::vector<std::string>& report_lines) {
  write_text_file_atomically(dir / "result.json", loop_json(result, data).dump(2) + "\n");
  write_text_file_atomically(dir / "fitted-params.json", to_parameter_json(result.model()));
  write_text_file_atomically(dir / "fitted-effects.json", to_effects_json(result.model()));
  const FitPlots plots = write_fit_plots(dir, result.model(), data, fit_options);
  const std::string table = steps_table(result);
  std::ostringstream report;
  report << "# Residual loop: the " << model_name << " model on " << data.source << "\n\n";
  for (const std::string& line : report_lines) report << line << ".\n\n";
  report << "Data: " << data.rate_summary << ".\n\n"
         << handle_radius_line(data, result.model()) << ".\n\n"
         << table << "\n```\n"
         << result.full_report() << "```\n\n"
         << "The final model's " << plots.whiteness << ".\n\n"
         << "Plots of the final model:\n\n";
  for (const std::string& plot : plots.files) report << "![" << plot << "](" << plot << ")\n\n";
  write_text_file_atomically(dir / "report.md", report.str());
  return table;
}

}  // namespace doorbench::app
