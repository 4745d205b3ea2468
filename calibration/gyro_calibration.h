#pragma once
// Rate-gyroscope calibration from a recording: the bias from still periods found
// automatically (the stillness test below), the bias drift across them, the scale factor
// against the inclinometer on the stretches of strokes within its range, and saturated
// samples flagged. docs/calibration.md states the test and the uncertainties.
#include <string>
#include <utility>
#include <vector>

#include "acquisition/session/session_file.h"
#include "acquisition/rig/calibration_record.h"
#include "calibration/procedure.h"

namespace doorbench::calibration {

// The stillness test. A sample is quiet when, over the centred window of window_s:
//  * the rate's standard deviation is at most max(noise_factor × σ̂, rate_std_floor_dps),
//    σ̂ being the rate's white noise estimated from the whole recording (second
//    differences, median absolute deviation: motion at 1 kHz hardly shows in them);
//  * where the inclinometer is within its range, its straight-line slope over the window is
//    at most max_inclinometer_rate_dps (the door is not creeping).
// A still period is a run of quiet samples with guard_s removed at both ends that still
// lasts min_duration_s. Only periods the inclinometer confirms (in range) give the bias
// when there is an inclinometer; without one, the periods whose mean is within
// consistency_dps of the median of all periods' means.
struct StillnessOptions {
  double window_s = 0.2;
  double noise_factor = 3.0;
  double rate_std_floor_dps = 0.02;
  double max_inclinometer_rate_dps = 0.2;
  double guard_s = 0.1;
  double min_duration_s = 0.25;
  double consistency_dps = 0.1;
  std::string validate() const;
};

struct StillPeriod {
  double start_s = 0.0, end_s = 0.0;
  std::size_t samples = 0;
  double mean_signal_V = 0.0;  // the gyroscope's mean signal
  double mean_rate_dps = 0.0;  // through the channel's current record: the bias it reads
  double std_rate_dps = 0.0;
  bool confirmed = false;  // the inclinometer was in range and still
  bool used = false;       // went into the bias
};

struct GyroCalibrationOptions {
  StillnessOptions stillness;
  // The gyroscope's range (°/s); samples within saturation_margin_dps of it are saturated.
  // 0: taken from the session's rig (the channel's range_dps parameter, default 100).
  double range_dps = 0.0;
  double saturation_margin_dps = 0.5;
  // The scale factor against the inclinometer (needs one in the session).
  bool estimate_scale = true;
  // Inclinometer range (°, 0: from the rig) and the margin kept from its ends.
  double inclinometer_range_deg = 0.0;
  double inclinometer_margin_deg = 0.5;
  std::string validate() const;
};

struct GyroCalibration {
  CalibrationRecord record;  // rad/s per V: the bias removed, the scale corrected
  std::vector<StillPeriod> still_periods;
  int bias_periods = 0;
  double noise_dps = 0.0;                     // σ̂, per sample
  double bias_dps = 0.0, bias_std_dps = 0.0;  // what the previous record read when still
  double drift_dps_per_s = 0.0, drift_std_dps_per_s = 0.0;  // the bias's straight-line trend
  bool scale_estimated = false;
  double scale_factor_error = 0.0, scale_factor_error_std = 0.0;  // reads (1 + this) × rate
  int scale_segments = 0;
  std::size_t saturated_samples = 0;
  std::vector<std::pair<double, double>> saturated_intervals;  // start, end (s)
  std::vector<std::string> warnings;

  std::string brief_report() const;
};

// The periods of a rate (°/s, uniform clock `rate_hz`) that pass the stillness test;
// `inclinometer_deg` (same samples; NaN where out of range or unknown) may be empty.
std::vector<StillPeriod> find_still_periods(const std::vector<double>& time_s,
                                            const std::vector<double>& rate_dps,
                                            const std::vector<double>& inclinometer_deg,
                                            const StillnessOptions& options, double* noise_dps);

// `gyro_channel` and `inclinometer_channel` may be "" for the session's only one (no
// inclinometer: bias only). Throws CalibrationError when no still period is found.
GyroCalibration calibrate_gyroscope(const SessionReader& session, const std::string& gyro_channel,
                                    const std::string& inclinometer_channel,
                                    const GyroCalibrationOptions& options,
                                    const RecordHeader& header);

}  // namespace doorbench::calibration
