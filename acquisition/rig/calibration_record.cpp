#include "acquisition/rig/calibration_record.h"

#include <cmath>
#include <ctime>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/time_text.h"

namespace doorbench {

const CalibrationQuantity* CalibrationRecord::quantity(std::string_view name) const {
  for (const CalibrationQuantity& q : quantities) {
    if (q.name == name) return &q;
  }
  return nullptr;
}

double CalibrationRecord::apply(double input) const {
  double value = 0.0;  // Horner, from the highest power down
  for (auto it = coefficients.rbegin(); it != coefficients.rend(); ++it)
    value = value * input + *it;
  return value;
}

std::string CalibrationRecord::unit_problem(std::string_view input, std::string_view output) const {
  if (unit != output) return "record " + id + " gives " + unit + ", not " + std::string(output);
  if (!input.empty() && input_unit != input) {
    return "record " + id + " takes " + input_unit + ", not " + std::string(input);
  }
  return "";
}

CalibrationRecord linear_record(std::string id, std::string input_unit, std::string unit,
                                double gain, double offset, std::string method) {
  if (!std::isfinite(gain) || !std::isfinite(offset) || gain == 0.0) {
    throw std::invalid_argument(
        "a linear record needs a finite gain other than 0 and a finite offset");
  }
  CalibrationRecord record;
  record.id = std::move(id);
  record.sensor_kind = "scale";
  record.input_unit = std::move(input_unit);
  record.unit = std::move(unit);
  record.coefficients = {offset, gain};
  record.method = std::move(method);
  record.date_utc = utc_now_iso8601();
  return record;
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
  if (!std::isfinite(delay_s)) return "calibration record " + id + ": delay_s is not finite";
  if (!(delay_standard_uncertainty_s >= 0)) {
    return "calibration record " + id + ": delay_standard_uncertainty_s must be >= 0";
  }
  if (std::isnan(valid_min) || std::isnan(valid_max) || !(valid_min < valid_max)) {
    return "calibration record " + id + ": valid_min must be below valid_max";
  }
  if (!valid_until_utc.empty()) {
    if (std::string problem = iso8601_utc_problem(valid_until_utc); !problem.empty()) {
      return "calibration record " + id + ": valid_until_utc: " + problem;
    }
  }
  for (const CalibrationPoint& p : points) {
    if (!std::isfinite(p.reference) || !std::isfinite(p.signal)) {
      return "calibration record " + id + ": a point's reference or signal is not finite";
    }
  }
  return "";
}

std::string new_valid_until_problem(const std::string& valid_until, const std::string& now_utc) {
  if (std::string problem = iso8601_utc_problem(valid_until); !problem.empty()) return problem;
  const std::string today = now_utc.substr(0, 10);
  if (valid_until.compare(0, 10, today) < 0) {
    return valid_until + " is before today (" + today +
           "): the record would have expired when made";
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
  // The fields added with the procedures only when set, so that records made before them
  // (and nominal ones) keep their short form.
  if (!r.supersedes.empty()) json["supersedes"] = r.supersedes;
  if (!r.references.empty()) json["references"] = r.references;
  if (!r.points.empty()) {
    nlohmann::ordered_json points = nlohmann::ordered_json::array();
    for (const CalibrationPoint& p : r.points) {
      points.push_back({{"reference", p.reference},
                        {"signal", p.signal},
                        {"signal_std", p.signal_std},
                        {"samples", p.samples},
                        {"residual", p.residual},
                        {"branch", p.branch}});
    }
    json["points"] = std::move(points);
  }
  if (!r.quantities.empty()) {
    nlohmann::ordered_json quantities = nlohmann::ordered_json::array();
    for (const CalibrationQuantity& q : r.quantities) {
      quantities.push_back({{"name", q.name},
                            {"value", q.value},
                            {"standard_uncertainty", q.standard_uncertainty},
                            {"unit", q.unit}});
    }
    json["quantities"] = std::move(quantities);
  }
  if (r.delay_s != 0.0 || r.delay_standard_uncertainty_s != 0.0) {
    json["delay_s"] = r.delay_s;
    json["delay_standard_uncertainty_s"] = r.delay_standard_uncertainty_s;
  }
  // JSON has no infinity: an unstated end of the range is left out.
  if (std::isfinite(r.valid_min)) json["valid_min"] = r.valid_min;
  if (std::isfinite(r.valid_max)) json["valid_max"] = r.valid_max;
  return json.dump(2);
}

CalibrationRecord calibration_record_from_json(std::string_view json_text,
                                               std::string_view source) {
  const std::string where(source);
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(json_text.begin(), json_text.end());
  } catch (const nlohmann::json::exception& error) {  // also numbers beyond a double
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
  text("supersedes", r.supersedes, false);
  text("references", r.references, false);
  auto number = [&](const nlohmann::json& object, const char* key, double& into,
                    const std::string& path) {
    if (!object.contains(key)) return;
    if (!object[key].is_number())
      throw std::runtime_error(where + ": " + path + key + " must be a number");
    into = object[key].get<double>();
  };
  number(json, "delay_s", r.delay_s, "");
  number(json, "delay_standard_uncertainty_s", r.delay_standard_uncertainty_s, "");
  number(json, "valid_min", r.valid_min, "");
  number(json, "valid_max", r.valid_max, "");
  auto array_of_objects = [&](const char* key) {
    if (!json.contains(key)) return nlohmann::json::array();
    if (!json[key].is_array()) throw std::runtime_error(where + ": " + key + " must be an array");
    for (const auto& element : json[key]) {
      if (!element.is_object()) {
        throw std::runtime_error(where + ": " + key + " must be an array of objects");
      }
    }
    return json[key];
  };
  auto element_text = [&](const nlohmann::json& object, const char* key, std::string& into,
                          const std::string& path) {
    if (!object.contains(key)) return;
    if (!object[key].is_string())
      throw std::runtime_error(where + ": " + path + key + " must be text");
    into = object[key].get<std::string>();
  };
  const nlohmann::json points = array_of_objects("points");
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string path = "points[" + std::to_string(i) + "].";
    CalibrationPoint p;
    double samples = 0.0;
    number(points[i], "reference", p.reference, path);
    number(points[i], "signal", p.signal, path);
    number(points[i], "signal_std", p.signal_std, path);
    number(points[i], "samples", samples, path);
    number(points[i], "residual", p.residual, path);
    element_text(points[i], "branch", p.branch, path);
    p.samples = static_cast<int>(samples);
    r.points.push_back(std::move(p));
  }
  const nlohmann::json quantities = array_of_objects("quantities");
  for (std::size_t i = 0; i < quantities.size(); ++i) {
    const std::string path = "quantities[" + std::to_string(i) + "].";
    CalibrationQuantity q;
    element_text(quantities[i], "name", q.name, path);
    number(quantities[i], "value", q.value, path);
    number(quantities[i], "standard_uncertainty", q.standard_uncertainty, path);
    element_text(quantities[i], "unit", q.unit, path);
    r.quantities.push_back(std::move(q));
  }
  if (std::string problem = r.validate(); !problem.empty()) {
    throw std::runtime_error(where + ": " + problem);
  }
  return r;
}

}  // namespace doorbench
