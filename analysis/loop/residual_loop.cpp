#include "analysis/loop/residual_loop.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <exception>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fit_windows.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/physical_model.h"
#include "analysis/model/sensory_model.h"
#include "core/clock.h"
#include "core/number_format.h"
#include "core/parallel.h"

namespace doorbench {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The median of a χ² variable of one degree of freedom over its mean.
constexpr double kChiSquare1Median = 0.454936;
// An eigenvalue of the free parameters' scaled normal matrix below this share of the largest
// is a direction the data does not determine (left out of the projection); a regressor
// with less than this share of its norm left after the projection is indistinguishable
// from the free parameters.
constexpr double kProjectionRankTolerance = 1e-10;




// The threads for `count` refits: one each when they run at once (each refit is a fit of
// its own, so they balance as whole tasks), else the caller's alone.
int refit_threads(bool parallel, std::size_t count) {
  return parallel ? static_cast<int>(count) : 1;
}

// Four significant digits: the loop's tables and its reasons.
std::string number(double value) {
  return format_significant(value, 4);
}

std::string percent(double fraction) {
  if (!std::isfinite(fraction)) return "-";
  return printf_text("%.1f%%", 100.0 * fraction);
}

std::string signed_percent(double fraction) {
  if (!std::isfinite(fraction)) return "-";
  return printf_text("%+.1f%%", 100.0 * fraction);
}

bool finite_in(double value, double lower, double upper) {
  return std::isfinite(value) && value >= lower && value <= upper;
}

// Why a grid is unusable for an effect parameter (empty when usable).
std::string check_grid(const std::vector<double>& grid, const char* option, effects::Kind kind,
                       int parameter) {
  const effects::EffectParameter& info = effects::info(kind).parameters[parameter];
  if (grid.empty()) return std::string("loop ") + option + " must not be empty";
  for (double value : grid) {
    if (!finite_in(value, info.default_bounds.lower, info.default_bounds.upper) ||
        (info.minimum_is_strict && value <= info.minimum)) {
      return std::string("loop ") + option + " must lie within " + std::string(info.info.name) +
             "'s bounds [" + number(info.default_bounds.lower) + ", " +
             number(info.default_bounds.upper) + "] (got " + number(value) + ")";
    }
  }
  return "";
}

std::vector<effects::Kind> candidate_kinds(const DoorModel& model, const LoopOptions& options) {
  std::vector<effects::Kind> kinds;
  if (options.candidates.empty()) {
    for (const effects::EffectInfo& effect : effects::catalogue()) kinds.push_back(effect.kind);
  } else {
    kinds = options.candidates;
  }
  std::erase_if(kinds, [&](effects::Kind kind) { return model.has_effect(kind); });
  return kinds;
}

effects::BaseFriction<double> base_friction(const DoorModel& model) {
  const auto p = model.parameter_values();
  if (model.kind() == ModelKind::kSensory) return {p[sensory::kD1], p[sensory::kS]};
  return {p[physical::kTh], 1.0 / p[physical::kWf]};
}

// One regressor of the examination: an effect at fixed nonlinear parameters, whose
// amplitude (the first parameter, or d_s − d1 for Stribeck) is free.
struct Regressor {
  effects::Kind kind;
  std::vector<double> unit_values;  // the effect's parameters at amplitude 1
  double amplitude_offset = 0.0;    // parameter 0 = offset + amplitude (Stribeck: d1)
  double lower = 0.0, upper = 0.0;  // the amplitude's range (parameter 0's bounds − offset)
  std::string scan;
};

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

// The forcing φ of the linearized window equations per unit amplitude, J ∂(dω/dt)/∂a: the
// effect's torque at amplitude 1, or for the inertia error −dω̂/dt (dω/dt = τ/(J + ΔJ)).
double unit_forcing(const Regressor& regressor, const DoorModel& model,
                    const effects::BaseFriction<double>& friction, double theta, double omega,
                    double acceleration) {
  if (regressor.kind == effects::Kind::kInertiaError) return -acceleration;
  return effects::torque(regressor.kind, regressor.unit_values.data(), friction,
                         model.geometry().handle_radius_m, theta, omega);
}

}  // namespace

std::string LoopOptions::validate() const {
  if (const std::string message = fit.validate(); !message.empty()) {
    return "loop fit options: " + message;
  }
  if (fit.cross_validation_folds < 2) {
    return "loop fit.cross_validation_folds must be >= 2: the loop compares held-out errors";
  }
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const int index = static_cast<int>(candidates[i]);
    if (index < 0 || index >= effects::kKindCount) return "loop candidates holds an unknown effect";
    for (std::size_t j = 0; j < i; ++j) {
      if (candidates[j] == candidates[i]) {
        return "loop candidates names " + std::string(effects::info(candidates[i]).name) + " twice";
      }
    }
  }
  if (max_steps < 1) return "loop max_steps must be >= 1";
  if (refit_candidates < 1) return "loop refit_candidates must be >= 1";
  if (!finite_in(min_explained_fraction, 0.0, 1.0) || min_explained_fraction >= 1.0) {
    return "loop min_explained_fraction must lie in [0, 1)";
  }
  if (!std::isfinite(min_score_z) || min_score_z < 0) return "loop min_score_z must be >= 0";
  if (!finite_in(min_held_out_improvement, 0.0, 1.0) || min_held_out_improvement >= 1.0) {
    return "loop min_held_out_improvement must lie in [0, 1)";
  }
  if (!std::isfinite(min_bic_decrease) || min_bic_decrease < 0) {
    return "loop min_bic_decrease must be >= 0";
  }
  if (std::string message =
          check_grid(stribeck_speeds_rad_s, "stribeck_speeds_rad_s", effects::Kind::kStribeck, 1);
      !message.empty()) {
    return message;
  }
  if (std::string message =
          check_grid(soft_close_angles_rad, "soft_close_angles_rad", effects::Kind::kSoftClose, 1);
      !message.empty()) {
    return message;
  }
  if (std::string message = check_grid(soft_close_sharpness_per_rad, "soft_close_sharpness_per_rad",
                                       effects::Kind::kSoftClose, 2);
      !message.empty()) {
    return message;
  }
  if (end_stop_angles < 1) return "loop end_stop_angles must be >= 1";
  if (screen_steps < 0) return "loop screen_steps must be >= 0 (0: no second look)";
  for (const std::string& name : fixed_effect_parameters) {
    bool known = false;
    for (const effects::EffectInfo& effect : effects::catalogue()) {
      for (const effects::EffectParameter& parameter : effect.parameters) {
        known = known || name == std::string(effect.name) + "." + std::string(parameter.info.name);
      }
    }
    if (!known) {
      return "loop fixed_effect_parameters names '" + name +
             "', which no effect has (write <effect>.<parameter>, e.g. end_stop.beta_e)";
    }
  }
  if (!finite_in(structure_max_explained_fraction, 0.0, 1.0)) {
    return "loop structure_max_explained_fraction must lie in [0, 1]";
  }
  if (!std::isfinite(structure_noise_ratio) || structure_noise_ratio < 1) {
    return "loop structure_noise_ratio must be >= 1";
  }
  if (refit_start != RefitStart::kBest && refit_start != RefitStart::kCurrentFit &&
      refit_start != RefitStart::kStartModel) {
    return "loop refit_start is not a RefitStart";
  }
  return "";
}

