#pragma once
// Where a channel sits at the end of its sensor's range: the one definition that
// `doorbench record` warns about, live and in its summary (app/limit_watcher.h), that the
// viewer shades in its channels layout, and that `doorbench info` and `calibration show`
// report afterwards (calibration/range_warnings.h). The limits come from the rig: an
// inclinometer's range_deg (default 10 deg) and a gyroscope's range_dps (default 100 deg/s),
// less 1 % (kAtLimitFraction: a saturated reading, bias and noise included, lands within it);
// a sample is at the limit when |physical value| >= limit, or, read before calibration, when
// |signal| >= the same limit on the sensor's output (inclinometer_limit_V, gyroscope_limit_V).
//
// Pure functions: safe from any thread.
#include <cstddef>
#include <string>
#include <vector>

#include "acquisition/rig/rig_file.h"
#include "acquisition/rig/sensor_parameters.h"
#include "acquisition/session/session_file.h"

namespace doorbench::sensors {

// The fraction of a sensor's range at and beyond which a reading is at its limit.
inline constexpr double kAtLimitFraction = 0.99;

// The limit on the sensor's output signal (V): kAtLimitFraction of the range times the
// output's nominal volts per unit.
double inclinometer_limit_V(const InclinometerParameters& parameters);
double gyroscope_limit_V(const GyroscopeParameters& parameters);

struct ChannelLimit {
  std::string channel;  // the rig's channel name (as recorded)
  std::string sensor;   // inclinometer | gyroscope
  double limit = 0.0;   // |physical value| at or beyond this is at the limit (rad, rad/s)
  std::string range;    // the sensor's range for messages, e.g. "±100 deg/s"
};

// The rig's channels with a known sensor range (inclinometers and gyroscopes, in rad and
// rad/s); others are not watched.
std::vector<ChannelLimit> rig_channel_limits(const RigDefinition& rig);

// The limits of the rig a session was recorded on (its metadata's rig_definition); empty
// when the session states no rig or its text does not parse.
std::vector<ChannelLimit> session_channel_limits(const SessionMetadata& metadata);

// A run of consecutive samples at the limit: indices [begin, end).
struct SampleStretch {
  std::size_t begin = 0;
  std::size_t end = 0;
};
// The runs of `values` with |value| >= limit, in order (NaN, a lost sample, is not at it).
std::vector<SampleStretch> limit_stretches(const std::vector<double>& values, double limit);

}  // namespace doorbench::sensors
