#include "viewer/fit_result.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "analysis/model/parameter_file.h"
#include "core/numbers.h"
#include "viewer/json_field.h"

namespace doorbench::viewer {

namespace {



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

FitResultFolder read_fit_result(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) {
    throw std::runtime_error(dir.string() + ": not a folder (expected a `doorbench fit` --out)");
  }
  const std::filesystem::path result_path = dir / "result.json";
  std::ifstream in(result_path);
  if (!in) throw std::runtime_error(result_path.string() + ": cannot open");
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& error) {
    throw std::runtime_error(result_path.string() + ": not JSON (" + error.what() + ")");
  }
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

}  // namespace doorbench::viewer
