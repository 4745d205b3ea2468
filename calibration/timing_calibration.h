#pragma once
// Timing: the delay between the inclinometer and the gyroscope (the inclinometer's
// low-pass makes it lag), found by cross-correlating the inclinometer's angle with the
// integrated gyroscope rate on the stretches of strokes within the inclinometer's range.
// The delay goes into a new version of the inclinometer's record (delay_s), and readers
// shift the channel back by it. The same alignment gives the gyroscope's scale factor.
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "acquisition/rig/calibration_record.h"
#include "calibration/gyro_calibration.h"
#include "calibration/procedure.h"

namespace doorbench::calibration {

struct AlignmentOptions {
  double max_delay_s = 0.2;   // the delay is searched in [−this, +this]
  double min_travel_deg = 2;  // a segment must move the door at least this much
  // A segment is a run of inclinometer samples within its range (less the margin) and
  // within motion_pad_s of a sample where the door turns faster than motion_rate_dps.
  double motion_rate_dps = 2.0;
  double motion_pad_s = 0.15;
  int min_segments = 2;
  std::string validate() const;
};

struct AlignmentSegment {
  double start_s = 0.0, end_s = 0.0;
  std::size_t samples = 0;
  double travel_deg = 0.0;
  double delay_without_s = 0.0;  // the delay found without this segment (jackknife)
};

// inclinometer(t) ≈ a_k + gain · Θ(t − delay), Θ the integrated rate, a_k one offset per
// segment: least squares over the delay (a cross-correlation normalised per segment).
struct Alignment {
  double delay_s = 0.0, delay_std_s = 0.0;
  double gain = 1.0, gain_std = 0.0;  // inclinometer angle per integrated gyroscope angle
  double residual_std_rad = 0.0;
  std::vector<AlignmentSegment> segments;
};

// Uniform gyroscope clock. `inclinometer_in_range[j]` says whether sample j is inside the
// inclinometer's range (less its margin); `gyro_valid[i]` is false for saturated samples
// (segments near them are left out). Throws CalibrationError with fewer than min_segments
// segments.
Alignment align_inclinometer_with_gyro(const std::vector<double>& inclinometer_time_s,
                                       const std::vector<double>& inclinometer_rad,
                                       const std::vector<bool>& inclinometer_in_range,
                                       const std::vector<double>& gyro_time_s,
                                       const std::vector<double>& gyro_rad_s,
                                       const std::vector<bool>& gyro_valid,
                                       const AlignmentOptions& options);

struct TimingCalibrationOptions {
  AlignmentOptions alignment;
  GyroCalibrationOptions gyro;  // for the gyroscope's bias and saturation
  std::string validate() const;
};

struct TimingCalibration {
  CalibrationRecord record;  // the inclinometer's current record with delay_s set
  Alignment alignment;
  double previous_delay_s = 0.0;  // what the current record said
  double gyro_bias_dps = 0.0;     // removed before integrating
  std::string brief_report() const;
};

TimingCalibration calibrate_timing(const SessionReader& session,
                                   const std::string& inclinometer_channel,
                                   const std::string& gyro_channel,
                                   const TimingCalibrationOptions& options,
                                   const RecordHeader& header);

// The inclinometer's in-range test for a session: |signal| within (range − margin) of the
// sensor's output, from the channel's parameters in the session's rig (or range_deg if
// > 0, with the nominal 0.4 V/°). Exposed for the range warnings.
std::vector<bool> inclinometer_in_range(const SessionReader& session, const std::string& channel,
                                        const std::vector<double>& signal_V, double range_deg,
                                        double margin_deg);

}  // namespace doorbench::calibration
