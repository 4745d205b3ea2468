#include "calibration/session_signals.h"

#include <algorithm>
#include <limits>

#include "calibration/procedure.h"

namespace doorbench::calibration {

ChannelSignal read_channel_signal(const SessionReader& session, const std::string& channel) {
  ChannelSignal s;
  s.info = session.channel(channel);
  if (!s.info.calibration_id.empty()) {
    for (const CalibrationRecord& r : session.calibrations()) {
      if (r.id == s.info.calibration_id) s.record = r;
    }
  }
  const ChannelSlice slice = session.read(channel);
  s.time_s = slice.time_s;
  s.signal.resize(slice.raw.size());
  s.physical.resize(slice.raw.size());
  for (std::size_t i = 0; i < slice.raw.size(); ++i) {
    if (is_lost_sample(s.info, slice.raw[i])) {  // a lost scan: missing, never a number
      s.signal[i] = s.physical[i] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    s.signal[i] = s.info.raw_offset + s.info.raw_scale * slice.raw[i];
    s.physical[i] = s.record ? s.record->apply(s.signal[i]) : s.signal[i];
  }
  return s;
}

std::string find_session_channel(const SessionReader& session, const std::string& sensor_kind,
                                 const std::string& name, bool optional) {
  std::vector<std::string> candidates;
  for (const ChannelInfo& c : session.channels()) {
    if (c.sensor_kind == sensor_kind) candidates.push_back(c.name);
  }
  std::string listed;
  for (const std::string& c : candidates) listed += (listed.empty() ? "" : ", ") + c;
  const std::string where = session.path().string() + ": ";
  if (!name.empty()) {
    if (std::find(candidates.begin(), candidates.end(), name) != candidates.end()) return name;
    throw CalibrationError(
        where + "no " + sensor_kind + " channel " + name +
        (listed.empty() ? "" : " (" + sensor_kind + " channels: " + listed + ")"));
  }
  if (candidates.empty()) {
    if (optional) return "";
    throw CalibrationError(where + "no " + sensor_kind + " channel");
  }
  if (candidates.size() > 1) {
    throw CalibrationError(where + "several " + sensor_kind + " channels (" + listed +
                           "); choose one with --channel");
  }
  return candidates.front();
}

std::optional<RigDefinition> session_rig(const SessionReader& session) {
  return parse_stored_rig(session.metadata().rig_definition,
                          session.path().string() + " (rig_definition)");
}

}  // namespace doorbench::calibration
