#pragma once
// What every backend makes of a rig file's channel: its sensor model's parameters, its
// calibration record (the datasheet figures for "nominal", else the record the store
// resolves), and the ChannelInfo of a DAQ channel that records counts.
#include <stdexcept>
#include <string>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/session_file.h"

namespace doorbench::sensors {

// The channel's sensor-model parameters (sensors::*Parameters) from its rig entry; unknown
// names and invalid values throw std::invalid_argument naming the channel.
template <typename Parameters>
Parameters parameters_of(const RigChannel& channel) {
  Parameters parameters;
  for (const auto& [name, value] : channel.parameters) {
    if (!parameters.set(name, value)) {
      throw std::invalid_argument("channel " + channel.name + ": unknown parameter " + name);
    }
  }
  if (std::string problem = parameters.validate(); !problem.empty()) {
    throw std::invalid_argument("channel " + channel.name + ": " + problem);
  }
  return parameters;
}

// The datasheet calibration of a channel's sensor model (volts → its unit).
CalibrationRecord nominal_calibration(const RigChannel& channel);

// The record the channel's `calibration` key names: nominal_calibration() for "nominal",
// else the record resolved in the rig's calibration store. Errors (std::invalid_argument)
// start with the rig file's name.
CalibrationRecord rig_channel_calibration(const RigDefinition& rig, const RigChannel& channel);

// Where a DAQ channel's counts sit: signal (V) = raw_offset_V + raw_scale_V · counts, valid
// within range_min_V … range_max_V, sampled at sample_rate_hz from first_sample_time_s.
struct CountsChannelClock {
  double raw_offset_V = 0.0;
  double raw_scale_V = 1.0;
  double range_min_V = -10.0;
  double range_max_V = 10.0;
  double sample_rate_hz = 1000.0;
  double first_sample_time_s = 0.0;
};

// The session's ChannelInfo of a rig channel recorded as DAQ counts with `record`.
ChannelInfo counts_channel_info(const RigChannel& channel, const CalibrationRecord& record,
                                const CountsChannelClock& clock);

}  // namespace doorbench::sensors
