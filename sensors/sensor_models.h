#pragma once
// Sensor models: each maps the physical truth to the raw signal a real sensor and DAQ
// would give, with its documented imperfections. Parameters (constant) are apart from
// state (filter memory, hysteresis, bias drift, the seeded noise generator), as in the
// door models. Calibration (calibration/) maps back; the nominal scale factors
// (LoadCellParameters::volts_per_newton(), InclinometerParameters::volts_per_rad(),
// GyroscopeParameters::volts_per_rad_s()) give the datasheet's ideal inverse, used by the
// simulated bench's nominal calibration records. See docs/sensor-models.md.
//
// Units: forces in N, angles in rad at the boundary (degrees only in parameter names that
// say so), rates in rad/s, signals in V, DAQ samples in counts.
//
// Thread safety: a sensor object is used by one thread; parameters may be shared.
//
// Every *Parameters struct lists its fields (fields(): name = the C++ field name, unit,
// meaning), sets one by name (set()) and checks itself (validate(): "" when usable, else
// one line `SENSOR FIELD = VALUE must be RULE` with SENSOR one of load_cell, inclinometer,
// gyroscope, daq, e.g. `load_cell full_scale_N = -1 must be > 0`). The constructors throw
// std::invalid_argument with that message.
//
// Noise comes from a std::mt19937_64 seeded with the constructor's seed through
// std::normal_distribution: the same seed gives the same samples (on one standard library).
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <string_view>

#include "acquisition/rig/sensor_parameters.h"

namespace doorbench::sensors {

// ---------------------------------------------------------------------------------------
class LoadCell {
 public:
  LoadCell(const LoadCellParameters& parameters, std::uint64_t seed);  // throws on invalid
  // One sample: the force on the cell (N, compression positive) → the amplifier's output
  // (V). Chain: compression-only clamp max(F, 0) (if compression_only is 1) → play-operator
  // hysteresis of width w = hysteresis_fraction_fs · FS (the output moves only when the
  // input leaves [out − w/2, out + w/2], starting from 0) → + non-linearity bow →
  // + zero_offset_N → + white noise → clip at ± overload_fraction_fs · FS → · volts_per_newton().
  double sample_V(double force_N);
  const LoadCellParameters& parameters() const { return parameters_; }

 private:
  LoadCellParameters parameters_;
  std::mt19937_64 random_;
  std::normal_distribution<double> unit_normal_{0.0, 1.0};
  double play_output_N_ = 0.0;  // hysteresis state
};

// ---------------------------------------------------------------------------------------
class Inclinometer {
 public:
  // The filter is discretized exactly for `sample_rate_hz` (zero-order hold input).
  // Throws std::invalid_argument on invalid parameters or a sample rate that is not > 0.
  Inclinometer(const InclinometerParameters& parameters, double sample_rate_hz, std::uint64_t seed);
  // One sample: the true angle (rad) → the output (V). Chain: degrees → first-order
  // low-pass y += (1 − pole)(x − y) (the output is the updated y) → + offset_deg →
  // + white noise → saturate at ± range_deg → · output_V_per_deg.
  double sample_V(double angle_rad);
  // Starts the filter settled at this angle (as after a long rest). The filter starts at 0.
  void settle(double angle_rad);
  const InclinometerParameters& parameters() const { return parameters_; }

 private:
  InclinometerParameters parameters_;
  double filter_pole_;  // exp(−2π f_c / f_s)
  std::mt19937_64 random_;
  std::normal_distribution<double> unit_normal_{0.0, 1.0};
  double filtered_deg_ = 0.0;
};

// ---------------------------------------------------------------------------------------
class Gyroscope {
 public:
  // Throws std::invalid_argument on invalid parameters or a sample rate that is not > 0.
  Gyroscope(const GyroscopeParameters& parameters, double sample_rate_hz, std::uint64_t seed);
  // One sample: the true rate (rad/s) → the output (V). Chain: °/s · (1 + scale_factor_error)
  // + current bias + white noise; then the bias takes a random-walk step
  // N(0, bias_random_walk · sqrt(1/sample_rate)); the reading saturates at ± range_dps and
  // is scaled by output_V_per_dps.
  double sample_V(double rate_rad_s);
  double current_bias_dps() const { return bias_dps_; }
  const GyroscopeParameters& parameters() const { return parameters_; }

 private:
  GyroscopeParameters parameters_;
  double sample_interval_s_;
  std::mt19937_64 random_;
  std::normal_distribution<double> unit_normal_{0.0, 1.0};
  double bias_dps_;
};

// ---------------------------------------------------------------------------------------
class Daq {
 public:
  explicit Daq(const DaqParameters& parameters);  // throws on invalid
  // Rounds (volts − min)/(max − min) · max_count() to the nearest count, clipped to
  // 0 … max_count() (NaN gives 0).
  std::int32_t to_counts(double volts) const;
  // The count's centre, min + counts · volts_per_count() (linear beyond the range).
  double to_volts(std::int32_t counts) const;
  std::int32_t max_count() const;  // 2^bits − 1
  double volts_per_count() const;  // (max − min) / max_count()
  // Skew within a scan: channel_index · convert_interval_s.
  double channel_time_offset_s(int channel_index) const;
  const DaqParameters& parameters() const { return parameters_; }

 private:
  DaqParameters parameters_;
};

}  // namespace doorbench::sensors
