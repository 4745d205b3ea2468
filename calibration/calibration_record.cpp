#include "calibration/calibration_record.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace doorbench::calibration {

double CalibrationRecord::apply(double input) const {
  double value = 0.0;  // Horner, from the highest power down
  for (auto it = coefficients.rbegin(); it != coefficients.rend(); ++it)
    value = value * input + *it;
  return value;
}

std::string CalibrationRecord::validate() const {
  if (id.empty()) return "calibration record: id is empty";
  if (unit.empty()) return "calibration record " + id + ": unit is empty";
  if (coefficients.size() < 2) {
    return "calibration record " + id + ": coefficients needs at least offset and gain";
  }
  for (double c : coefficients) {
    if (!std::isfinite(c)) return "calibration record " + id + ": a coefficient is not finite";
  }
  if (!(standard_uncertainty >= 0)) {
    return "calibration record " + id + ": standard_uncertainty must be >= 0";
  }
  return "";
}

std::string to_json(const CalibrationRecord& r) {
  nlohmann::ordered_json json = {
      {"id", r.id},
      {"version", r.version},
      {"sensor_kind", r.sensor_kind},
      {"sensor_serial", r.sensor_serial},
      {"input_unit", r.input_unit},
      {"unit", r.unit},
      {"coefficients", r.coefficients},
      {"standard_uncertainty", r.standard_uncertainty},
      {"method", r.method},
      {"date_utc", r.date_utc},
      {"operator", r.operator_name},
      {"valid_until_utc", r.valid_until_utc},
      {"notes", r.notes},
  };
  return json.dump(2);
}

CalibrationRecord calibration_record_from_json(std::string_view json_text,
                                               std::string_view source) {
  const std::string where(source);
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(json_text.begin(), json_text.end());
  } catch (const nlohmann::json::parse_error& error) {
    throw std::runtime_error(where + ": calibration record is not valid JSON: " + error.what());
  }
  if (!json.is_object()) throw std::runtime_error(where + ": calibration record must be an object");
  CalibrationRecord r;
  auto text = [&](const char* key, std::string& into, bool required) {
    if (!json.contains(key)) {
      if (required) throw std::runtime_error(where + ": calibration record lacks " + key);
      return;
    }
    if (!json[key].is_string()) throw std::runtime_error(where + ": " + key + " must be text");
    into = json[key].get<std::string>();
  };
  text("id", r.id, true);
  text("sensor_kind", r.sensor_kind, false);
  text("sensor_serial", r.sensor_serial, false);
  text("input_unit", r.input_unit, false);
  text("unit", r.unit, true);
  text("method", r.method, false);
  text("date_utc", r.date_utc, false);
  text("operator", r.operator_name, false);
  text("valid_until_utc", r.valid_until_utc, false);
  text("notes", r.notes, false);
  if (json.contains("version")) {
    if (!json["version"].is_number_integer())
      throw std::runtime_error(where + ": version must be an integer");
    r.version = json["version"].get<int>();
  }
  if (!json.contains("coefficients") || !json["coefficients"].is_array()) {
    throw std::runtime_error(where + ": calibration record lacks coefficients (an array)");
  }
  for (const auto& c : json["coefficients"]) {
    if (!c.is_number()) throw std::runtime_error(where + ": coefficients must be numbers");
    r.coefficients.push_back(c.get<double>());
  }
  if (json.contains("standard_uncertainty")) {
    if (!json["standard_uncertainty"].is_number()) {
      throw std::runtime_error(where + ": standard_uncertainty must be a number");
    }
    r.standard_uncertainty = json["standard_uncertainty"].get<double>();
  }
  if (std::string problem = r.validate(); !problem.empty()) {
    throw std::runtime_error(where + ": " + problem);
  }
  return r;
}

}  // namespace doorbench::calibration
