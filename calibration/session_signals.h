#pragma once
// A session's channel as the procedures need it: times, the signal (V, before any
// calibration) and the physical values through the channel's current record, plus the
// rig the session was recorded with (for the sensors' ranges).
#include <optional>
#include <string>
#include <vector>

#include "acquisition/rig/rig_file.h"
#include "acquisition/session/session_file.h"
#include "acquisition/rig/calibration_record.h"

namespace doorbench::calibration {

struct ChannelSignal {
  ChannelInfo info;
  std::optional<CalibrationRecord> record;  // the channel's current record, if it has one
  std::vector<double> time_s;               // as stored (not corrected for the record's delay)
  std::vector<double> signal;               // raw_offset + raw_scale · raw
  std::vector<double> physical;             // through the record (the signal when there is none)
};

ChannelSignal read_channel_signal(const SessionReader& session, const std::string& channel);

// The name of the session's channel of this sensor kind called `name`, or its only one
// when `name` is empty; "" when `optional` and there is none. Throws CalibrationError.
std::string find_session_channel(const SessionReader& session, const std::string& sensor_kind,
                                 const std::string& name, bool optional = false);

// The rig the session was recorded with (metadata/rig_definition), if it has one that
// parses.
std::optional<RigDefinition> session_rig(const SessionReader& session);

}  // namespace doorbench::calibration
