// result.json of a residual loop, written and read back (loop_result_file.h).
#include "analysis/loop/loop_result_file.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "analysis/fit/fit_result_file.h"
#include "analysis/report/json_field.h"
#include "core/json_number.h"

namespace doorbench {
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

nlohmann::ordered_json loop_result_object(const LoopResult& result, const PreparedData& data) {
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
          {"start_fit", nlohmann::ordered_json::parse(fit_result_json(result.start_fit, data))},
          {"final_fit", nlohmann::ordered_json::parse(fit_result_json(result.final_fit, data))}};
}

double loop_number(const nlohmann::json& object, const char* name, const std::string& where) {
  const nlohmann::json& value = json_field(object, name, where);
  if (value.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (!value.is_number()) {
    throw std::runtime_error(
        std::string(where).append(": '").append(name).append("' is not a number"));
  }
  return value.get<double>();
}

}  // namespace

std::string loop_result_json(const LoopResult& result, const PreparedData& data) {
  return loop_result_object(result, data).dump(2) + "\n";
}

LoopResultFile read_loop_result(const std::filesystem::path& dir_or_file) {
  const std::filesystem::path path =
      std::filesystem::is_directory(dir_or_file) ? dir_or_file / "result.json" : dir_or_file;
  nlohmann::json json = read_json_file(path);
  LoopResultFile result;
  result.path = path;
  const std::string file = path.string();
  if (json.contains("source") && json["source"].is_string()) result.source = json["source"];
  const nlohmann::json& steps = json_field(json, "steps", file);
  if (!steps.is_array()) throw std::runtime_error(file + ": 'steps' is not an array");
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::string where =
        std::string(file).append(": steps[").append(std::to_string(i)).append("]");
    const nlohmann::json& s = steps[i];
    LoopResultStep step;
    step.number = int(loop_number(s, "step", where));
    step.effect = json_field(s, "effect", where).get<std::string>();
    const nlohmann::json& before = json_field(s, "before", where);
    const nlohmann::json& after = json_field(s, "after", where);
    step.fitted_before_rad_s = loop_number(before, "fitted_rmse_rad_s", where + ".before");
    step.held_out_before_rad_s = loop_number(before, "held_out_rmse_rad_s", where + ".before");
    step.fitted_after_rad_s = loop_number(after, "fitted_rmse_rad_s", where + ".after");
    step.held_out_after_rad_s = loop_number(after, "held_out_rmse_rad_s", where + ".after");
    step.held_out_improvement = loop_number(s, "held_out_improvement", where);
    step.bic_change = loop_number(s, "bic_change", where);
    if (s.contains("parameters") && s["parameters"].is_array()) {
      for (const auto& p : s["parameters"]) {
        LoopResultStep::Parameter parameter;
        parameter.value = p.value("value", std::numeric_limits<double>::quiet_NaN());
        const auto& u = p.contains("standard_uncertainty") ? p["standard_uncertainty"] : nullptr;
        parameter.standard_uncertainty =
            u.is_number() ? u.get<double>() : std::numeric_limits<double>::quiet_NaN();
        parameter.name = p.value("name", "?");
        parameter.unit = p.value("unit", "");
        step.parameters.push_back(std::move(parameter));
      }
    }
    result.steps.push_back(std::move(step));
  }
  return result;
}
}  // namespace doorbench
