#pragma once
// The calibration part of `doorbench demo`: the simulated bench whose sensors are off in
// known ways (rigs/simulated-uncalibrated.toml, built in) is calibrated — load cell and
// inclinometer by the guided procedure with a simulated operator, gyroscope and timing
// from a recording — and the errors against the simulation's truth are shown before and
// after. Works in a scratch folder that it removes; takes a few seconds.
#include <iosfwd>

namespace doorbench::app {

void run_calibration_demo(std::ostream& out);

}  // namespace doorbench::app
