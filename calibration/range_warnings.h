#pragma once
// Where a recording left a sensor's range: one line per sensor, for `calibration show
// SESSION` and `doorbench info SESSION` (docs/calibration.md, "Range warnings").
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"

namespace doorbench::calibration {

// The checks, per channel:
//  * an inclinometer or a gyroscope on the session's rig: its signal at its sensor's limit,
//    the rule of sensors/channel_limits.h that `record` warns about live (99 % of the rig's
//    range_deg or range_dps): inclinometer_range_warning for an inclinometer;
//  * any other channel, and those two when the session has no rig: physical values beyond
//    the range its record states (valid_min … valid_max) by more than 0.5 % of its span.
// A channel without a stated range is not checked; an inclinometer whose range cannot be
// known gets a line saying so.
struct RangeWarningOptions {
  double record_tolerance_fraction = 0.005;  // of the record's valid span
  std::string validate() const;
};

std::vector<std::string> range_warnings(const SessionReader& session,
                                        const RangeWarningOptions& options = {});

}  // namespace doorbench::calibration
