#pragma once
// The simulated bench whose sensors need calibrating (rigs/simulated-uncalibrated.toml)
// and last year's load-cell record it names (rigs/calibrations/), built in so that the
// calibration demo runs without the rigs folder.
#include <string_view>

namespace doorbench::calibration {

std::string_view uncalibrated_rig_text();
std::string_view uncalibrated_rig_load_cell_record_json();

}  // namespace doorbench::calibration
