// result.json of a fit folder, written and read back (fit_result_file.h).
#include "analysis/fit/fit_result_file.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "analysis/fit/fit_metrics.h"
#include "analysis/model/parameter_file.h"
#include "analysis/report/json_field.h"
#include "core/json_number.h"
#include "core/numbers.h"

namespace doorbench {
namespace {

nlohmann::ordered_json error_stats_json(const ErrorStats& stats) {
  constexpr nlohmann::ordered_json (*number)(double) = &json_number<nlohmann::ordered_json>;
  return {{"samples", stats.count},
          {"rmse_rad_s", number(stats.rmse())},
          {"max_abs_error_rad_s", number(stats.max_abs_error)},
          {"time_of_max_s", stats.time_of_max_s},
          {"fit_percent", number(stats.fit_percent())}};
}

nlohmann::ordered_json metrics_json(const FitMetrics& metrics) {
  nlohmann::ordered_json strokes = nlohmann::ordered_json::array();
  for (const StrokeFitMetrics& stroke : metrics.strokes) {
    strokes.push_back(
        {{"stroke", stroke.stroke_id},
         {"direction", stroke.direction == StrokeDirection::kOpening ? "opening" : "closing"},
         {"windows", error_stats_json(stroke.window)},
         {"whole_stroke_replay", error_stats_json(stroke.replay)},
         {"replay_ok", stroke.replay_ok}});
  }
  const double study = metrics.study_objective_rad_s();
  return {{"windows", error_stats_json(metrics.window)},
          {"whole_stroke_replay", error_stats_json(metrics.replay)},
          {"study_objective_max_abs_rate_error_rad_s",
           std::isfinite(study) ? nlohmann::ordered_json(study) : nlohmann::ordered_json(nullptr)},
          {"failed_replays", metrics.failed_replays},
          {"strokes", strokes}};
}

// The global stage's starts and distinct optima; null when the stage did not run.
nlohmann::ordered_json global_search_json(const FitSummary& s) {
  if (!s.global.ran) return nullptr;
  constexpr nlohmann::ordered_json (*number)(double) = &json_number<nlohmann::ordered_json>;
  nlohmann::ordered_json optima = nlohmann::ordered_json::array();
  for (const GlobalOptimum& optimum : s.global.optima) {
    nlohmann::ordered_json values = nlohmann::ordered_json::object();
    for (std::size_t k = 0; k < optimum.free_values.size() && k < s.free_names.size(); ++k) {
      values[s.free_names[k]] = number(optimum.free_values[k]);
    }
    optima.push_back({{"cost", number(optimum.cost)},
                      {"fit_percent", number(optimum.fit_percent)},
                      {"reached_from", optimum.reached_from},
                      {"parameters", values}});
  }
  return {{"starts_tried", s.global.starts_tried},
          {"start_as_given", s.global.start_as_given},
          {"subset_refits", s.global.subset_refits},
          {"subsets", s.global.partition},
          {"rounds", s.global.rounds},
          {"reset_parameters", s.global.reset_parameters},
          {"soft_starts", s.global.soft_starts},
          {"soft_polished", s.global.soft_polished},
          {"repolished", s.global.repolished},
          {"repolished_lower", s.global.repolished_lower},
          {"sample_points", s.global.sample_points},
          {"promising", s.global.promising},
          {"polished", s.global.polished},
          {"hops", s.global.hops},
          {"hops_lower", s.global.hops_lower},
          {"distinct_optima", s.global.optima.size()},
          {"reached_best", s.global.reached_best},
          {"best_from", s.global.best_from},
          {"optima", optima},
          {"report", s.global.report(s.free_names)}};
}

// For each free parameter undetermined or on a bound, the kinds of stroke that would
// determine it (FitSummary::determining); an empty array when there is none.
nlohmann::ordered_json determining_json(const FitSummary& s) {
  constexpr nlohmann::ordered_json (*number)(double) = &json_number<nlohmann::ordered_json>;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (const DeterminingStrokes& row : s.determining) {
    nlohmann::ordered_json kinds = nlohmann::ordered_json::array();
    for (const DeterminingStrokes::Kind& kind : row.kinds) {
      kinds.push_back({{"kind", kind.kind},
                       {"label", kind.label},
                       {"relative_uncertainty", number(kind.relative)},
                       {"determines", kind.determines}});
    }
    rows.push_back({{"parameter", row.parameter},
                    {"undetermined", row.undetermined},
                    {"at_bound", row.at_bound},
                    {"relative_uncertainty_now", number(row.relative_now)},
                    {"kinds", kinds}});
  }
  return rows;
}

nlohmann::ordered_json fit_result_object(const FitResult& result, const PreparedData& data) {
  const FitSummary& s = result.summary;
  nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
  for (const FittedParameter& p : s.parameters) {
    constexpr nlohmann::ordered_json (*number)(double) = &json_number<nlohmann::ordered_json>;
    parameters.push_back({{"name", p.name},
                          {"unit", p.unit},
                          {"free", p.free},
                          {"start", p.start},
                          {"value", p.value},
                          {"standard_uncertainty", number(p.uncertainty)},
                          {"bounds", {p.bounds.lower, p.bounds.upper}},
                          {"at_bound", p.at_bound},
                          {"determined", p.determined}});
  }
  nlohmann::ordered_json correlations = nlohmann::ordered_json::array();
  for (const ParameterCorrelation& c : s.strong_correlations) {
    correlations.push_back({{"first", c.first}, {"second", c.second}, {"value", c.value}});
  }
  nlohmann::ordered_json excluded = nlohmann::ordered_json::array();
  for (const ExcludedSegment& e : data.excluded) {
    excluded.push_back({{"start_s", e.start_s}, {"end_s", e.end_s}, {"reason", e.reason}});
  }
  const nlohmann::ordered_json sampling = {{"sample_rate_hz", data.sample_rate_hz},
                                           {"interval_median_s", data.interval_median_s},
                                           {"interval_min_s", data.interval_min_s},
                                           {"interval_max_s", data.interval_max_s},
                                           {"jittered", data.jittered},
                                           {"derivative_cutoff_hz", data.derivative_cutoff_hz},
                                           {"rate_summary", data.rate_summary},
                                           {"handle_radius_m", data.handle_radius_m},
                                           {"handle_radius_origin", data.handle_radius_origin}};
  return {{"source", data.source},
          {"data", sampling},
          {"model", std::string(to_string(s.model_kind))},
          {"strokes", s.strokes},
          {"windows", s.windows},
          {"residuals", s.residuals},
          {"free_parameters", s.free_parameters},
          {"interrupted", s.interrupted.empty() ? nlohmann::ordered_json(nullptr)
                                                : nlohmann::ordered_json(s.interrupted)},
          {"converged", s.converged},
          {"termination", s.termination},
          {"iterations", s.iterations},
          {"solve_time_s", s.solve_time_s},
          {"total_time_s", s.total_time_s},
          {"residual_variance", s.residual_variance},
          {"parameters", parameters},
          {"correlations_above_threshold", correlations},
          {"undetermined", s.undetermined},
          {"identifiable", s.identifiable},
          {"global_search", global_search_json(s)},
          {"what_would_determine", determining_json(s)},
          {"fitted", metrics_json(s.fitted)},
          {"held_out", s.held_out ? metrics_json(*s.held_out) : nlohmann::ordered_json(nullptr)},
          {"folds", s.folds},
          {"excluded_segments", excluded},
          {"notes", s.notes}};
}

// The window RMSE of a metrics block ("fitted" or "held_out"); NaN when the block or the
// number is null (no cross-validation, or no samples).
double window_rmse(const nlohmann::json& json, const char* block, const std::string& file) {
  const nlohmann::json& metrics = json_field(json, block, file);
  if (metrics.is_null()) return kNaN;
  const std::string where = std::string(file).append(": ").append(block);
  const nlohmann::json& windows = json_field(metrics, "windows", where);
  const nlohmann::json& rmse = json_field(windows, "rmse_rad_s", where + ".windows");
  if (rmse.is_null()) return kNaN;
  if (!rmse.is_number()) {
    throw std::runtime_error(where + ".windows: 'rmse_rad_s' is not a number");
  }
  return rmse.get<double>();
}

}  // namespace

std::string fit_result_json(const FitResult& result, const PreparedData& data) {
  return fit_result_object(result, data).dump(2) + "\n";
}

FitResultFolder read_fit_result(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) {
    throw std::runtime_error(dir.string() + ": not a folder (expected a `doorbench fit` --out)");
  }
  const std::filesystem::path result_path = dir / "result.json";
  nlohmann::json json = read_json_file(result_path);
  const std::string file = result_path.string();
  if (json.is_object() && json.contains("steps")) {
    throw std::runtime_error(file + ": a `doorbench loop` result; open it with --loop");
  }
  const nlohmann::json& model = json_field(json, "model", file);
  const std::optional<ModelKind> kind =
      model.is_string() ? parse_model_kind(model.get<std::string>()) : std::nullopt;
  if (!kind) {
    throw std::runtime_error(file + ": 'model' is not sensory or physical");
  }
  const std::filesystem::path params = dir / "fitted-params.json";
  if (!std::filesystem::exists(params)) throw std::runtime_error(params.string() + ": missing");
  const std::filesystem::path effects = dir / "fitted-effects.json";
  const bool has_effects = std::filesystem::exists(effects);
  FitResultFolder result{.dir = dir,
                         .params_path = params,
                         .effects_path = has_effects ? effects : std::filesystem::path(),
                         .model_kind = *kind,
                         .source = "",
                         .converged = false,
                         .termination = "",
                         .strokes = 0,
                         .fitted_window_rmse_rad_s = kNaN,
                         .held_out_window_rmse_rad_s = kNaN,
                         .model = load_model(*kind, params, has_effects ? effects : "")};
  const nlohmann::json& source = json_field(json, "source", file);
  if (!source.is_string()) throw std::runtime_error(file + ": 'source' is not a string");
  result.source = source.get<std::string>();
  const nlohmann::json& converged = json_field(json, "converged", file);
  if (!converged.is_boolean()) throw std::runtime_error(file + ": 'converged' is not true/false");
  result.converged = converged.get<bool>();
  const nlohmann::json& termination = json_field(json, "termination", file);
  if (termination.is_string()) result.termination = termination.get<std::string>();
  const nlohmann::json& strokes = json_field(json, "strokes", file);
  if (!strokes.is_number_integer()) throw std::runtime_error(file + ": 'strokes' is not a count");
  result.strokes = strokes.get<int>();
  result.fitted_window_rmse_rad_s = window_rmse(json, "fitted", file);
  result.held_out_window_rmse_rad_s = window_rmse(json, "held_out", file);
  return result;
}

std::string FitResultFolder::description() const {
  char rmse[120];
  if (std::isfinite(held_out_window_rmse_rad_s)) {
    std::snprintf(rmse, sizeof rmse, "window RMSE %.4g rad/s fitted, %.4g held out",
                  fitted_window_rmse_rad_s, held_out_window_rmse_rad_s);
  } else {
    std::snprintf(rmse, sizeof rmse, "window RMSE %.4g rad/s fitted", fitted_window_rmse_rad_s);
  }
  return std::string(to_string(model_kind))
      .append(" fit ")
      .append(dir.string())
      .append(" (")
      .append(converged ? "converged" : "NOT converged")
      .append(", ")
      .append(std::to_string(strokes))
      .append(" strokes, ")
      .append(rmse)
      .append(")");
}

}  // namespace doorbench
