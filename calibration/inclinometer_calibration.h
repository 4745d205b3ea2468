#pragma once
// Inclinometer calibration against reference angles (a tilt table or a precision level)
// across its range: offset and gain by least squares, with uncertainty; and the warning
// whenever a recording leaves the inclinometer's range.
#include <span>
#include <string>
#include <vector>

#include "acquisition/session_file.h"
#include "calibration/calibration_record.h"
#include "calibration/guided_procedure.h"
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

// Where a recording's inclinometer is outside its range (saturated): the intervals.
struct RangeExcursion {
  double start_s = 0.0, end_s = 0.0;
};
std::vector<RangeExcursion> inclinometer_range_excursions(const SessionReader& session,
                                                          const std::string& channel,
                                                          double range_deg = 0.0,
                                                          double margin_deg = 0.05);
// One line, or "" when the recording stays in range: "inclinometer angle left its ±10°
// range 6 times for 12.3 s in all (first at 0.98 s); those samples are not angles".
std::string inclinometer_range_warning(const SessionReader& session, const std::string& channel,
                                       double range_deg = 0.0);

}  // namespace doorbench::calibration
