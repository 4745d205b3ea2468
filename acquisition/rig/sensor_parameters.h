#pragma once
// The sensors' parameter sets: what a rig file's channel may say about its load cell,
// inclinometer, gyroscope and DAQ (rig_file.h reads them by name). They live at the bottom
// layer, beside the rig description that names them; the sensor models that use them to
// simulate a sensor (sensors/sensor_models.h, docs/sensor-models.md) are a layer above.
//
// Units: forces in N, angles in degrees only where the field name says so, rates in deg/s
// where it says dps, signals in V.
//
// Every *Parameters struct lists its fields (fields(): name = the C++ field name, unit,
// meaning), sets one by name (set()) and checks itself (validate(): "" when usable, else
// one line `SENSOR FIELD = VALUE must be RULE` with SENSOR one of load_cell, inclinometer,
// gyroscope, daq, e.g. `load_cell full_scale_N = -1 must be > 0`).
//
// Thread safety: plain values; const methods may be called from any thread.
#include <span>
#include <string>
#include <string_view>

namespace doorbench {

// A named numeric parameter, for rig files: each *Parameters struct lists its fields so
// that a rig file can set them by name (unknown names are rejected by the caller).
struct ParameterField {
  std::string_view name;
  std::string_view unit;
  std::string_view meaning;
};

struct LoadCellParameters {
  double full_scale_N = 445.0;        // rated capacity
  double sensitivity_mV_per_V = 2.0;  // bridge output at full scale per volt of excitation
  double excitation_V = 10.0;
  double amplifier_gain = 500.0;           // V/V, bridge to DAQ: 2 mV/V · 10 V · 500 = 10 V at FS
  double noise_rms_N = 0.2;                // white (per sample), referred to the force
  double nonlinearity_fraction_fs = 5e-4;  // largest deviation from the straight line / FS,
                                           // a bow 4·nl·F·(1 − |F|/FS), largest at ±FS/2
                                           // (nl·FS there; beyond FS the bow keeps growing)
  double hysteresis_fraction_fs = 3e-4;    // loading vs unloading difference / FS (a play
                                           // operator of that width)
  double overload_fraction_fs = 1.5;       // the output clips at ± this × FS
  double zero_offset_N = 0.0;              // unloaded reading
  double compression_only = 1.0;           // 1: reads max(F, 0) (the bench's cell); 0: both ways

  static std::span<const ParameterField> fields();
  bool set(std::string_view name, double value);  // false for an unknown name
  std::string validate() const;  // empty when usable, else one line naming the field
  // Nominal: sensitivity (mV/V) · 1e-3 · excitation · gain / FS (V/N).
  double volts_per_newton() const;
};

struct InclinometerParameters {
  double range_deg = 10.0;     // the output saturates beyond ± this
  double bandwidth_hz = 10.0;  // first-order low-pass (−3 dB)
  double noise_rms_deg = 0.01;
  double offset_deg = 0.0;        // reading when level
  double output_V_per_deg = 0.4;  // ±10° → ±4 V

  static std::span<const ParameterField> fields();
  bool set(std::string_view name, double value);
  std::string validate() const;
  double volts_per_rad() const;  // nominal: output_V_per_deg · 180/π
};

struct GyroscopeParameters {
  double range_dps = 100.0;     // the output saturates beyond ± this
  double noise_rms_dps = 0.05;  // white, per sample
  double bias_dps = 0.2;        // initial bias
  double bias_random_walk_dps_per_sqrt_s = 0.005;
  double scale_factor_error = 0.0;  // reads (1 + this) · rate
  double output_V_per_dps = 0.025;  // ±100 °/s → ±2.5 V

  static std::span<const ParameterField> fields();
  bool set(std::string_view name, double value);
  std::string validate() const;
  double volts_per_rad_s() const;  // nominal: output_V_per_dps · 180/π
};

// A multiplexed analog-input converter: all channels share one sample clock; within a
// scan, channel k is converted k · convert_interval_s after the scan starts.
struct DaqParameters {
  double range_min_V = -10.0;
  double range_max_V = 10.0;
  double resolution_bits = 16;  // an integer in [8, 24]; counts 0 … 2^bits − 1
  double sample_rate_hz = 1000.0;
  double convert_interval_s = 10e-6;  // >= 0; keeping (channels − 1) · this below
                                      // 1 / sample_rate_hz is the caller's concern

  static std::span<const ParameterField> fields();
  bool set(std::string_view name, double value);
  std::string validate() const;
};

// "" when sample_rate_hz is finite and > 0, else `SENSOR sample_rate_hz = VALUE must be > 0`
// (or `... must be finite`).
std::string sample_rate_violation(std::string_view sensor, double sample_rate_hz);

}  // namespace doorbench
