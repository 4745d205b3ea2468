// What `doorbench loop` and the demo write for a residual loop (app/loop_output.h).
#include "app/loop_output.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "acquisition/session/output_file.h"
#include "analysis/loop/loop_result_file.h"
#include "analysis/model/parameter_file.h"
#include "app/fit_inputs.h"
#include "app/fit_output.h"
#include "core/json_number.h"

namespace doorbench::app {
namespace {

// The structure check's row of the steps table (labelled `label`).
std::string structure_row(const StructureCheck& check, const std::string& label) {
  const std::string other(to_string(check.other_kind));
  const std::string current(to_string(check.current_kind));
  char row[512];
  std::snprintf(row, sizeof row,
                "| %s | structure: %s model is better%s | held out: %s %.4g, %s %.4g rad/s; BIC "
                "%+.4g | %.4g → %.4g | %.4g → %.4g |\n",
                label.c_str(), check.other_better ? other.c_str() : current.c_str(),
                check.switched ? " (the loop goes on with it)" : "", current.c_str(),
                check.current.held_out_rmse_rad_s, other.c_str(), check.other.held_out_rmse_rad_s,
                check.bic_change, check.current.fitted_rmse_rad_s, check.other.fitted_rmse_rad_s,
                check.current.held_out_rmse_rad_s, check.other.held_out_rmse_rad_s);
  return row;
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
  const StructureCheck& check = result.structure;
  const bool check_row = check.ran && check.other_fit;
  for (std::size_t i = 0; i < result.steps.size(); ++i) {
    const LoopStep& step = result.steps[i];
    if (check_row && check.switched && static_cast<int>(i) == check.after_steps) {
      table += structure_row(check, "-");
    }
    std::string parameters;
    for (const FittedParameter& p : step.parameters) {
      char text[128];
      std::snprintf(text, sizeof text, "%s%s = %.4g ± %.2g %s", parameters.empty() ? "" : ", ",
                    p.name.c_str(), p.value, p.uncertainty, p.unit.c_str());
      parameters += text;
    }
    std::snprintf(
        row, sizeof row, "| %d | %s%s | %s | %.4g → %.4g | %.4g → %.4g |\n", step.number,
        step.effect_name.c_str(),
        check.switched ? (" (" + std::string(to_string(step.model_kind)) + ")").c_str() : "",
        parameters.c_str(), step.before.fitted_rmse_rad_s, step.after.fitted_rmse_rad_s,
        step.before.held_out_rmse_rad_s, step.after.held_out_rmse_rad_s);
    table += row;
  }
  if (check_row && !(check.switched && check.after_steps < static_cast<int>(result.steps.size()))) {
    table += structure_row(check, check.switched ? "-" : std::to_string(result.steps.size() + 1));
  }
  return table;
}

std::string write_loop_outputs(const std::filesystem::path& dir, const LoopResult& result,
                               const PreparedData& data, const std::string& model_name,
                               const FitOptions& fit_options,
                               const std::vector<std::string>& report_lines) {
  write_text_file_atomically(dir / "result.json", loop_result_json(result, data));
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
