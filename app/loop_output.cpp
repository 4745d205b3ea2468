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
#include "core/json_number.h"

namespace doorbench::app {
namespace {

constexpr nlohmann::ordered_json (*finite_or_null)(double) = &json_number<nlohmann::ordered_json>;

nlohmann::ordered_json figures_json(const ModelFigures& f) {
  return {{"fitted_rmse_rad_s", finite_or_null(f.fitted_rmse_rad_s)},
          {"fitted_fit_percent", finite_or_null(f.fitted_fit_percent)},
          {"held_out_rmse_rad_s", finite_or_null(f.held_out_rmse_rad_s)},
          {"held_out_fit_percent", finite_or_null(f.held_out_fit_percent)},
          {"bic", finite_or_null(f.bic)},
          {"sum_of_squares", finite_or_null(f.sum_of_squares)},
          {"residuals", f.residuals},
          {"parameters", f.parameters},
          {"free_parameters", f.free_parameters},
          {"fitted_samples", f.fitted_samples},
          {"held_out_samples", f.held_out_samples}};
}

nlohmann::ordered_json loop_parameters_json(const std::vector<FittedParameter>& list) {
  nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
  for (const FittedParameter& p : list) {
    parameters.push_back({{"name", p.name},
                          {"unit", p.unit},
                          {"value", p.value},
                          {"standard_uncertainty", finite_or_null(p.uncertainty)},
                          {"free", p.free},
                          {"at_bound", p.at_bound},
                          {"determined", p.determined}});
  }
  return parameters;
}

// One candidate of an examination: its evidence and, when refitted, the refit's figures
// against its parent's, the effect's parameters and the verdict (kept or rejected, and why).
nlohmann::ordered_json candidate_json(const CandidateEvidence& c) {
  nlohmann::ordered_json out = {{"rank", c.rank},
                                {"effect", c.name},
                                {"explained_fraction", c.explained_fraction},
                                {"score_z", c.score_z},
                                {"independent_share", c.independent_share},
                                {"scan", c.scan}};
  if (c.screened) {
    out["second_look"] = {{"explained_fraction", c.screen_explained_fraction},
                          {"score_z", c.screen_score_z},
                          {"promoted", c.promoted}};
  }
  out["refitted"] = c.refitted;
  if (c.refitted) {
    out["reexamined_after_family_switch"] = c.reexamined;
    out["refit_start"] = c.refit_start;
    out["parent_stands"] = c.parent_stands;
    out["before"] = figures_json(c.before);
    if (c.after) {
      out["after"] = figures_json(*c.after);
      out["held_out_improvement"] = finite_or_null(c.held_out_improvement);
      out["bic_change"] = finite_or_null(c.bic_change);
      out["parameters"] = loop_parameters_json(c.parameters);
    }
  }
  out["qualifies"] = c.qualifies;
  out["verdict"] = c.verdict;
  return out;
}

nlohmann::ordered_json candidates_json(const std::vector<CandidateEvidence>& candidates) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const CandidateEvidence& c : candidates) list.push_back(candidate_json(c));
  return list;
}

nlohmann::ordered_json loop_json(const LoopResult& result, const PreparedData& data) {
  nlohmann::ordered_json steps = nlohmann::ordered_json::array();
  for (const LoopStep& step : result.steps) {
    steps.push_back({{"step", step.number},
                     {"model", std::string(to_string(step.model_kind))},
                     {"effect", step.effect_name},
                     {"evidence",
                      {{"explained_fraction", step.explained_fraction},
                       {"score_z", step.score_z},
                       {"second_look", step.second_look},
                       {"rank", step.rank}}},
                     {"parameters", loop_parameters_json(step.parameters)},
                     {"before", figures_json(step.before)},
                     {"after", figures_json(step.after)},
                     {"held_out_improvement", step.held_out_improvement},
                     {"bic_change", step.bic_change},
                     {"candidates", candidates_json(step.candidates)}});
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
    structure["other_undetermined_parameters"] = check.other_undetermined;
    structure["other_is_better"] = check.other_better;
    structure["verdict"] = check.verdict;
    structure["after_steps"] = check.after_steps;
    structure["switched"] = check.switched;
    structure["reexamined"] = check.reexamined;
    structure["abandoned_step_candidates"] = candidates_json(check.candidates);
    structure["remaining"] = candidates_json(check.remaining);
  }
  return {{"source", data.source},
          {"interrupted", result.interrupted},
          {"stop_reason", result.stop_reason},
          {"final_model", std::string(to_string(result.model().kind()))},
          {"steps", steps},
          {"last_candidates", candidates_json(result.last_candidates)},
          {"structure_check", structure},
          {"start_fit", fit_result_json(result.start_fit, data)},
          {"final_fit", fit_result_json(result.final_fit, data)}};
}

}  // namespace

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
    std::snprintf(row, sizeof row, "| %d | %s%s | %s | %.4g → %.4g | %.4g → %.4g |\n", step.number,
                  step.effect_name.c_str(),
                  check.switched ? (" (" + std::string(to_string(step.model_kind)) + ")").c_str()
                                 : "",
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
