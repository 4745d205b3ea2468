#include "analysis/fit/commanded_torque.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "acquisition/session/session_file.h"
#include "analysis/fit/fit_problem.h"
#include "core/numbers.h"

namespace doorbench {

namespace {

bool is_inertia(const std::string& name) {
  return name == "J_d" || name == "J";
}

}  // namespace

std::optional<CommandedTorque> read_commanded_torque(const std::filesystem::path& session_path,
                                                     int decimation) {
  if (decimation < 1) throw std::invalid_argument("read_commanded_torque: decimation must be >= 1");
  const SessionReader reader(session_path);
  const auto has = [&](const char* name) {
    return std::any_of(reader.channels().begin(), reader.channels().end(),
                       [&](const ChannelInfo& info) { return info.name == name; });
  };
  if (!has("model_torque") || !has("angle") || !has("rate")) return std::nullopt;
  const auto values = [&](const char* name) { return reader.physical(name, reader.read(name)); };
  const std::vector<double> theta = values("angle");
  const std::vector<double> omega = values("rate");
  const std::vector<double> torque = values("model_torque");
  if (theta.size() != omega.size() || theta.size() != torque.size()) {
    throw std::invalid_argument(session_path.string() +
                                ": the angle, rate and model_torque channels differ in length (" +
                                std::to_string(theta.size()) + ", " + std::to_string(omega.size()) +
                                ", " + std::to_string(torque.size()) + " samples)");
  }
  CommandedTorque out;
  out.source = session_path.string();
  out.decimation = decimation;
  for (std::size_t i = 0; i < theta.size(); i += static_cast<std::size_t>(decimation)) {
    if (!std::isfinite(theta[i]) || !std::isfinite(omega[i]) || !std::isfinite(torque[i])) {
      continue;
    }
    out.theta_rad.push_back(theta[i]);
    out.omega_rad_s.push_back(omega[i]);
    out.torque_Nm.push_back(torque[i]);
  }
  return out;
}

CommandedTorqueFit fit_commanded_torque(const DoorModel& start,
                                        const std::vector<CommandedTorque>& data,
                                        const std::vector<std::string>& free,
                                        const std::vector<ParameterPrior>& priors,
                                        const FitOptions& options, double torque_scale_Nm) {
  if (!(torque_scale_Nm > 0) || !std::isfinite(torque_scale_Nm)) {
    throw std::invalid_argument("commanded-torque fit: torque_scale_Nm must be > 0");
  }
  // The torques as strokes of the equation-error problem: force −τ_cmd / r_h makes its
  // residual τ_cmd − τ_m(θ, ω) once dω/dt is taken as zero.
  PreparedData strokes;
  const double radius = start.geometry().handle_radius_m;
  strokes.handle_radius_m = radius;
  int samples = 0;
  for (const CommandedTorque& part : data) {
    if (part.theta_rad.size() != part.omega_rad_s.size() ||
        part.theta_rad.size() != part.torque_Nm.size()) {
      throw std::invalid_argument("commanded-torque fit: " + part.source +
                                  ": angle, rate and torque differ in length");
    }
    if (part.theta_rad.empty()) continue;
    Stroke stroke;
    stroke.id = static_cast<int>(strokes.strokes.size()) + 1;
    stroke.theta_rad = part.theta_rad;
    stroke.omega_rad_s = part.omega_rad_s;
    for (std::size_t i = 0; i < part.torque_Nm.size(); ++i) {
      stroke.time_s.push_back(static_cast<double>(i));
      stroke.force_N.push_back(-part.torque_Nm[i] / radius);
    }
    samples += static_cast<int>(stroke.size());
    strokes.strokes.push_back(std::move(stroke));
  }
  if (samples == 0) throw std::invalid_argument("commanded-torque fit: no samples");

  ParameterMap map;
  map.base_values.assign(start.parameter_values().begin(), start.parameter_values().end());
  const auto bounds = start.parameter_bounds();
  for (const std::string& name : free) {
    const std::optional<int> index = start.find_parameter(name);
    if (!index) {
      throw std::invalid_argument("commanded-torque fit: the model has no parameter '" + name +
                                  "'");
    }
    if (is_inertia(name)) {
      throw std::invalid_argument("commanded-torque fit: '" + name +
                                  "' is the inertia, which the commanded torque does not contain");
    }
    map.free_index.push_back(*index);
    map.scale.push_back(parameter_scale(map.base_values[*index], bounds[*index]));
  }
  if (map.free_index.empty()) {
    throw std::invalid_argument("commanded-torque fit: no free parameter");
  }
  std::vector<PriorResidual> prior_residuals;
  for (const ParameterPrior& prior : priors) {
    const auto position = std::find_if(map.free_index.begin(), map.free_index.end(), [&](int i) {
      return start.parameter_name(i) == prior.parameter;
    });
    if (position == map.free_index.end()) continue;  // on a parameter not fitted here
    const std::size_t k = static_cast<std::size_t>(position - map.free_index.begin());
    prior_residuals.push_back(
        {static_cast<int>(k), prior.center / map.scale[k], prior.sigma / map.scale[k]});
  }

  const TorqueMapOutcome outcome =
      solve_torque_map(start, strokes, map, solver_settings(options), map.scaled(map.base_values),
                       prior_residuals, torque_scale_Nm);
  if (!outcome.usable) {
    throw std::runtime_error("commanded-torque fit: the solver failed (" + outcome.termination +
                             ")");
  }
  CommandedTorqueFit fit(start.with_parameter_values(map.values(outcome.x.data())));
  const int p = map.free_count();
  fit.samples = samples;
  fit.iterations = outcome.iterations;
  fit.converged = outcome.converged;
  fit.termination = outcome.termination;
  fit.data_cost = 0.5 * outcome.sum_of_squares;
  fit.rms_error_Nm = torque_scale_Nm * std::sqrt(outcome.sum_of_squares / samples);
  fit.reduced_data_cost = samples > p ? outcome.sum_of_squares / (samples - p) : kNaN;
  fit.uncertainty.assign(start.parameter_count(), kNaN);
  const Eigen::MatrixXd covariance =
      outcome.information.completeOrthogonalDecomposition().pseudoInverse();
  for (int k = 0; k < p; ++k) {
    const double variance = covariance(k, k) * std::max(fit.reduced_data_cost, 0.0);
    fit.uncertainty[map.free_index[k]] = std::sqrt(std::max(variance, 0.0)) * map.scale[k];
  }
  return fit;
}

}  // namespace doorbench