ModelFigures model_figures(const FitSummary& summary) {
  ModelFigures figures;
  figures.fitted_rmse_rad_s = summary.fitted.window.rmse();
  figures.fitted_fit_percent = summary.fitted.window.fit_percent();
  figures.held_out_rmse_rad_s = summary.held_out ? summary.held_out->window.rmse() : kNaN;
  figures.held_out_fit_percent = summary.held_out ? summary.held_out->window.fit_percent() : kNaN;
  figures.residuals = summary.residuals;
  figures.free_parameters = summary.free_parameters;
  figures.parameters = summary.free_parameters + summary.window_state_parameters;
  const double n = static_cast<double>(summary.residuals);
  const double degrees_of_freedom = n - figures.parameters;
  figures.sum_of_squares = std::isfinite(summary.residual_variance) && degrees_of_freedom > 0
                               ? summary.residual_variance * degrees_of_freedom
                               : 2.0 * summary.final_cost;
  figures.bic = n > 0 && figures.sum_of_squares > 0
                    ? n * std::log(figures.sum_of_squares / n) + figures.parameters * std::log(n)
                    : kNaN;
  return figures;
}

namespace {

// The free parameters a fit with `fit` would estimate (as fit_model resolves them; names
// the model lacks are skipped here, the fit itself reports them).
std::vector<int> free_indices(const DoorModel& model, const FitOptions& fit) {
  const std::vector<std::string> names =
      fit.free_parameters.empty() ? default_free_parameters(model) : fit.free_parameters;
  std::vector<char> free(model.parameter_count(), 0);
  for (const std::string& name : names) {
    if (const std::optional<int> index = model.find_parameter(name)) free[*index] = 1;
  }
  for (const std::string& name : fit.fixed_parameters) {
    if (const std::optional<int> index = model.find_parameter(name)) free[*index] = 0;
  }
  std::vector<int> indices;
  for (int i = 0; i < model.parameter_count(); ++i) {
    if (free[i]) indices.push_back(i);
  }
  return indices;
}

// A column of the linearized window simulation: the sensitivity (δθ, δω) of the simulated
// state to one quantity, driven by a torque-like forcing (see examine()).
struct Sensitivity {
  double d_theta = 0.0, d_omega = 0.0, forcing = 0.0;
};

// The linearized window simulation of one model: the normal equations (Gram matrix) of the
// columns [parameters..., regressors..., e], in total and per window, and Σe².
struct Linearization {
  Eigen::MatrixXd gram;
  std::vector<Eigen::MatrixXd> window_grams;  // each window's share of `gram`
  double rate_sum_of_squares = 0.0;           // Σ(ω − ω̂)², rad²/s²
  std::size_t samples = 0;
  int failed_windows = 0;  // windows whose simulation failed (left out)
  // Σe² and samples per band of measured |ω| (kSpeedBandEdges_rad_s).
  std::array<double, std::size(kSpeedBandEdges_rad_s)> band_sum{}, band_samples{};
  void add_to_band(double measured_rad_s, double error) {
    std::size_t band = std::size(kSpeedBandEdges_rad_s) - 1;
    while (band > 0 && std::abs(measured_rad_s) < kSpeedBandEdges_rad_s[band]) --band;
    band_sum[band] += error * error;
    band_samples[band] += 1.0;
  }
  // The examination's residual by speed (ResidualExamination::speed_bands).
  std::vector<SpeedBand> speed_bands() const {
    std::vector<SpeedBand> bands;
    for (std::size_t b = 0; b < std::size(kSpeedBandEdges_rad_s); ++b) {
      SpeedBand band;
      band.low_rad_s = kSpeedBandEdges_rad_s[b];
      band.high_rad_s = b + 1 < std::size(kSpeedBandEdges_rad_s)
                            ? kSpeedBandEdges_rad_s[b + 1]
                            : std::numeric_limits<double>::infinity();
      band.samples = static_cast<std::size_t>(band_samples[b]);
      band.rms_rad_s = band.samples > 0 ? std::sqrt(band_sum[b] / band_samples[b]) : 0.0;
      bands.push_back(band);
    }
    return bands;
  }
  // The residual's differences along each window, for the noise floor: (e_j − e_{j−1} − d̄)²
  // and (e_j − e_{j−2} − d̄)² (d̄ each window's mean difference), and Σ j over the residuals.
  std::vector<double> lag1_squares, lag2_squares;
  double index_sum = 0.0;
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
    const double correction = static_cast<double>(differences.size()) /
                              static_cast<double>(differences.size() - 1);
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

// Σ(ω − ω̂)² over the windows as linearize() counts it, and the windows that failed, from
// the simulation alone (a trial step's test, without the sensitivities).
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

// A few damped Gauss–Newton (Levenberg–Marquardt) steps on the measured-state windows of
// the examination, the linearization above as the Jacobian: moves `parameters` (model
// indices) of `model` to lower Σ(ω − ω̂)². A step is taken only when it lowers the sum and
// no more windows fail to simulate. `linear` holds the columns [parameters..., e] at the
// result.
struct Refined {
  DoorModel model;
  Linearization linear;
  int steps = 0;
};

Refined refine_parameters(const DoorModel& start, const PreparedData& data,
                          const WindowOptions& windows, const std::vector<int>& parameters,
                          int max_steps) {
  Refined refined{start, linearize(start, data, windows, parameters, {}), 0};
  const int p = static_cast<int>(parameters.size());
  const auto bounds = start.parameter_bounds();
  double damping = 1e-3;
  for (int attempt = 0; attempt < 4 * max_steps && refined.steps < max_steps; ++attempt) {
    const Eigen::MatrixXd& g = refined.linear.gram;
    Eigen::VectorXd scale(p);
    for (int k = 0; k < p; ++k) {
      const double d = g(k, k);
      scale[k] = d > 0 && std::isfinite(d) ? 1.0 / std::sqrt(d) : 0.0;
    }
    const Eigen::MatrixXd a = scale.asDiagonal() * g.topLeftCorner(p, p) * scale.asDiagonal();
    const Eigen::VectorXd b = scale.cwiseProduct(g.block(0, p, p, 1));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
    const Eigen::VectorXd& values = eigen.eigenvalues();
    const double largest = values.size() > 0 ? values.maxCoeff() : 0.0;
    Eigen::VectorXd inverse = Eigen::VectorXd::Zero(p);
    for (int k = 0; k < p; ++k) {
      if (values[k] > kProjectionRankTolerance * largest) {
        inverse[k] = 1.0 / (values[k] + damping * largest);
      }
    }
    const Eigen::VectorXd step = scale.cwiseProduct(
        eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose() * b);
    if (!step.allFinite() || largest <= 0) break;
    std::vector<double> trial_values(refined.model.parameter_values().begin(),
                                     refined.model.parameter_values().end());
    for (int k = 0; k < p; ++k) {
      const int i = parameters[k];
      trial_values[i] = std::clamp(trial_values[i] + step[k], bounds[i].lower, bounds[i].upper);
    }
    std::optional<DoorModel> trial;
    try {
      trial = refined.model.with_parameter_values(std::move(trial_values));
    } catch (const std::invalid_argument&) {
      damping *= 10.0;
      continue;
    }
    const auto [trial_sum, trial_failed] = window_sum_of_squares(*trial, data, windows);
    const double before = refined.linear.rate_sum_of_squares;
    if (trial_failed <= refined.linear.failed_windows && trial_sum < before) {
      refined.model = std::move(*trial);
      refined.linear = linearize(refined.model, data, windows, parameters, {});
      ++refined.steps;
      damping = std::max(1e-6, 0.1 * damping);
      if (before - refined.linear.rate_sum_of_squares < 1e-3 * before) break;
    } else {
      damping *= 10.0;
    }
  }
  return refined;
}

// The projection off a Gram matrix's first `count` columns (X): (XᵀX)⁺ taken on
// unit-diagonal scaling with a relative eigenvalue cut-off, the coefficients β_a = (XᵀX)⁺
// Xᵀ(column a) in scaled coordinates, and (P column a)·(P column b) over the rows of any
// Gram matrix `g` of the same columns (the whole data or one window), P = I − X (XᵀX)⁺ Xᵀ.
class GramProjector {
 public:
  GramProjector(const Eigen::MatrixXd& gram, int count)
      : count_(count), scale_(Eigen::VectorXd::Ones(count)) {
    if (count_ == 0) return;
    for (int k = 0; k < count_; ++k) {
      const double d = gram(k, k);
      scale_[k] = d > 0 && std::isfinite(d) ? 1.0 / std::sqrt(d) : 0.0;
    }
    const Eigen::MatrixXd scaled =
        scale_.asDiagonal() * gram.topLeftCorner(count_, count_) * scale_.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
    const Eigen::VectorXd& values = eigen.eigenvalues();
    const double largest = values.size() > 0 ? values.maxCoeff() : 0.0;
    Eigen::VectorXd inverse_values = Eigen::VectorXd::Zero(values.size());
    for (int k = 0; k < values.size(); ++k) {
      if (values[k] > kProjectionRankTolerance * largest) inverse_values[k] = 1.0 / values[k];
    }
    inverse_ =
        eigen.eigenvectors() * inverse_values.asDiagonal() * eigen.eigenvectors().transpose();
  }
  Eigen::VectorXd coefficients(const Eigen::MatrixXd& gram, int a) const {
    if (count_ == 0) return Eigen::VectorXd();
    return inverse_ * scale_.cwiseProduct(gram.block(0, a, count_, 1));
  }
  double project(const Eigen::MatrixXd& g, int a, const Eigen::VectorXd& beta_a, int b,
                 const Eigen::VectorXd& beta_b) const {
    double value = g(a, b);
    if (count_ == 0) return value;
    const Eigen::VectorXd ga = scale_.cwiseProduct(g.block(0, a, count_, 1));
    const Eigen::VectorXd gb = scale_.cwiseProduct(g.block(0, b, count_, 1));
    const Eigen::MatrixXd h =
        scale_.asDiagonal() * g.topLeftCorner(count_, count_) * scale_.asDiagonal();
    return value - beta_a.dot(gb) - beta_b.dot(ga) + beta_a.dot(h * beta_b);
  }

