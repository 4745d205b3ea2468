#include "analysis/fit/fit_init.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "analysis/fit/fit_start.h"
#include "analysis/model/sensory_model.h"
#include "core/number_format.h"

namespace doorbench {

namespace {

// Moving: |ω| above this or 3 σ_ω, whichever is larger.
constexpr double kMovingFloor_rad_s = 0.02;
// Fewer samples of free motion than this: J and the friction stay the base's.
constexpr int kMinimumFreeMotionSamples = 20;

// Widens `bounds` to hold [low, high] (never below `floor`).
void widen(Bounds& bounds, double low, double high, double floor = 0.0) {
  bounds.lower = std::max(floor, std::min(bounds.lower, low));
  bounds.upper = std::max(bounds.upper, high);
}

}  // namespace

DataStart start_from_data(const PreparedData& data, const DoorModel& base) {
  if (base.kind() != ModelKind::kSensory) {
    throw std::invalid_argument("start values from the data: only for the sensory model");
  }
  if (data.strokes.empty()) {
    throw std::invalid_argument("start values from the data: the data has no strokes");
  }
  const auto base_values = base.parameter_values();
  const auto base_bounds = base.parameter_bounds();
  const auto count = static_cast<std::size_t>(base.base_parameter_count());
  std::vector<double> values(base_values.begin(), base_values.begin() + count);
  std::vector<Bounds> bounds(base_bounds.begin(), base_bounds.begin() + count);
  DataStart out{base, std::vector<std::string>(count, "reference door"), 0, 0.0, 0.0, {}};
  const double r_h = base.geometry().handle_radius_m;
  const double s = values[sensory::kS];
  const double theta4 = values[sensory::kTheta4];
  const double zone_rad =
      std::min(std::max(0.12, 2.0 * values[sensory::kTheta3]), 0.5 * base.geometry().theta_max_rad);
  const double moving_rad_s = std::max(kMovingFloor_rad_s, 3.0 * data.rate_noise_rad_s);
  const double half_width_s = std::max(0.005, 1.5 * data.interval_median_s);

  // Free motion: y = J α + d_open tanh(s ω)[θ > θ4] + d_near tanh(s ω)[θ <= θ4] + g1 sin θ + b.
  Eigen::Matrix<double, 5, 5> normal = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 1> right = Eigen::Matrix<double, 5, 1>::Zero();
  int samples = 0, near_samples = 0, open_samples = 0;
  for (const Stroke& stroke : data.strokes) {
    const std::vector<double> acceleration = rate_derivative(stroke, half_width_s);
    for (std::size_t i = 1; i + 1 < stroke.size(); ++i) {
      const double theta = stroke.theta_rad[i], omega = stroke.omega_rad_s[i];
      if (theta <= zone_rad || std::abs(omega) <= moving_rad_s) continue;
      const double friction = std::tanh(s * omega);
      const bool open = theta > theta4;
      Eigen::Matrix<double, 5, 1> row;
      row << acceleration[i], open ? friction : 0.0, open ? 0.0 : friction, std::sin(theta), 1.0;
      normal += row * row.transpose();
      right += row * (r_h * stroke.force_N[i]);
      ++samples;
      ++(open ? open_samples : near_samples);
    }
  }
  out.free_motion_samples = samples;
  if (samples >= kMinimumFreeMotionSamples) {
    // Columns without samples (no motion on one side of θ4) are pinned to zero.
    if (open_samples == 0) normal(1, 1) = 1.0;
    if (near_samples == 0) normal(2, 2) = 1.0;
    const Eigen::Matrix<double, 5, 1> c = normal.ldlt().solve(right);
    const double inertia = c(0);
    if (c.allFinite() && inertia > 0) {
      const double d_open = open_samples > 0 ? std::max(0.0, c(1)) : values[sensory::kD1];
      const double d_near = near_samples > 0 ? std::max(0.0, c(2)) : d_open;
      values[sensory::kJ] = inertia;
      widen(bounds[sensory::kJ], 0.25 * inertia, 4.0 * inertia, 1e-6);
      values[sensory::kD1] = d_open;
      values[sensory::kD2] = std::clamp(d_open - d_near, 0.0, d_open);
      const double friction_upper = std::max(5.0 * d_open, 1.0);
      widen(bounds[sensory::kD1], 0.0, friction_upper);
      widen(bounds[sensory::kD2], 0.0, friction_upper);
      out.origin[sensory::kJ] = out.origin[sensory::kD1] = out.origin[sensory::kD2] = "free motion";
      out.balance_torque_Nm = c(3);
      out.force_offset_N = c(4) / r_h;
      if (open_samples == 0 || near_samples == 0) {
        out.notes.push_back("no free motion " + std::string(open_samples == 0 ? "above" : "below") +
                            " theta4 = " + format_number(theta4) +
                            " rad: d2 is not read (0), the friction one level");
      }
    } else {
      out.notes.push_back(
          "free motion gave no positive inertia: J, d1, d2 are the reference door's");
    }
  } else {
    out.notes.push_back("only " + std::to_string(samples) +
                        " samples of free motion (moving, above " + format_number(zone_rad) +
                        " rad): J, d1, d2 are the reference door's");
  }
  // The latch, read off with the data's J.
  DoorModel with_inertia = DoorModel(ModelKind::kSensory, base.geometry(), values, bounds);
  const LatchReadOff latch = read_latch_start(data, with_inertia, data.rate_noise_rad_s);
  for (const std::string& note : latch.notes) out.notes.push_back(note);
  const std::pair<int, std::optional<double>> readings[] = {
      {sensory::kTheta0, latch.theta0_rad},     {sensory::kTheta1, latch.theta1_rad},
      {sensory::kTheta2, latch.theta2_rad},     {sensory::kTheta3, latch.theta3_rad},
      {sensory::kKInf, latch.k_inf_Nm_per_rad}, {sensory::kKLock, latch.k_lock_Nm_per_rad}};
  std::vector<double> trial = values;
  std::vector<Bounds> trial_bounds = bounds;
  std::vector<int> read;
  const double theta_max = base.geometry().theta_max_rad;
  for (const auto& [index, reading] : readings) {
    if (!reading || !(*reading > 0)) continue;
    const bool angle = index >= sensory::kTheta0 && index <= sensory::kTheta3;
    if (angle) {
      widen(trial_bounds[index], 0.5 * *reading, std::min(2.0 * *reading, theta_max), 1e-6);
      trial_bounds[index].upper = std::min(trial_bounds[index].upper, theta_max);
    } else {
      widen(trial_bounds[index], 0.0, 4.0 * *reading);
    }
    trial[index] = std::clamp(*reading, trial_bounds[index].lower, trial_bounds[index].upper);
    read.push_back(index);
  }
  if (!read.empty()) {
    try {
      (void)DoorModel(ModelKind::kSensory, base.geometry(), trial, trial_bounds);
      values = trial;
      bounds = trial_bounds;
      for (int index : read) out.origin[index] = "latch read-off";
    } catch (const std::invalid_argument& error) {
      out.notes.push_back(std::string("the latch read off the data was not used: ") + error.what());
    }
  }
  out.model = DoorModel(ModelKind::kSensory, base.geometry(), values, bounds,
                        {base.effects().begin(), base.effects().end()});
  return out;
}

}  // namespace doorbench
