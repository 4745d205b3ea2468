#include "sensors/channel_limits.h"

#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/units.h"
#include "sensors/sensor_models.h"

namespace doorbench::sensors {

namespace {

std::string range_text(double range, const char* unit) {
  char text[64];
  std::snprintf(text, sizeof text, "±%g %s", range, unit);
  return text;
}

}  // namespace

double inclinometer_limit_V(const InclinometerParameters& parameters) {
  return kAtLimitFraction * parameters.range_deg * parameters.output_V_per_deg;
}

double gyroscope_limit_V(const GyroscopeParameters& parameters) {
  return kAtLimitFraction * parameters.range_dps * parameters.output_V_per_dps;
}

std::vector<ChannelLimit> rig_channel_limits(const RigDefinition& rig) {
  std::vector<ChannelLimit> limits;
  for (const RigChannel& channel : rig.channels) {
    if (channel.sensor == "inclinometer") {
      InclinometerParameters p;
      for (const auto& [name, value] : channel.parameters) p.set(name, value);
      limits.push_back({.channel = channel.name,
                        .sensor = channel.sensor,
                        .limit = kAtLimitFraction * p.range_deg * kRadPerDeg,
                        .range = range_text(p.range_deg, "deg")});
    } else if (channel.sensor == "gyroscope") {
      GyroscopeParameters p;
      for (const auto& [name, value] : channel.parameters) p.set(name, value);
      limits.push_back({.channel = channel.name,
                        .sensor = channel.sensor,
                        .limit = kAtLimitFraction * p.range_dps * kRadPerDeg,
                        .range = range_text(p.range_dps, "deg/s")});
    }
  }
  return limits;
}

std::vector<ChannelLimit> session_channel_limits(const SessionMetadata& metadata) {
  const std::optional<RigDefinition> rig =
      parse_stored_rig(metadata.rig_definition, "the session's rig " + metadata.rig_name);
  return rig ? rig_channel_limits(*rig) : std::vector<ChannelLimit>{};
}

std::vector<SampleStretch> limit_stretches(const std::vector<double>& values, double limit) {
  std::vector<SampleStretch> stretches;
  bool at = false;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const bool now = std::abs(values[i]) >= limit;  // NaN: false
    if (now && !at) stretches.push_back({i, i});
    if (now) stretches.back().end = i + 1;
    at = now;
  }
  return stretches;
}

}  // namespace doorbench::sensors