 private:
  int count_;
  Eigen::VectorXd scale_;
  Eigen::MatrixXd inverse_;
};

// The score of the last parameter column of `linear` (columns [nuisance..., x, e]) with
// the nuisance projected out: returns (x·Pe, |Px|², Σ_w (Px·r)_w²), the pieces of the
// window-clustered Wald statistic. r = Pe − (x·Pe/|Px|²) Px is the residual the linearised
// least-squares step in x would leave, as the first look's standard error takes it: at a
// least-squares point x·Pe = 0 and r = Pe, but a refinement cut off after a few steps is
// not at one, and Pe then still holds the score of the step not taken, which is no noise
// (the soft close of docs/residual-loop.md, "Recordings with the tremor hand": z 1.6 with
// Pe, 6.4 with r, after 5 steps).
struct ColumnScore {
  double pxe = 0.0, pxx = 0.0, spread = 0.0;
};

ColumnScore last_column_score(const Linearization& linear) {
  const int columns = static_cast<int>(linear.gram.rows());
  const int x = columns - 2, e = columns - 1;
  const GramProjector projector(linear.gram, x);
  const Eigen::VectorXd beta_x = projector.coefficients(linear.gram, x);
  const Eigen::VectorXd beta_e = projector.coefficients(linear.gram, e);
  ColumnScore score;
  score.pxe = projector.project(linear.gram, x, beta_x, e, beta_e);
  score.pxx = projector.project(linear.gram, x, beta_x, x, beta_x);
  const double step = score.pxx > 0 ? score.pxe / score.pxx : 0.0;
  for (const Eigen::MatrixXd& window_gram : linear.window_grams) {
    const double w = projector.project(window_gram, x, beta_x, e, beta_e) -
                     step * projector.project(window_gram, x, beta_x, x, beta_x);
    score.spread += w * w;
  }
  return score;
}

// A candidate chosen for the second look: the model with it added at its start values, and
// the parameters to refine (the free ones, the effect's other free parameters, its
// amplitude last: the column scored).
struct SecondLook {
  CandidateEvidence* candidate = nullptr;
  DoorModel with;
  std::vector<int> parameters;
};

// The candidates the second look takes (those the linear score leaves refit slots for).
std::vector<SecondLook> second_look_candidates(const DoorModel& model, const LoopOptions& options,
                                               const std::vector<int>& free,
                                               ResidualExamination& examination) {
  std::vector<SecondLook> chosen;
  // Only refit slots that the linear score leaves free are worth a second look.
  int slots = options.refit_candidates;
  for (const CandidateEvidence& candidate : examination.candidates) {
    if (candidate.explained_fraction >= options.min_explained_fraction &&
        candidate.score_z >= options.min_score_z) {
      --slots;
    }
  }
  int taken = 0;  // slots used, by a candidate the second look then takes or not
  for (CandidateEvidence& candidate : examination.candidates) {
    if (taken >= slots) break;
    if (candidate.explained_fraction < options.min_explained_fraction ||
        candidate.score_z >= options.min_score_z || candidate.start_values.empty()) {
      continue;
    }
    ++taken;
    const effects::EffectInfo& info = effects::info(candidate.kind);
    EffectSetting setting{candidate.kind, candidate.start_values, {}};
    for (const effects::EffectParameter& parameter : info.parameters) {
      setting.bounds.push_back(parameter.default_bounds);
    }
    std::optional<DoorModel> with;
    try {
      with = model.with_effect(setting);
    } catch (const std::invalid_argument&) {
      continue;  // the start breaks a constraint: no second look
    }
    std::vector<int> parameters = free;
    int amplitude = -1;
    for (std::size_t k = 0; k < info.parameters.size(); ++k) {
      const std::string name =
          std::string(info.name) + "." + std::string(info.parameters[k].info.name);
      const bool fixed = std::find(options.fixed_effect_parameters.begin(),
                                   options.fixed_effect_parameters.end(),
                                   name) != options.fixed_effect_parameters.end();
      const std::optional<int> index = with->find_parameter(name);
      if (!index) continue;
      if (k == 0) {
        amplitude = *index;
      } else if (!fixed) {
        parameters.push_back(*index);
      }
    }
    if (amplitude < 0) continue;
    parameters.push_back(amplitude);
    chosen.push_back({&candidate, std::move(*with), std::move(parameters)});
  }
  return chosen;
}

// The second look (LoopOptions::screen_steps): the best-ranked candidates that explain at
// least min_explained_fraction but score z below min_score_z, as many as refit slots are
// left by the candidates that pass both, are each added at their examination start
// and refined, with the free parameters, by a few Gauss–Newton steps on the examination's
// windows (refine_parameters); the model without it is refined the same way. Its screened
// share is the fall of Σe² between the two over the examination's Σe², its screened z the
// refined amplitude over its window-clustered standard error there. A linear score is
// poor where the effect's response is not linear in its amplitude: breakaway friction
// that holds the door a few milliseconds longer before the latch snaps.
void screen_weak_candidates(const DoorModel& model, const PreparedData& data,
                            const LoopOptions& options, const WindowOptions& windows,
                            const std::vector<int>& free, ResidualExamination& examination) {
  if (options.screen_steps <= 0) return;
  const std::vector<SecondLook> chosen =
      second_look_candidates(model, options, free, examination);
  if (chosen.empty()) return;
  // The model without any candidate and each candidate's, refined at once (each is
  // deterministic and independent: the same results as one after another).
  std::vector<std::optional<Refined>> refined(chosen.size() + 1);
  std::vector<std::exception_ptr> errors(chosen.size() + 1);
  parallel_for(static_cast<int>(refined.size()), refit_threads(options.parallel_refits, refined.size()),
               [&](std::size_t j) {
    try {
      refined[j] = j == 0 ? refine_parameters(model, data, windows, free, options.screen_steps)
                          : refine_parameters(chosen[j - 1].with, data, windows,
                                              chosen[j - 1].parameters, options.screen_steps);
    } catch (...) {
      errors[j] = std::current_exception();
    }
  });
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
  const Refined& without = *refined[0];
  for (std::size_t j = 0; j < chosen.size(); ++j) {
    CandidateEvidence& candidate = *chosen[j].candidate;
    const Refined& with = *refined[j + 1];
    const effects::EffectInfo& info = effects::info(candidate.kind);
    const ColumnScore score = last_column_score(with.linear);
    const double offset =
        candidate.kind == effects::Kind::kStribeck ? base_friction(with.model).level_Nm : 0.0;
    const double value = with.model.parameter_values()[chosen[j].parameters.back()] - offset;
    const double fall = without.linear.rate_sum_of_squares - with.linear.rate_sum_of_squares;
    candidate.screened = true;
    candidate.screen_explained_fraction =
        examination.rate_sum_of_squares > 0 ? std::max(0.0, fall) / examination.rate_sum_of_squares
                                            : 0.0;
    candidate.screen_score_z =
        score.spread > 0 && fall > 0 ? std::abs(value) * score.pxx / std::sqrt(score.spread) : 0.0;
    candidate.screen_values.clear();
    for (const effects::EffectParameter& parameter : info.parameters) {
      const std::optional<int> index = with.model.find_parameter(
          std::string(info.name) + "." + std::string(parameter.info.name));
      candidate.screen_values.push_back(with.model.parameter_values()[*index]);
    }
  }
}

ResidualExamination examine(const DoorModel& model, const PreparedData& data,
                            const LoopOptions& options, const FitOptions& fit) {
  const StageClock::time_point began = StageClock::now();
  const std::vector<effects::Kind> kinds = candidate_kinds(model, options);
  std::vector<Regressor> regressors = make_regressors(model, data, kinds, options);
  const WindowOptions windows = metric_window_options(fit, model);
  const std::vector<int> free = free_indices(model, fit);
  const int free_count = static_cast<int>(free.size());
  const int regressor_count = static_cast<int>(regressors.size());
  const int columns = free_count + regressor_count + 1;
  Linearization linear = linearize(model, data, windows, free, regressors);
  const Eigen::MatrixXd& gram = linear.gram;
  const std::vector<Eigen::MatrixXd>& window_grams = linear.window_grams;
  ResidualExamination examination;
  examination.samples = linear.samples;
  examination.rate_sum_of_squares = linear.rate_sum_of_squares;
  estimate_noise_floor(linear, examination);
  examination.speed_bands = linear.speed_bands();


  // Project the free parameters' columns out (the fit re-estimates them with the effect):
  // with X those columns, x a regressor and P = I − X (XᵀX)⁺ Xᵀ,
  //   x·Pe = x·e − xᵀX (XᵀX)⁺ Xᵀe,  |Px|² = x·x − xᵀX (XᵀX)⁺ Xᵀx,
  // (XᵀX)⁺ taken on unit-diagonal scaling with a relative eigenvalue cut-off.
  const GramProjector projector(gram, free_count);
  // β_a = (XᵀX)⁺ Xᵀ(column a), scaled: Xβ is the part of a column the parameters mimic.
  auto coefficients = [&](int a) { return projector.coefficients(gram, a); };
  // (P column a)·(P column b) over the rows of `g` (the whole data or one window).
  auto project = [&](const Eigen::MatrixXd& g, int a, const Eigen::VectorXd& beta_a, int b,
                     const Eigen::VectorXd& beta_b) {
    return projector.project(g, a, beta_a, b, beta_b);
  };
  const int e_column = columns - 1;
  const Eigen::VectorXd beta_e = coefficients(e_column);

  // Each effect's best configuration: the amplitude minimizing |Pe − a Px|² within its
  // range, and the share of Σe² it removes.
  for (effects::Kind kind : kinds) {
    CandidateEvidence candidate;
    candidate.kind = kind;
    candidate.name = std::string(effects::info(kind).name);
    int best = -1;
    double best_amplitude = 0.0;
    double best_reduction = -1.0;
    double best_independent = 0.0;
    double best_score = 0.0;
    for (int r = 0; r < regressor_count; ++r) {
      const Regressor& regressor = regressors[r];
      if (regressor.kind != kind) continue;
      const int c = free_count + r;
      const Eigen::VectorXd beta_x = coefficients(c);
      const double xx = gram(c, c);
      const double pxx = project(gram, c, beta_x, c, beta_x);
      const double pxe = project(gram, c, beta_x, e_column, beta_e);
      double amplitude = 0.0;
      double reduction = 0.0;
      const double independent = xx > 0 ? std::max(0.0, pxx) / xx : 0.0;
      if (independent > kProjectionRankTolerance && std::isfinite(pxe)) {
        amplitude = std::clamp(pxe / pxx, regressor.lower, regressor.upper);
        reduction = 2.0 * amplitude * pxe - amplitude * amplitude * pxx;
      }
      if (reduction > best_reduction) {
        // The amplitude over its window-clustered standard error (a Wald test): windows are
        // independent, the samples within one are not (the force noise integrates along
        // it). With r = Pe − â Px the residual left, Var(â) = Σ_w (Px·r)_w² / |Px|⁴.
        const double unconstrained = pxx > 0 ? pxe / pxx : 0.0;
        double spread = 0.0;
        for (const Eigen::MatrixXd& window_gram : window_grams) {
          const double score = project(window_gram, c, beta_x, e_column, beta_e) -
                               unconstrained * project(window_gram, c, beta_x, c, beta_x);
          spread += score * score;
        }
        best = r;
        best_amplitude = amplitude;
        best_reduction = reduction;
        best_independent = independent;
        best_score = spread > 0 ? std::abs(pxe) / std::sqrt(spread) : 0.0;
      }
    }
    if (best < 0) continue;  // no configuration (the end stop without data)
    candidate.explained_fraction =
        examination.rate_sum_of_squares > 0
            ? std::max(0.0, best_reduction) / examination.rate_sum_of_squares
            : 0.0;
    candidate.independent_share = best_independent;
    candidate.score_z = best_amplitude != 0.0 ? best_score : 0.0;
    candidate.start_values = regressors[best].unit_values;
    candidate.start_values[0] = regressors[best].amplitude_offset + best_amplitude;
    candidate.scan = regressors[best].scan;
    examination.candidates.push_back(std::move(candidate));
  }
  std::stable_sort(examination.candidates.begin(), examination.candidates.end(),
                   [](const CandidateEvidence& a, const CandidateEvidence& b) {
                     return a.explained_fraction > b.explained_fraction;
                   });
  for (std::size_t k = 0; k < examination.candidates.size(); ++k) {
    examination.candidates[k].rank = static_cast<int>(k) + 1;
  }
  const StageClock::time_point screen_began = StageClock::now();
  screen_weak_candidates(model, data, options, windows, free, examination);
  examination.screen_time_s = seconds_since(screen_began);
  examination.time_s = seconds_since(began);
  return examination;
}

}  // namespace

ResidualExamination examine_residual(const DoorModel& model, const PreparedData& data,
                                     const LoopOptions& options) {
  if (const std::string message = options.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
  return examine(model, data, options, options.fit);
}

namespace {

std::vector<std::string> effect_parameter_names(effects::Kind kind) {
  const effects::EffectInfo& info = effects::info(kind);
  std::vector<std::string> names;
  for (const effects::EffectParameter& parameter : info.parameters) {
    names.push_back(std::string(info.name) + "." + std::string(parameter.info.name));
  }
  return names;
}

// The fit options of a refit with `kind` added to a model fitted with `current`.
FitOptions refit_options(const FitOptions& current, const LoopOptions& options,
                         effects::Kind kind) {
  FitOptions fit = current;
  fit.latch_start_from_data = false;  // the start is already a fit
  for (const std::string& name : effect_parameter_names(kind)) {
    const bool fixed =
        std::find(options.fixed_effect_parameters.begin(), options.fixed_effect_parameters.end(),
                  name) != options.fixed_effect_parameters.end();
    if (fixed) {
      fit.fixed_parameters.push_back(name);
    } else if (!fit.free_parameters.empty()) {
      fit.free_parameters.push_back(name);
    }
  }
  return fit;
}

// Refits `current` with the candidate effect added (LoopOptions::RefitStart). `fits` counts
// the calls of fit_model; `origin` says which start won.
FitResult refit(const DoorModel& start, const FitResult& current, const FitOptions& current_options,
                const PreparedData& data, const LoopOptions& options,
                const CandidateEvidence& candidate, int& fits, std::string& origin) {
  const effects::EffectInfo& info = effects::info(candidate.kind);
  EffectSetting setting{candidate.kind, candidate.start_values, {}};
  for (const effects::EffectParameter& parameter : info.parameters) {
    setting.bounds.push_back(parameter.default_bounds);
  }
  const FitOptions from_fit = refit_options(current_options, options, candidate.kind);
  FitOptions from_start = from_fit;
  from_start.latch_start_from_data = options.fit.latch_start_from_data;
  auto fresh_start = [&] {
    std::vector<double> values(current.model.parameter_values().begin(),
                               current.model.parameter_values().end());
    for (int i = 0; i < current.model.base_parameter_count(); ++i) {
      values[i] = start.parameter_values()[i];
    }
    return current.model.with_parameter_values(std::move(values)).with_effect(setting);
  };
  switch (options.refit_start) {
    case LoopOptions::RefitStart::kCurrentFit:
      origin = "the current fit";
      ++fits;
      return fit_model(current.model.with_effect(setting), data, from_fit);
    case LoopOptions::RefitStart::kStartModel:
      origin = "the start model";
      ++fits;
      return fit_model(fresh_start(), data, from_start);
    case LoopOptions::RefitStart::kBest:
      break;
  }
  // Both starts without cross-validation (at once when options.parallel_refits: each fit
  // is the same on any thread); the better one again, with it, from its result.
  struct Attempt {
    std::optional<FitResult> result;
    std::string error;
  };
  Attempt attempts[2];
  const char* names[2] = {"the current fit", "the start model"};
  auto attempt = [&](std::size_t which) {
    FitOptions fit = which == 0 ? from_fit : from_start;
    fit.cross_validation_folds = 0;
    // A start is the loop's search, not its measurement: its coarse pass goes on to the fine
    // pass's own precision instead of stopping at once where σ is inflated (a model lacking
    // an effect), so the iterations run at the coarse problem's half cost.
    fit.coarse_tolerance_factor = 1.0;
    try {
      const DoorModel model = which == 0 ? current.model.with_effect(setting) : fresh_start();
      attempts[which].result = fit_model(model, data, fit);
    } catch (const std::exception& error) {
      attempts[which].error = error.what();
    }
  };
  parallel_for(2, refit_threads(options.parallel_refits, 2), attempt);
  std::optional<FitResult> best;
  std::string failures;
  for (std::size_t which = 0; which < 2; ++which) {
    ++fits;
    Attempt& tried = attempts[which];
    if (!tried.result) {
      failures += std::string(failures.empty() ? "" : "; ") + "from " + names[which] + ": " +
                  tried.error;
      continue;
    }
    if (!best || model_figures(tried.result->summary).sum_of_squares <
                     model_figures(best->summary).sum_of_squares) {
      best = std::move(tried.result);
      origin = names[which];
    }
  }
  if (!best) throw std::runtime_error(failures);
  // It starts at the better start's optimum of the fine problem: no equation-error stage and
  // no coarse pass (which would leave that optimum for the coarse one's and come back).
  FitOptions final_fit = from_fit;
  final_fit.equation_error_start = false;
  final_fit.coarse_first = false;
  ++fits;
  return fit_model(best->model, data, final_fit);
}

std::string describe_figures(const ModelFigures& figures) {
  return "window RMSE of omega " + number(figures.fitted_rmse_rad_s) + " rad/s fitted, " +
         number(figures.held_out_rmse_rad_s) + " held out";
}

std::string parameter_text(const FittedParameter& parameter) {
  std::string text = parameter.name + " = " + number(parameter.value);
  if (parameter.free) {
    text += " +- " + number(parameter.uncertainty);
  } else {
    text += " (fixed)";
  }
  if (!parameter.unit.empty()) text += " " + parameter.unit;
  if (parameter.at_bound) text += " [at a bound]";
  if (parameter.free && !parameter.determined) text += " [undetermined]";
  return text;
}

}  // namespace

namespace {

using Say = std::function<void(const std::string&)>;

std::string ranking_line(int step_number, const ResidualExamination& examination) {
  std::string ranking = "step " + std::to_string(step_number) + ": the residual ranks ";
  for (std::size_t k = 0; k < examination.candidates.size() && k < 4; ++k) {
    if (k > 0) ranking += ", ";
    ranking += examination.candidates[k].name + " (" +
               percent(examination.candidates[k].explained_fraction) +
               printf_text(", z %.3g)", examination.candidates[k].score_z);
  }
  return ranking;
}

// Who is refitted: the candidates whose linear share and z pass, in rank order, then those
// the second look promotes, while refit slots are left. Gives the others their verdicts.
std::vector<std::size_t> select_refits(ResidualExamination& examination, const LoopOptions& options,
                                       int step_number, const Say& say) {
  std::vector<std::size_t> order, promoted;
  for (std::size_t k = 0; k < examination.candidates.size(); ++k) {
    CandidateEvidence& candidate = examination.candidates[k];
    const bool share_ok = candidate.explained_fraction >= options.min_explained_fraction;
    if (share_ok && candidate.score_z >= options.min_score_z) {
      order.push_back(k);
    } else if (candidate.screened &&
               candidate.screen_explained_fraction >= options.min_explained_fraction &&
               candidate.screen_score_z >= options.min_score_z) {
      promoted.push_back(k);
    } else if (!share_ok) {
      candidate.verdict = "not refitted: explains " + percent(candidate.explained_fraction) +
                          " of the residual (needs " + percent(options.min_explained_fraction) +
                          ")";
    } else {
      candidate.verdict = "not refitted: score z = " + printf_text("%.2g", candidate.score_z) +
                          " (needs " + printf_text("%.2g", options.min_score_z) + ")";
      if (candidate.screened) {
        candidate.verdict +=
            printf_text(", second look %.1f%%, z %.2g", 100.0 * candidate.screen_explained_fraction,
                        candidate.screen_score_z);
      }
    }
  }
  for (std::size_t k : promoted) {
    CandidateEvidence& candidate = examination.candidates[k];
    candidate.promoted = true;
    candidate.start_values = candidate.screen_values;
    candidate.scan +=
        std::string(candidate.scan.empty() ? "" : "; ") +
        printf_text("second look: %.1f%%, z %.3g", 100.0 * candidate.screen_explained_fraction,
                    candidate.screen_score_z);
  }
  order.insert(order.end(), promoted.begin(), promoted.end());
  std::vector<std::size_t> to_refit;
  for (std::size_t k : order) {
    CandidateEvidence& candidate = examination.candidates[k];
    if (static_cast<int>(to_refit.size()) >= options.refit_candidates) {
      candidate.verdict = "not refitted: ranked below the " +
                          std::to_string(options.refit_candidates) + " refitted";
      continue;
    }
    to_refit.push_back(k);
    candidate.refitted = true;
    say("step " + std::to_string(step_number) + ": refitting with " + candidate.name +
        (candidate.scan.empty() ? "" : " (" + candidate.scan + ")"));
  }
  return to_refit;
}

// A refitted candidate's figures and verdict against `before`.
void judge(CandidateEvidence& candidate, const ModelFigures& before, const ModelFigures& after,
           const LoopOptions& options) {
  candidate.after = after;
  candidate.held_out_improvement =
      (before.held_out_rmse_rad_s - after.held_out_rmse_rad_s) / before.held_out_rmse_rad_s;
  candidate.bic_change = after.bic - before.bic;
  const bool held_out_ok = candidate.held_out_improvement > options.min_held_out_improvement;
  const bool bic_ok = candidate.bic_change < -options.min_bic_decrease;
  candidate.qualifies = held_out_ok && bic_ok;
  const std::string held_out_text = "held-out RMSE " + number(before.held_out_rmse_rad_s) + " -> " +
                                    number(after.held_out_rmse_rad_s) + " rad/s (" +
                                    signed_percent(-candidate.held_out_improvement) + ")";
  const std::string bic_text = "BIC " + printf_text("%+.4g", candidate.bic_change);
  if (candidate.qualifies) {
    candidate.verdict = "qualifies: " + held_out_text + ", " + bic_text;
  } else if (!held_out_ok) {
    candidate.verdict = "rejected: " + held_out_text + ", needs a fall of more than " +
                        percent(options.min_held_out_improvement);
  } else {
    candidate.verdict = "rejected: " + bic_text + " (must fall by more than " +
                        number(options.min_bic_decrease) + "), " + held_out_text;
  }
}

// The refits of one step (LoopOptions::parallel_refits): fit_model gives the same result bit
// for bit on any thread and with any num_threads (docs/fitting.md), so running them at once
// changes no verdict, only the time. Returns the refits by candidate index; counts fits.
std::vector<std::optional<FitResult>> run_refits(
    const DoorModel& start, const FitResult& current, const FitOptions& current_options,
    const PreparedData& data, const LoopOptions& options, const std::vector<std::size_t>& to_refit,
    ResidualExamination& examination, int& fits, const Say& say, int step_number) {
  std::vector<std::optional<FitResult>> refits(examination.candidates.size());
  const ModelFigures before = model_figures(current.summary);
  std::vector<std::string> refit_errors(to_refit.size());
  std::vector<int> refit_fits(to_refit.size(), 0);
  std::vector<double> refit_seconds(to_refit.size(), 0.0);
  LoopProgress progress{step_number, options.max_steps, 0, static_cast<int>(to_refit.size())};
  std::mutex progress_mutex;
  std::exception_ptr progress_error;
  if (options.step_progress && !to_refit.empty()) options.step_progress(progress);
  auto run_refit = [&](std::size_t j) {
    CandidateEvidence& candidate = examination.candidates[to_refit[j]];
    const StageClock::time_point refit_began = StageClock::now();
    try {
      refits[to_refit[j]] = refit(start, current, current_options, data, options, candidate,
                                  refit_fits[j], candidate.refit_start);
    } catch (const std::exception& error) {
      refit_errors[j] = error.what();
    } catch (...) {
      refit_errors[j] = "an exception that is not a std::exception";
    }
    refit_seconds[j] = seconds_since(refit_began);
    if (options.step_progress) {
      const std::lock_guard lock(progress_mutex);
      ++progress.refits_done;
      try {  // on a refit's thread: what it throws is rethrown on the caller's, after the join
        options.step_progress(progress);
      } catch (...) {
        if (!progress_error) progress_error = std::current_exception();
      }
    }
  };
  parallel_for(static_cast<int>(to_refit.size()),
               refit_threads(options.parallel_refits, to_refit.size()), run_refit);
  if (progress_error) std::rethrow_exception(progress_error);
  for (std::size_t j = 0; j < to_refit.size(); ++j) {
    const std::size_t k = to_refit[j];
    CandidateEvidence& candidate = examination.candidates[k];
    fits += refit_fits[j];
    if (!refits[k]) {
      candidate.verdict = "refit failed: " + refit_errors[j];
      say("  " + candidate.name + ": " + candidate.verdict);
      continue;
    }
    judge(candidate, before, model_figures(refits[k]->summary), options);
    say("  " + candidate.name + ": " + candidate.verdict +
        printf_text(" [refit from %s, %.1f s]", candidate.refit_start.c_str(), refit_seconds[j]));
  }
  return refits;
}

// The qualifying candidate with the lowest held-out RMSE; -1 when none qualifies.
int choose(const std::vector<CandidateEvidence>& candidates) {
  int chosen = -1;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const CandidateEvidence& candidate = candidates[k];
    if (!candidate.qualifies) continue;
    if (chosen < 0 ||
        candidate.after->held_out_rmse_rad_s < candidates[chosen].after->held_out_rmse_rad_s) {
      chosen = static_cast<int>(k);
    }
  }
  return chosen;
}

LoopStep make_step(int step_number, ResidualExamination& examination, int chosen,
                   const FitResult& refit_result, const ModelFigures& before) {
  const CandidateEvidence& accepted = examination.candidates[chosen];
  LoopStep step;
  step.number = step_number;
  step.effect = accepted.kind;
  step.effect_name = accepted.name;
  step.second_look = accepted.promoted;
  step.explained_fraction =
      accepted.promoted ? accepted.screen_explained_fraction : accepted.explained_fraction;
  step.score_z = accepted.promoted ? accepted.screen_score_z : accepted.score_z;
  step.rank = accepted.rank;
  const std::string prefix = accepted.name + ".";
  for (const FittedParameter& parameter : refit_result.summary.parameters) {
    if (parameter.name.rfind(prefix, 0) == 0) step.parameters.push_back(parameter);
  }
  step.before = before;
  step.after = *accepted.after;
  step.held_out_improvement = accepted.held_out_improvement;
  step.bic_change = accepted.bic_change;
  step.candidates = std::move(examination.candidates);
  step.speed_bands = std::move(examination.speed_bands);
  return step;
}

// The reference door of the other family with the structure check's free set.
FitOptions structure_fit_options(const LoopOptions& options, ModelKind other) {
  FitOptions fit = options.fit;
  fit.fixed_parameters.clear();
  fit.free_parameters = options.structure_free_parameters;
  if (fit.free_parameters.empty() && other == ModelKind::kPhysical) {
    fit.free_parameters = {"J_d", "k_s", "F0", "T_h", "mu_g"};
  }
  return fit;
}

// Whether the structure check runs, and why (or why not).
bool structure_check_due(const LoopOptions& options, const ModelFigures& figures,
                         const ResidualExamination& last, StructureCheck& check) {
  for (const CandidateEvidence& candidate : last.candidates) {
    check.best_explained_fraction =
        std::max(check.best_explained_fraction, candidate.explained_fraction);
  }
  check.noise_floor_rad_s = last.noise_floor_rad_s;
  const double ratio = last.noise_floor_rad_s > 0
                           ? figures.held_out_rmse_rad_s / last.noise_floor_rad_s
                           : std::numeric_limits<double>::infinity();
  if (!options.structure_check) {
    check.reason = "off (structure_check)";
  } else if (check.best_explained_fraction >= options.structure_max_explained_fraction) {
    check.reason = "not run: the best candidate explains " +
                   percent(check.best_explained_fraction) + " of the residual (at least " +
                   percent(options.structure_max_explained_fraction) + ")";
  } else if (ratio <= options.structure_noise_ratio) {
    check.reason = "not run: the held-out RMSE " + number(figures.held_out_rmse_rad_s) +
                   " rad/s is " + printf_text("%.2g", ratio) + " times the noise floor " +
                   number(last.noise_floor_rad_s) + " rad/s (needs more than " +
                   printf_text("%.3g", options.structure_noise_ratio) + ")";
  } else {
    check.reason = "no effect closes the gap: the best remaining candidate explains " +
                   percent(check.best_explained_fraction) +
                   " of the residual and the held-out "
                   "RMSE " +
                   number(figures.held_out_rmse_rad_s) + " rad/s is " + printf_text("%.3g", ratio) +
                   " times the noise floor " + number(last.noise_floor_rad_s) + " rad/s";
    return true;
  }
  return false;
}

// The structure check: the other family fitted and compared, then examined for what it
// leaves. Counts its fit in `fits`.
StructureCheck check_structure(const FitResult& current, const PreparedData& data,
                               const LoopOptions& options, const ResidualExamination& last,
                               int& fits, const Say& say) {
  StructureCheck check;
  check.current_kind = current.model.kind();
  check.other_kind =
      check.current_kind == ModelKind::kSensory ? ModelKind::kPhysical : ModelKind::kSensory;
  check.current = model_figures(current.summary);
  if (!structure_check_due(options, check.current, last, check)) {
    return check;
  }
  check.ran = true;
  const std::string other_name(to_string(check.other_kind));
  say("structure check: " + check.reason + "; fitting the " + other_name + " model");
  const FitOptions fit = structure_fit_options(options, check.other_kind);
  try {
    ++fits;
    check.other_fit = fit_model(reference_model(check.other_kind), data, fit);
  } catch (const std::exception& error) {
    check.verdict = "the " + other_name + " model's fit failed: " + error.what();
    say("structure check: " + check.verdict);
    return check;
  }
  const FitSummary& other = check.other_fit->summary;
  check.other = model_figures(other);
  for (const FittedParameter& parameter : other.parameters) {
    if (parameter.free) check.other_free.push_back(parameter.name);
  }
  check.other_undetermined = other.undetermined;
  check.held_out_improvement =
      (check.current.held_out_rmse_rad_s - check.other.held_out_rmse_rad_s) /
      check.current.held_out_rmse_rad_s;
  check.bic_change = check.other.bic - check.current.bic;
  check.other_better = check.held_out_improvement > options.min_held_out_improvement &&
                       check.bic_change < -options.min_bic_decrease;
  ResidualExamination examination = examine(check.other_fit->model, data, options, fit);
  for (const CandidateEvidence& candidate : examination.candidates) {
    if (candidate.explained_fraction >= options.min_explained_fraction &&
        candidate.score_z >= options.min_score_z) {
      check.remaining.push_back(candidate);
    }
  }
  const std::string current_name(to_string(check.current_kind));
  check.verdict = std::string(check.other_better ? "the " + other_name : "the " + current_name) +
                  " model is the better structure: held-out RMSE " +
                  number(check.current.held_out_rmse_rad_s) + " rad/s (" + current_name +
                  ") against " + number(check.other.held_out_rmse_rad_s) + " (" + other_name +
                  ", " + signed_percent(-check.held_out_improvement) + "), BIC " +
                  printf_text("%+.4g", check.bic_change);
  say("structure check: " + check.verdict);
  return check;
}

}  // namespace

LoopResult run_residual_loop(const DoorModel& start, const PreparedData& data,
                             const LoopOptions& options) {
  const StageClock::time_point began = StageClock::now();
  if (const std::string message = options.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
  int usable_strokes = 0;
  for (const Stroke& stroke : data.strokes) usable_strokes += stroke.size() >= 2 ? 1 : 0;
  if (usable_strokes < 2) {
    throw std::invalid_argument(
        "residual loop: the data needs at least 2 strokes (held-out errors need strokes left "
        "out of a fit)");
  }
  const Say say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };

  say("fitting the start model (" + std::string(to_string(start.kind())) + ", " +
      std::to_string(start.effects().size()) + " effects) with " +
      std::to_string(options.fit.cross_validation_folds) + "-fold cross-validation");
  FitResult start_fit = fit_model(start, data, options.fit);
  LoopResult result{.start_fit = start_fit,
                    .final_fit = std::move(start_fit),
                    .steps = {},
                    .last_candidates = {},
                    .last_speed_bands = {},
                    .stop_reason = "",
                    .fits = 1,
                    .total_time_s = 0.0,
                    .options = options,
                    .structure = {}};
  say("start model: " + describe_figures(model_figures(result.start_fit.summary)) +
      printf_text(" [%.1f s]", result.start_fit.summary.total_time_s));

  FitResult current = result.start_fit;
  FitOptions current_options = options.fit;  // the options current was fitted with
  current_options.progress = nullptr;        // the refits run several at once
  ResidualExamination last;                  // the examination that ended the loop
  for (int step_number = 1;; ++step_number) {
    if (step_number > options.max_steps) {
      result.stop_reason = "reached max_steps (" + std::to_string(options.max_steps) + ")";
      // The structure check's evidence: the final model's residual (no refits).
      if (options.structure_check) last = examine(current.model, data, options, current_options);
      break;
    }
    ResidualExamination examination = examine(current.model, data, options, current_options);
    if (examination.candidates.empty()) {
      result.stop_reason = "no candidate effect is left (every candidate is in the model)";
      last = std::move(examination);
      break;
    }
    say(ranking_line(step_number, examination));
    const ModelFigures before = model_figures(current.summary);
    const std::vector<std::size_t> to_refit = select_refits(examination, options, step_number, say);
    std::vector<std::optional<FitResult>> refits =
        run_refits(start, current, current_options, data, options, to_refit, examination,
                   result.fits, say, step_number);
    const int chosen = choose(examination.candidates);
    if (chosen < 0) {
      result.stop_reason =
          to_refit.empty()
              ? "no candidate was worth a refit (explained share or z below the thresholds)"
              : "no refitted candidate qualified";
      result.last_candidates = examination.candidates;
      result.last_speed_bands = examination.speed_bands;
      last = std::move(examination);
      break;
    }
    const effects::Kind accepted = examination.candidates[chosen].kind;
    LoopStep step = make_step(step_number, examination, chosen, *refits[chosen], before);
    std::string added = "step " + std::to_string(step_number) + ": added " + step.effect_name + ":";
    for (const FittedParameter& parameter : step.parameters) {
      added += ' ';
      added += parameter_text(parameter);
    }
    say(added);
    current = std::move(*refits[chosen]);
    current_options = refit_options(current_options, options, accepted);
    result.steps.push_back(std::move(step));
  }
  say("stopped: " + result.stop_reason);
  result.structure = check_structure(current, data, options, last, result.fits, say);
  result.final_fit = std::move(current);
  result.total_time_s = seconds_since(began);
  return result;
}

// ---------------------------------------------------------------------------------------
// Reports.

namespace {

void figures_table(std::string& out, const ModelFigures& before, const ModelFigures& after) {
  out += printf_text("    %-30s %-12s %-12s\n", "", "before", "after");
  auto row = [&](const char* name, double a, double b) {
    out += printf_text("    %-30s %-12s %-12s\n", name, number(a).c_str(), number(b).c_str());
  };
  row("window RMSE fitted (rad/s)", before.fitted_rmse_rad_s, after.fitted_rmse_rad_s);
  row("window RMSE held out (rad/s)", before.held_out_rmse_rad_s, after.held_out_rmse_rad_s);
  row("window FIT% fitted", before.fitted_fit_percent, after.fitted_fit_percent);
  row("window FIT% held out", before.held_out_fit_percent, after.held_out_fit_percent);
  row("BIC", before.bic, after.bic);
  row("free parameters", before.free_parameters, after.free_parameters);
  row("p in BIC (with window states)", before.parameters, after.parameters);
}

void candidate_table(std::string& out, const std::vector<CandidateEvidence>& candidates) {
  out += printf_text("    %-4s %-19s %-9s %-6s %-13s %-10s %s\n", "rank", "effect", "explains", "z",
                     "held-out RMSE", "BIC change", "verdict");
  for (const CandidateEvidence& candidate : candidates) {
    out += printf_text(
        "    %-4d %-19s %-9s %-6.3g %-13s %-10s %s\n", candidate.rank, candidate.name.c_str(),
        percent(candidate.explained_fraction).c_str(), candidate.score_z,
        candidate.after ? signed_percent(-candidate.held_out_improvement).c_str() : "-",
        candidate.after ? printf_text("%+.4g", candidate.bic_change).c_str() : "-",
        candidate.verdict.c_str());
    if (!candidate.scan.empty()) out += printf_text("         scan: %s\n", candidate.scan.c_str());
    if (!candidate.refit_start.empty()) {
      out += printf_text("         refit from %s\n", candidate.refit_start.c_str());
    }
  }
}

void speed_band_line(std::string& out, const std::vector<SpeedBand>& bands) {
  if (bands.empty()) return;
  out += "    residual by measured speed |omega| (RMS of omega - omega_hat, rad/s, samples):";
  for (const SpeedBand& band : bands) {
    out += std::isfinite(band.high_rad_s)
               ? printf_text(" [%g, %g) %s (%zu);", band.low_rad_s, band.high_rad_s,
                             number(band.rms_rad_s).c_str(), band.samples)
               : printf_text(" >= %g %s (%zu)", band.low_rad_s, number(band.rms_rad_s).c_str(),
                             band.samples);
  }
  out += "\n";
}

void structure_section(std::string& out, const StructureCheck& check) {
  out += "\nStructure check: " + check.reason + "\n";
  if (!check.ran) return;
  out += "  " + check.verdict + "\n";
  if (!check.other_fit) return;
  out += "  " + std::string(to_string(check.other_kind)) + " model, free:";
  for (const std::string& name : check.other_free) out += " " + name;
  out += check.other_undetermined.empty() ? "; every one determined\n" : "; undetermined:";
  for (const std::string& name : check.other_undetermined) out += " " + name;
  if (!check.other_undetermined.empty()) out += "\n";
  figures_table(out, check.current, check.other);
  out += "  (before: the loop's " + std::string(to_string(check.current_kind)) +
         " model; after: the " + std::string(to_string(check.other_kind)) + " model)\n";
  if (check.remaining.empty()) {
    out += "  the examination of the " + std::string(to_string(check.other_kind)) +
           " fit ranks no catalogue effect above the refit thresholds\n";
    return;
  }
  out += "  effects the " + std::string(to_string(check.other_kind)) +
         " fit still lacks, by the examination (not refitted):\n";
  candidate_table(out, check.remaining);
}

std::string effect_list(const std::vector<LoopStep>& steps) {
  std::string list;
  for (const LoopStep& step : steps) list += (list.empty() ? "" : ", ") + step.effect_name;
  return list;
}

}  // namespace

std::string LoopResult::brief_report() const {
  const ModelFigures first = model_figures(start_fit.summary);
  const ModelFigures last = model_figures(final_fit.summary);
  std::string out;
  out += printf_text("Residual loop: %zu effect%s added%s; %d fits, %.2f s.\n", steps.size(),
                     steps.size() == 1 ? "" : "s",
                     steps.empty() ? "" : (" (" + effect_list(steps) + ")").c_str(), fits,
                     total_time_s);
  out += "Window RMSE of omega, held out: " + number(first.held_out_rmse_rad_s) + " -> " +
         number(last.held_out_rmse_rad_s) + " rad/s; fitted: " + number(first.fitted_rmse_rad_s) +
         " -> " + number(last.fitted_rmse_rad_s) + " rad/s.\n";
  for (const LoopStep& step : steps) {
    out += printf_text(
        "Step %d: %s (explains %s of the residual, z %.3g%s, rank %d of %zu):", step.number,
        step.effect_name.c_str(), percent(step.explained_fraction).c_str(), step.score_z,
        step.second_look ? " on the second look" : "", step.rank, step.candidates.size());
    for (const FittedParameter& parameter : step.parameters) {
      if (!parameter.free) continue;
      out += ' ';
      out += parameter_text(parameter);
      out += ';';
    }
    out += " held-out RMSE " + signed_percent(-step.held_out_improvement) + ", BIC " +
           printf_text("%+.4g", step.bic_change) + ".\n";
  }
  out += "Stopped: " + stop_reason + ".\n";
  if (structure.ran) out += "Structure check: " + structure.verdict + ".\n";
  return out;
}

std::string LoopResult::full_report() const {
  std::string out = brief_report();
  const FitOptions& fit = start_fit.summary.options;
  out +=
      "\nMethod (docs/residual-loop.md): each step ranks the candidate effects by the share of "
      "the rate residual's\nsum of squares their best amplitude explains (linearized window "
      "sensitivity, free parameters\nprojected out), refits the best that are significant, and "
      "accepts the one with the lowest\nheld-out RMSE among those that lower it by more than "
      "the threshold and lower BIC.\n";
  out += printf_text("  cross-validation folds %d, window %.3g s\n", fit.cross_validation_folds,
                     fit.window_s);
  out += printf_text(
      "  refit at most %d per step if it explains >= %s and z >= %.3g; accept if the "
      "held-out RMSE falls > %s and BIC falls > %.3g\n",
      options.refit_candidates, percent(options.min_explained_fraction).c_str(),
      options.min_score_z, percent(options.min_held_out_improvement).c_str(),
      options.min_bic_decrease);
  out += "\nStart model: " + std::string(to_string(start_fit.model.kind())) + ", " +
         describe_figures(model_figures(start_fit.summary)) + ", BIC " +
         number(model_figures(start_fit.summary).bic) + "\n";
  for (const LoopStep& step : steps) {
    out += printf_text("\nStep %d: added %s\n", step.number, step.effect_name.c_str());
    out += "  parameters (standard uncertainty):\n";
    for (const FittedParameter& parameter : step.parameters) {
      out += "    " + parameter_text(parameter) + "\n";
    }
    out += "  figures:\n";
    figures_table(out, step.before, step.after);
    out += "  candidates:\n";
    speed_band_line(out, step.speed_bands);
    candidate_table(out, step.candidates);
  }
  if (!last_candidates.empty()) {
    out += "\nLast examination (no step taken):\n";
    speed_band_line(out, last_speed_bands);
    candidate_table(out, last_candidates);
  }
  out += "\nStopped: " + stop_reason + ".\n";
  structure_section(out, structure);
  out += "\nFinal fit:\n" + final_fit.summary.brief_report();
  return out;
}

}  // namespace doorbench
