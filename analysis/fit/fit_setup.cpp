// The set-up of a fit (internal/fit_setup.h), and default_free_parameters() and
// parameter_scale(), which it and the callers of fit_model() share.
#include "analysis/fit/internal/fit_setup.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "analysis/fit/fit_start.h"
#include "analysis/model/sensory_model.h"
#include "core/number_format.h"

namespace doorbench {

std::vector<std::string> default_free_parameters(const DoorModel& model) {
  std::vector<std::string> names;
  for (int i = 0; i < model.parameter_count(); ++i) {
    const std::string& name = model.parameter_name(i);
    if (name == "k_stop" || name == "c_stop") continue;
    if (model.kind() == ModelKind::kSensory && (name == "beta" || name == "beta_f")) continue;
    names.push_back(name);
  }
  return names;
}

double parameter_scale(double start, const Bounds& bounds) {
  const double width = bounds.upper - bounds.lower;
  const bool usable_width = std::isfinite(width) && width > 0;
  if (std::abs(start) > 0 && (!usable_width || std::abs(start) >= 1e-3 * width)) {
    return std::abs(start);
  }
  if (usable_width) return 0.1 * width;
  return 1.0;
}

namespace {

std::string parameter_list(const DoorModel& model) {
  std::string list;
  for (int i = 0; i < model.parameter_count(); ++i) {
    if (i > 0) list += ", ";
    list += model.parameter_name(i);
  }
  return list;
}

int find_or_throw(const DoorModel& model, const std::string& name, const char* option) {
  const std::optional<int> index = model.find_parameter(name);
  if (!index) {
    throw std::invalid_argument("fit: " + std::string(option) + " names '" + name +
                                "', which the " + std::string(to_string(model.kind())) +
                                " model does not have (its parameters: " + parameter_list(model) +
                                ")");
  }
  return *index;
}

std::vector<int> resolve_free(const DoorModel& model, const FitOptions& options) {
  const std::vector<std::string> names =
      options.free_parameters.empty() ? default_free_parameters(model) : options.free_parameters;
  std::vector<char> free(model.parameter_count(), 0);
  for (const std::string& name : names) free[find_or_throw(model, name, "free_parameters")] = 1;
  for (const std::string& name : options.fixed_parameters) {
    free[find_or_throw(model, name, "fixed_parameters")] = 0;
  }
  std::vector<int> indices;
  for (int i = 0; i < model.parameter_count(); ++i) {
    if (free[i]) indices.push_back(i);
  }
  if (indices.empty()) throw std::invalid_argument("fit: no parameter is free");
  return indices;
}

// Replaces the start's free latch values with those read off the data, when they keep
// every constraint. Records the origin of each value.
void apply_latch_read_off(const DoorModel& start, const LatchReadOff& read,
                          const std::vector<int>& free_index, std::vector<double>& values,
                          std::vector<std::string>& origin, std::vector<std::string>& notes) {
  const std::pair<int, std::optional<double>> readings[] = {
      {sensory::kTheta0, read.theta0_rad},     {sensory::kTheta1, read.theta1_rad},
      {sensory::kTheta2, read.theta2_rad},     {sensory::kTheta3, read.theta3_rad},
      {sensory::kKInf, read.k_inf_Nm_per_rad}, {sensory::kKLock, read.k_lock_Nm_per_rad}};
  std::vector<double> trial = values;
  std::vector<int> replaced;
  const auto bounds = start.parameter_bounds();
  for (const auto& [index, reading] : readings) {
    if (!reading || std::find(free_index.begin(), free_index.end(), index) == free_index.end()) {
      continue;
    }
    trial[index] = std::clamp(*reading, bounds[index].lower, bounds[index].upper);
    replaced.push_back(index);
  }
  if (replaced.empty()) return;
  // When only one side of the latch was read (no stroke unlatched from closed, say), the
  // angles not read keep their proportion to those read: a start latch scaled to the data
  // instead of one that crosses it (θ1 above the θ2 read off, and the reading discarded).
  const bool opening_read = read.theta1_rad.has_value();
  std::vector<int> scaled;
  const bool closing_read = read.theta2_rad.has_value();
  const auto scale_free = [&](std::initializer_list<int> indices, double factor) {
    for (int index : indices) {
      if (std::find(free_index.begin(), free_index.end(), index) == free_index.end()) continue;
      trial[index] = std::clamp(values[index] * factor, bounds[index].lower, bounds[index].upper);
      scaled.push_back(index);
    }
  };
  if (closing_read && !opening_read && !(trial[sensory::kTheta1] < trial[sensory::kTheta2])) {
    scale_free({sensory::kTheta0, sensory::kTheta1},
               trial[sensory::kTheta2] / values[sensory::kTheta2]);
  } else if (opening_read && !closing_read &&
             !(trial[sensory::kTheta1] < trial[sensory::kTheta2])) {
    scale_free({sensory::kTheta2, sensory::kTheta3},
               trial[sensory::kTheta1] / values[sensory::kTheta1]);
  }
  try {
    (void)start.with_parameter_values(trial);
  } catch (const std::invalid_argument& error) {
    notes.push_back(std::string("the latch read off the data was not used: ") + error.what());
    return;
  }
  values = trial;
  for (int index : replaced) origin[index] = "read off the data";
  // Shown as "start <origin>" in the report's status column.
  for (int index : scaled) origin[index] = "scaled to the latch read off";
}

}  // namespace

namespace fit_detail {

void check_data(const PreparedData& data, const DoorModel& model) {
  if (data.strokes.empty()) throw std::invalid_argument("fit: the data has no strokes");
  for (const Stroke& stroke : data.strokes) {
    const std::string which = "fit: stroke " + std::to_string(stroke.id);
    const std::size_t n = stroke.time_s.size();
    if (stroke.force_N.size() != n || stroke.theta_rad.size() != n ||
        stroke.omega_rad_s.size() != n) {
      throw std::invalid_argument(which + ": time, force, angle and rate differ in length");
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(stroke.time_s[i]) || !std::isfinite(stroke.force_N[i]) ||
          !std::isfinite(stroke.theta_rad[i]) || !std::isfinite(stroke.omega_rad_s[i])) {
        throw std::invalid_argument(which + ": sample " + std::to_string(i) + " is not finite");
      }
      if (i > 0 && !(stroke.time_s[i] > stroke.time_s[i - 1])) {
        throw std::invalid_argument(which + ": time does not increase at sample " +
                                    std::to_string(i));
      }
    }
  }
  const double model_radius = model.geometry().handle_radius_m;
  if (data.handle_radius_m > 0 &&
      std::abs(data.handle_radius_m - model_radius) > 1e-6 * model_radius) {
    throw std::invalid_argument("fit: the data's handle radius (" +
                                format_number(data.handle_radius_m) +
                                " m) differs from the model's (" + format_number(model_radius) +
                                " m); build the model with the bench's geometry");
  }
}

FitWeights resolve_weights(const FitOptions& options, const PreparedData& data,
                           std::vector<std::string>& notes) {
  FitWeights weights;
  weights.angle_residuals = options.angle_residuals;
  weights.rate_noise_rad_s = options.rate_noise_rad_s > 0 ? options.rate_noise_rad_s
                             : data.rate_noise_rad_s > 0  ? data.rate_noise_rad_s
                                                          : kBenchRateNoise_rad_s;
  weights.angle_noise_rad = options.angle_noise_rad > 0 ? options.angle_noise_rad
                            : data.angle_noise_rad > 0  ? data.angle_noise_rad
                                                        : kBenchAngleNoise_rad;
  if (options.rate_noise_rad_s == 0 && !(data.rate_noise_rad_s > 0)) {
    notes.push_back("the data gives no rate noise level: sigma_omega is the bench's");
  }
  if (options.angle_noise_rad == 0 && !(data.angle_noise_rad > 0)) {
    notes.push_back("the data gives no angle noise level: sigma_theta is the bench's");
  }
  return weights;
}

StartValues start_values(const DoorModel& start, const PreparedData& data,
                         const FitOptions& options, const FitWeights& weights,
                         FitSummary& summary) {
  StartValues chosen;
  chosen.free_index = resolve_free(start, options);
  const std::vector<int>& free_index = chosen.free_index;
  std::vector<double>& values = chosen.values;
  std::vector<std::string>& origin = chosen.origin;
  values.assign(start.parameter_values().begin(), start.parameter_values().end());
  origin.assign(static_cast<std::size_t>(start.parameter_count()), "start model");
  if (options.latch_start_from_data && start.kind() == ModelKind::kSensory) {
    summary.latch_start = read_latch_start(data, start, weights.rate_noise_rad_s);
    for (const std::string& note : summary.latch_start.notes) summary.notes.push_back(note);
    apply_latch_read_off(start, summary.latch_start, free_index, values, origin, summary.notes);
  }
  const auto bounds = start.parameter_bounds();
  for (int index : free_index) {
    const double clamped = std::clamp(values[index], bounds[index].lower, bounds[index].upper);
    if (clamped != values[index]) {
      values[index] = clamped;
      origin[index] = "clamped into bounds";
      summary.notes.push_back("the start of " + start.parameter_name(index) +
                              " lay outside its bounds and was moved onto the nearer one");
    }
  }
  return chosen;
}

DoorModel checked_start_model(const DoorModel& start, const std::vector<double>& values) {
  try {
    return start.with_parameter_values(values);
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(std::string("fit: the start breaks a constraint: ") + error.what());
  }
}

// The solver's map of the free parameters, and the priors on them in its units.
ParameterMap make_map(const DoorModel& start, const StartValues& chosen, const FitOptions& options,
                      FitWeights& weights, FitSummary& summary) {
  const std::vector<int>& free_index = chosen.free_index;
  const auto bounds = start.parameter_bounds();
  ParameterMap map;
  map.base_values = chosen.values;
  map.free_index = free_index;
  for (int index : free_index) {
    map.scale.push_back(parameter_scale(chosen.values[index], bounds[index]));
  }
  summary.free_parameters = map.free_count();
  for (int index : free_index) summary.free_names.push_back(start.parameter_name(index));
  for (const ParameterPrior& prior : options.priors) {
    const int index = find_or_throw(start, prior.parameter, "priors");
    const auto position = std::find(free_index.begin(), free_index.end(), index);
    if (position == free_index.end()) continue;
    const std::size_t k = static_cast<std::size_t>(position - free_index.begin());
    weights.priors.push_back(
        {static_cast<int>(k), prior.center / map.scale[k], prior.sigma / map.scale[k]});
  }

  return map;
}

}  // namespace fit_detail

}  // namespace doorbench
