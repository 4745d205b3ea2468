#pragma once
// Inclinometer calibration against reference angles (a tilt table or a precision level)
// across its range: offset and gain by least squares, with uncertainty; and the warning
// whenever a recording leaves the inclinometer's range.
#include <span>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/session_file.h"
#include "calibration/guided_procedure.h"
#include "calibration/gyro_calibration.h"
#include "calibration/procedure.h"

namespace doorbench::calibration {

struct InclinometerCalibrationOptions {
  double range_deg = 10.0;        // the sensor's range (its output saturates beyond)
  double output_V_per_deg = 0.4;  // nominal, to recognise a saturated reading
  // References must lie within this fraction of the range: near its ends the sensor's own
  // offset can push the reading into saturation.
  double max_reference_fraction = 0.9;
  int min_references = 3;
  double min_span_fraction = 0.5;                   // of the whole range (2 × range_deg)
  double reference_standard_uncertainty_deg = 0.0;  // of the tilt table
  std::string references = "reference angles (tilt table)";
  std::string validate() const;
};

struct InclinometerCalibration {
  CalibrationRecord record;                       // rad per V
  double offset_deg = 0.0, offset_std_deg = 0.0;  // the sensor reads this when level
  double gain_rad_per_V = 0.0, gain_std_rad_per_V = 0.0;
  double residual_std_deg = 0.0;
  double standard_uncertainty_deg = 0.0;
  int points = 0;
  std::string brief_report() const;
};

// Points' references in rad. Throws CalibrationError for too few points, references
// outside the range or readings at the end of it (saturated).
InclinometerCalibration calibrate_inclinometer(std::span<const CalibrationPoint> points,
                                               const InclinometerCalibrationOptions& options,
                                               const RecordHeader& header);

// Guided points at these angles (°), in the order given.
std::vector<GuidedPoint> inclinometer_angle_points(std::span<const double> angles_deg);

// From a recording made while the operator held the inclinometer (or the door it is on) at
// the reference angles, in the order given, still at each and moving between them. The
// holds are found by the gyroscope calibration's stillness test (find_still_periods)
// applied to the inclinometer's angle (° through the channel's current record) instead of
// a rate: a sample is still when, over the centred window, the angle's standard deviation
// is at most max(noise_factor × σ̂, floor) and its straight-line slope at most the limit;
// a hold is a run of still samples, less the guard at both ends, lasting min_duration_s.
// Consecutive holds whose means differ by less than merge_deg are one hold (a touch that
// interrupted it); each must drift by at most max_drift_deg between its halves, the guided
// procedure's limit.
struct InclinometerRecordingOptions {
  StillnessOptions stillness{.window_s = 0.5,
                             .noise_factor = 3.0,
                             .rate_std_floor_dps = 0.05,  // here: the angle's sd floor, °
                             .max_inclinometer_rate_dps = 0.1,
                             .guard_s = 0.2,
                             .min_duration_s = 1.0,
                             .consistency_dps = 0.1};
  double max_drift_deg = 0.02;
  double merge_deg = 0.25;
  std::string validate() const;
};

struct InclinometerHold {
  double start_s = 0.0, end_s = 0.0;
  std::size_t samples = 0;
  double mean_deg = 0.0;  // through the channel's current record
  double drift_deg = 0.0;
  CalibrationPoint point;  // the reference matched to it, the mean signal (V) and its sd
};

struct InclinometerRecordingPoints {
  std::vector<InclinometerHold> holds;  // in time order, one per reference
  double noise_deg = 0.0;               // σ̂, per sample
  std::vector<CalibrationPoint> points() const;
  std::string brief_report() const;
};

// `channel` "" for the session's only inclinometer; it must have a record (for the angle
// the stillness test reads). Throws CalibrationError when the number of holds differs
// from the references (naming where each was found), when a hold does not follow the
// references' order, or drifts.
InclinometerRecordingPoints inclinometer_points_from_recording(
    const SessionReader& session, const std::string& channel, std::span<const double> angles_deg,
    const InclinometerRecordingOptions& options = {});

// Where a recording's inclinometer is at its sensor's limit (saturated; the rule of
// sensors/channel_limits.h, 99 % of range_deg, the rig's unless given): the intervals.
struct RangeExcursion {
  double start_s = 0.0, end_s = 0.0;
};
std::vector<RangeExcursion> inclinometer_range_excursions(const SessionReader& session,
                                                          const std::string& channel,
                                                          double range_deg = 0.0);
// One line, or "" when the recording stays in range: "inclinometer angle left its ±10°
// range 6 times for 12.3 s in all (first at 0.98 s); those samples are not angles".
std::string inclinometer_range_warning(const SessionReader& session, const std::string& channel,
                                       double range_deg = 0.0);

}  // namespace doorbench::calibration
