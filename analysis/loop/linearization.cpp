// The residual examination's linearized window simulation (internal/linearization.h).
#include "analysis/loop/internal/linearization.h"

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/loop/internal/loop_common.h"
#include "analysis/model/physical_model.h"
#include "analysis/model/sensory_model.h"

namespace doorbench::loop_detail {

namespace {

// The median of a χ² variable of one degree of freedom over its mean.
constexpr double kChiSquare1Median = 0.454936;

// The forcing φ of the linearized window equations per unit amplitude, J ∂(dω/dt)/∂a: the
// effect's torque at amplitude 1, or for the inertia error −dω̂/dt (dω/dt = τ/(J + ΔJ)).
double unit_forcing(const Regressor& regressor, const DoorModel& model,
                    const effects::BaseFriction<double>& friction, double theta, double omega,
                    double acceleration) {
  if (regressor.kind == effects::Kind::kInertiaError) return -acceleration;
  return effects::torque(regressor.kind, regressor.unit_values.data(), friction,
                         model.geometry().handle_radius_m, theta, omega);
}

// A column of the linearized window simulation: the sensitivity (δθ, δω) of the simulated
// state to one quantity, driven by a torque-like forcing (see examine()).
struct Sensitivity {
  double d_theta = 0.0, d_omega = 0.0, forcing = 0.0;
};

// One window's differences e_j − e_{j−k}, each taken about the window's own mean difference
// (a model error that grows steadily along the window differs by about the same amount at
// every sample, noise does not); close() adds their squares to the examination's list.
struct LagDifferences {
  std::vector<double> differences;
  void add(double difference) { differences.push_back(difference); }
  void close(std::vector<double>& squares) {
    if (differences.size() < 2) return;
    double mean = 0.0;
    for (double d : differences) mean += d;
    mean /= static_cast<double>(differences.size());
    const double correction =
        static_cast<double>(differences.size()) / static_cast<double>(differences.size() - 1);
    for (double d : differences) squares.push_back((d - mean) * (d - mean) * correction);
    differences.clear();
  }
};

// The variance of Gaussian differences from the median of their squares (the median of a
// χ²₁ variable is 0.4549 times its mean): the samples where a wrong model's error changes
// abruptly (a latch it lacks) are few and leave the median alone.
double robust_variance(std::vector<double>& squares) {
  if (squares.empty()) return 0.0;
  const auto middle = squares.begin() + static_cast<std::ptrdiff_t>(squares.size() / 2);
  std::nth_element(squares.begin(), middle, squares.end());
  return *middle / kChiSquare1Median;
}

}  // namespace

effects::BaseFriction<double> base_friction(const DoorModel& model) {
  const auto p = model.parameter_values();
  if (model.kind() == ModelKind::kSensory) return {p[sensory::kD1], p[sensory::kS]};
  return {p[physical::kTh], 1.0 / p[physical::kWf]};
}

std::vector<Regressor> make_regressors(const DoorModel& model, const PreparedData& data,
                                       const std::vector<effects::Kind>& kinds,
                                       const LoopOptions& options) {
  const effects::BaseFriction<double> friction = base_friction(model);
  double theta_low = std::numeric_limits<double>::infinity();
  double theta_high = -theta_low;
  for (const Stroke& stroke : data.strokes) {
    for (double theta : stroke.theta_rad) {
      theta_low = std::min(theta_low, theta);
      theta_high = std::max(theta_high, theta);
    }
  }
  std::vector<Regressor> regressors;
  for (effects::Kind kind : kinds) {
    const effects::EffectInfo& info = effects::info(kind);
    std::vector<double> defaults;
    for (const effects::EffectParameter& parameter : info.parameters) {
      defaults.push_back(parameter.default_value);
    }
    const Bounds amplitude_bounds = info.parameters[0].default_bounds;
    auto add = [&](std::vector<double> values, double offset, std::string scan) {
      Regressor regressor;
      regressor.kind = kind;
      values[0] = offset + 1.0;
      regressor.unit_values = std::move(values);
      regressor.amplitude_offset = offset;
      regressor.lower = amplitude_bounds.lower - offset;
      regressor.upper = amplitude_bounds.upper - offset;
      regressor.scan = std::move(scan);
      regressors.push_back(std::move(regressor));
    };
    switch (kind) {
      case effects::Kind::kStribeck:
        for (double speed : options.stribeck_speeds_rad_s) {
          add({0.0, speed}, friction.level_Nm, "w_s = " + number(speed) + " rad/s");
        }
        break;
      case effects::Kind::kSoftClose:
        for (double angle : options.soft_close_angles_rad) {
          for (double sharpness : options.soft_close_sharpness_per_rad) {
            add({0.0, angle, sharpness}, 0.0,
                "theta_sc = " + number(angle) + " rad, beta_sc = " + number(sharpness) + " 1/rad");
          }
        }
        break;
      case effects::Kind::kEndStop: {
        const Bounds angle_bounds = info.parameters[1].default_bounds;
        const int count = options.end_stop_angles;
        for (int k = 0; k < count && std::isfinite(theta_low); ++k) {
          const double angle =
              std::clamp(theta_low + (theta_high - theta_low) * k / static_cast<double>(count),
                         angle_bounds.lower, angle_bounds.upper);
          add({0.0, angle, defaults[2]}, 0.0, "theta_e = " + number(angle) + " rad");
        }
        break;
      }
      default:
        add(defaults, 0.0, "");
        break;
    }
  }
  return regressors;
}

// The noise floor from the lag differences (ResidualExamination::noise_floor_rad_s).
void estimate_noise_floor(Linearization& linear, ResidualExamination& examination) {
  if (linear.lag1_squares.empty() || linear.lag2_squares.empty() || linear.samples == 0) return;
  const double lag1 = robust_variance(linear.lag1_squares);  // q + 2σ²
  const double lag2 = robust_variance(linear.lag2_squares);  // 2q + 2σ²
  const double walk = std::max(0.0, lag2 - lag1);
  const double white = std::max(0.0, 0.5 * (lag1 - walk));
  const double mean_index = linear.index_sum / static_cast<double>(linear.samples);
  examination.white_noise_rad_s = std::sqrt(white);
  examination.walk_per_sample_rad_s = std::sqrt(walk);
  examination.noise_floor_rad_s = std::sqrt(white + walk * mean_index);
}

namespace {

// ∂τ/∂p of the free parameters `free` (model indices) at one state, the linearization's
// parameter forcings: J ∂(dω/dt)/∂p, and −dω/dt for an inertia. Eight parameters per
// evaluation: a Jet's parts are computed one by one, so each is bit for bit what a
// one-part Jet seeded on that parameter alone gives.
class ParameterForcings {
 public:
  ParameterForcings(const DoorModel& model, const std::vector<int>& free)
      : model_(model),
        free_(free),
        is_inertia_(free.size(), 0),
        parameters_(model.parameter_values().begin(), model.parameter_values().end()),
        values_(free.size(), 0.0) {
    for (std::size_t k = 0; k < free.size(); ++k) {
      const std::string& name = model.parameter_name(free[k]);
      is_inertia_[k] = (model.kind() == ModelKind::kSensory && free[k] == sensory::kJ) ||
                       (model.kind() == ModelKind::kPhysical && free[k] == physical::kJd) ||
                       name == "inertia_error.delta_J";
    }
  }
  // The forcings at (θ, ω), where the door's acceleration is `acceleration`, by position in
  // `free` (valid until the next call).
  const std::vector<double>& compute(double theta, double omega, double acceleration) {
    const int count = static_cast<int>(free_.size());
    for (int first = 0; first < count; first += kParts) {
      const int last = std::min(count, first + kParts);
      for (int k = first; k < last; ++k) {
        if (!is_inertia_[k]) parameters_[free_[k]].v[k - first] = 1.0;
      }
      const Chunk torque = model_.evaluate(parameters_.data(), Chunk(theta), Chunk(omega), terms_);
      for (int k = first; k < last; ++k) {
        values_[k] = is_inertia_[k] ? -acceleration : torque.v[k - first];
        parameters_[free_[k]].v[k - first] = 0.0;
      }
    }
    return values_;
  }

