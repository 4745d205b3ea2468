#pragma once
// Where a recording left a sensor's range: one line per sensor, for `calibration show
// SESSION` and `doorbench info SESSION` (docs/calibration.md, "Range warnings").
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"

namespace doorbench::calibration {

// The checks, per channel:
//  * an inclinometer: its signal at the end of the sensor's output (the rig's range_deg,
//    less 0.05°): inclinometer_range_warning;
//  * a gyroscope: its signal within saturation_margin_dps of the rig's range_dps
//    (saturated, as the gyroscope calibration flags it);
//  * any other channel, and those two when the session has no rig: physical values beyond
//    the range its record states (valid_min … valid_max) by more than 0.5 % of its span.
// A channel without a stated range is not checked; an inclinometer whose range cannot be
// known gets a line saying so.
struct RangeWarningOptions {
  double saturation_margin_dps = 0.5;
  double record_tolerance_fraction = 0.005;  // of the record's valid span
  std::string validate() const;
};

std::vector<std::string> range_warnings(const SessionReader& session,
                                        const RangeWarningOptions& options = {});

}  // namespace doorbench::calibration
