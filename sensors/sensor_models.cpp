#include "sensors/sensor_models.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/units.h"

namespace doorbench::sensors {
namespace {

void throw_if_invalid(const std::string& message) {
  if (!message.empty()) throw std::invalid_argument(message);
}

void check_sample_rate(std::string_view sensor, double sample_rate_hz) {
  throw_if_invalid(sample_rate_violation(sensor, sample_rate_hz));
}

}  // namespace

// --- load cell ------------------------------------------------------------------------

LoadCell::LoadCell(const LoadCellParameters& parameters, std::uint64_t seed)
    : parameters_(parameters), random_(seed) {
  throw_if_invalid(parameters_.validate());
}

double LoadCell::sample_V(double force_N) {
  const LoadCellParameters& p = parameters_;
  double force = force_N;
  if (p.compression_only != 0) force = std::max(force, 0.0);

  // Play operator: the output follows the input at half the width behind it.
  const double half_width = 0.5 * p.hysteresis_fraction_fs * p.full_scale_N;
  if (force > play_output_N_ + half_width) {
    play_output_N_ = force - half_width;
  } else if (force < play_output_N_ - half_width) {
    play_output_N_ = force + half_width;
  }
  double reading = play_output_N_;

  reading +=
      4.0 * p.nonlinearity_fraction_fs * reading * (1.0 - std::abs(reading) / p.full_scale_N);
  reading += p.zero_offset_N;
  reading += p.noise_rms_N * unit_normal_(random_);

  const double limit = p.overload_fraction_fs * p.full_scale_N;
  reading = std::clamp(reading, -limit, limit);
  return reading * p.volts_per_newton();
}

// --- inclinometer ---------------------------------------------------------------------

Inclinometer::Inclinometer(const InclinometerParameters& parameters, double sample_rate_hz,
                           std::uint64_t seed)
    : parameters_(parameters), filter_pole_(0.0), random_(seed) {
  throw_if_invalid(parameters_.validate());
  check_sample_rate("inclinometer", sample_rate_hz);
  filter_pole_ = std::exp(-2.0 * std::numbers::pi * parameters_.bandwidth_hz / sample_rate_hz);
}

double Inclinometer::sample_V(double angle_rad) {
  const InclinometerParameters& p = parameters_;
  const double angle_deg = angle_rad * kDegPerRad;
  filtered_deg_ += (1.0 - filter_pole_) * (angle_deg - filtered_deg_);
  double reading = filtered_deg_ + p.offset_deg + p.noise_rms_deg * unit_normal_(random_);
  reading = std::clamp(reading, -p.range_deg, p.range_deg);
  return reading * p.output_V_per_deg;
}

void Inclinometer::settle(double angle_rad) {
  filtered_deg_ = angle_rad * kDegPerRad;
}

// --- gyroscope ------------------------------------------------------------------------

Gyroscope::Gyroscope(const GyroscopeParameters& parameters, double sample_rate_hz,
                     std::uint64_t seed)
    : parameters_(parameters),
      sample_interval_s_(0.0),
      random_(seed),
      bias_dps_(parameters.bias_dps) {
  throw_if_invalid(parameters_.validate());
  check_sample_rate("gyroscope", sample_rate_hz);
  sample_interval_s_ = 1.0 / sample_rate_hz;
}

double Gyroscope::sample_V(double rate_rad_s) {
  const GyroscopeParameters& p = parameters_;
  const double rate_dps = rate_rad_s * kDegPerRad;
  double reading =
      rate_dps * (1.0 + p.scale_factor_error) + bias_dps_ + p.noise_rms_dps * unit_normal_(random_);
  bias_dps_ +=
      p.bias_random_walk_dps_per_sqrt_s * std::sqrt(sample_interval_s_) * unit_normal_(random_);
  reading = std::clamp(reading, -p.range_dps, p.range_dps);
  return reading * p.output_V_per_dps;
}

// --- DAQ ------------------------------------------------------------------------------

Daq::Daq(const DaqParameters& parameters) : parameters_(parameters) {
  throw_if_invalid(parameters_.validate());
}

std::int32_t Daq::max_count() const {
  const int bits = static_cast<int>(parameters_.resolution_bits);
  return static_cast<std::int32_t>((std::int64_t{1} << bits) - 1);
}

double Daq::volts_per_count() const {
  return (parameters_.range_max_V - parameters_.range_min_V) / max_count();
}

std::int32_t Daq::to_counts(double volts) const {
  const std::int32_t top = max_count();
  const double position =
      (volts - parameters_.range_min_V) / (parameters_.range_max_V - parameters_.range_min_V) * top;
  if (!(position > 0)) return 0;  // below the range, or NaN
  if (position >= top) return top;
  return static_cast<std::int32_t>(std::round(position));
}

double Daq::to_volts(std::int32_t counts) const {
  return parameters_.range_min_V + counts * volts_per_count();
}

double Daq::channel_time_offset_s(int channel_index) const {
  return channel_index * parameters_.convert_interval_s;
}

}  // namespace doorbench::sensors