 private:
  static constexpr int kParts = 8;
  using Chunk = ceres::Jet<double, kParts>;
  const DoorModel& model_;
  const std::vector<int>& free_;
  std::vector<char> is_inertia_;
  std::vector<Chunk> parameters_;
  Chunk terms_[DoorModel::kMaxTerms];
  std::vector<double> values_;
};

}  // namespace

// Along each window the simulated state (θ̂, ω̂) starts from the measured one. A change a
// of one quantity (an effect's amplitude, a parameter) changes it, to first order, by
// a·(δθ, δω) with
//   d(δθ)/dt = δω,  J d(δω)/dt = ∂τ/∂θ δθ + ∂τ/∂ω δω + φ(θ̂, ω̂),  δ = 0 at the start,
// φ the quantity's torque per unit (∂τ/∂a; for J and ΔJ, −dω̂/dt), with ∂τ from the current
// model along the simulation. δω is the column of the rate residual e = ω − ω̂; the
// trapezoidal rule integrates it (A-stable through the stiff latch). `parameters` are model
// indices: their forcing is the torque's derivative by forward-mode differentiation; J (and
// an inertia error) act through 1/J, like the inertia error.
Linearization linearize(const DoorModel& model, const PreparedData& data,
                        const WindowOptions& windows, const std::vector<int>& parameters,
                        const std::vector<Regressor>& regressors) {
  const WindowSimulation simulation = simulate_windows(model, data, windows);
  const effects::BaseFriction<double> friction = base_friction(model);
  const double inertia = model.inertia_kg_m2();
  const double handle_radius_m = model.geometry().handle_radius_m;

  const int free_count = static_cast<int>(parameters.size());
  ParameterForcings parameter_forcings(model, parameters);
  const int regressor_count = static_cast<int>(regressors.size());
  const int columns = free_count + regressor_count + 1;
  Linearization result;
  result.gram = Eigen::MatrixXd::Zero(columns, columns);
  Eigen::VectorXd row(columns);
  std::vector<Sensitivity> state(free_count + regressor_count);
  for (const FitWindow& window : split_windows(data, windows)) {
    const Stroke& stroke = data.strokes[window.stroke];
    const std::vector<double>& theta_sim = simulation.theta_rad[window.stroke];
    const std::vector<double>& omega_sim = simulation.omega_rad_s[window.stroke];
    bool usable = true;
    for (int j = 1; j < window.count && usable; ++j) {
      const int i = window.first + j;
      usable = std::isfinite(theta_sim[i]) && std::isfinite(omega_sim[i]);
    }
    if (!usable) {
      ++result.failed_windows;
      continue;
    }
    auto state_at = [&](int j, double& theta, double& omega) {
      const int i = window.first + j;
      theta = j == 0 ? stroke.theta_rad[i] : theta_sim[i];
      omega = j == 0 ? stroke.omega_rad_s[i] : omega_sim[i];
    };
    // Column c's forcing at (θ, ω) with the door's acceleration there: a parameter's from
    // `forcings`, parameter_forcings computed at that state.
    auto forcing_of = [&](int c, const std::vector<double>& forcings, double theta, double omega,
                          double acceleration) {
      return c < free_count ? forcings[c]
                            : unit_forcing(regressors[c - free_count], model, friction, theta,
                                           omega, acceleration);
    };
    double theta = 0.0, omega = 0.0;
    state_at(0, theta, omega);
    TorqueDerivatives derivatives = model.torque_derivatives(theta, omega);
    double acceleration =
        (handle_radius_m * stroke.force_N[window.first] + derivatives.torque_Nm) / inertia;
    const std::vector<double>& start_forcings =
        parameter_forcings.compute(theta, omega, acceleration);
    for (int c = 0; c < free_count + regressor_count; ++c) {
      state[c] = {0.0, 0.0, forcing_of(c, start_forcings, theta, omega, acceleration)};
    }
    Eigen::MatrixXd window_gram = Eigen::MatrixXd::Zero(columns, columns);
    double error_1 = 0.0, error_2 = 0.0;  // e_{j−1}, e_{j−2}
    LagDifferences lag1, lag2;
    for (int j = 1; j < window.count; ++j) {
      const int i = window.first + j;
      const double h = stroke.time_s[i] - stroke.time_s[i - 1];
      const double half_h = 0.5 * h;
      const double a_theta = derivatives.dtorque_dtheta_Nm_per_rad / inertia;
      const double a_omega = derivatives.dtorque_domega_Nm_s_per_rad / inertia;
      state_at(j, theta, omega);
      derivatives = model.torque_derivatives(theta, omega);
      acceleration = (handle_radius_m * stroke.force_N[i] + derivatives.torque_Nm) / inertia;
      const double b_theta = derivatives.dtorque_dtheta_Nm_per_rad / inertia;
      const double b_omega = derivatives.dtorque_domega_Nm_s_per_rad / inertia;
      const double determinant = (1.0 - half_h * b_omega) - half_h * half_h * b_theta;
      const std::vector<double>& forcings = parameter_forcings.compute(theta, omega, acceleration);
      const double error = stroke.omega_rad_s[i] - omega;
      result.rate_sum_of_squares += error * error;
      ++result.samples;
      result.index_sum += j;
      if (j >= 2) lag1.add(error - error_1);
      if (j >= 3) lag2.add(error - error_2);
      error_2 = error_1;
      error_1 = error;
      result.add_to_band(stroke.omega_rad_s[i], error);
      for (int c = 0; c < free_count + regressor_count; ++c) {
        Sensitivity& s = state[c];
        const double forcing = forcing_of(c, forcings, theta, omega, acceleration);
        const double rhs_theta = s.d_theta + half_h * s.d_omega;
        const double rhs_omega = s.d_omega + half_h * (a_theta * s.d_theta + a_omega * s.d_omega +
                                                       (s.forcing + forcing) / inertia);
        s.d_theta = (rhs_theta * (1.0 - half_h * b_omega) + half_h * rhs_omega) / determinant;
        s.d_omega = (rhs_omega + half_h * b_theta * rhs_theta) / determinant;
        s.forcing = forcing;
        row[c] = s.d_omega;
      }
      row[columns - 1] = error;
      if (!row.allFinite()) continue;
      window_gram.selfadjointView<Eigen::Upper>().rankUpdate(row);
    }
    lag1.close(result.lag1_squares);
    lag2.close(result.lag2_squares);
    window_gram = window_gram.selfadjointView<Eigen::Upper>();
    result.gram += window_gram;
    result.window_grams.push_back(std::move(window_gram));
  }
  return result;
}

std::pair<double, int> window_sum_of_squares(const DoorModel& model, const PreparedData& data,
                                             const WindowOptions& windows) {
  const WindowSimulation simulation = simulate_windows(model, data, windows);
  double sum = 0.0;
  int failed = 0;
  for (const FitWindow& window : split_windows(data, windows)) {
    const Stroke& stroke = data.strokes[window.stroke];
    const std::vector<double>& theta_sim = simulation.theta_rad[window.stroke];
    const std::vector<double>& omega_sim = simulation.omega_rad_s[window.stroke];
    double window_sum = 0.0;
    bool usable = true;
    for (int j = 1; j < window.count && usable; ++j) {
      const int i = window.first + j;
      usable = std::isfinite(theta_sim[i]) && std::isfinite(omega_sim[i]);
      const double error = stroke.omega_rad_s[i] - omega_sim[i];
      window_sum += error * error;
    }
    if (usable) {
      sum += window_sum;
    } else {
      ++failed;
    }
  }
  return {sum, failed};
}

}  // namespace doorbench::loop_detail
