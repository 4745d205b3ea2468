#include "app/limit_watcher.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "analysis/text_format.h"
#include "sensors/sensor_models.h"

namespace doorbench::app {

namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
constexpr double kLimitFraction = 0.99;  // of the range: at the limit

std::string range_text(double range, const char* unit) {
  return printf_text("±%g %s", range, unit);
}

std::string seconds(double s) {
  return printf_text("%.1f s", s);
}

}  // namespace

std::vector<ChannelLimit> rig_channel_limits(const RigDefinition& rig) {
  std::vector<ChannelLimit> limits;
  for (const RigChannel& channel : rig.channels) {
    if (channel.sensor == "inclinometer") {
      sensors::InclinometerParameters p;
      for (const auto& [name, value] : channel.parameters) p.set(name, value);
      limits.push_back({channel.name, channel.sensor, kLimitFraction * p.range_deg * kRadPerDeg,
                        range_text(p.range_deg, "deg")});
    } else if (channel.sensor == "gyroscope") {
      sensors::GyroscopeParameters p;
      for (const auto& [name, value] : channel.parameters) p.set(name, value);
      limits.push_back({channel.name, channel.sensor, kLimitFraction * p.range_dps * kRadPerDeg,
                        range_text(p.range_dps, "deg/s")});
    }
  }
  return limits;
}

LimitWatcher::LimitWatcher(std::vector<ChannelLimit> limits) {
  for (ChannelLimit& limit : limits) watched_.push_back({std::move(limit)});
}

void LimitWatcher::update(const RecordStatus& status) {
  const double elapsed_s = std::max(0.0, status.recorded_s - last_recorded_s_);
  last_recorded_s_ = status.recorded_s;
  for (Watched& w : watched_) {
    bool found = false, at_limit = false;
    for (const ChannelStatus& channel : status.channels) {
      if (channel.name != w.limit.channel || channel.samples == 0) continue;
      found = true;
      at_limit = std::max(std::abs(channel.latest), channel.largest_abs) >= w.limit.limit;
    }
    if (!found) continue;
    if (at_limit && !w.at_limit) {
      if (w.stretches == 0) w.first_s = status.recorded_s;
      ++w.stretches;
    }
    // The time since the previous status is counted as at the limit when this one is:
    // statuses come several times a second, a stretch seen once still counts.
    if (at_limit) w.total_s += elapsed_s;
    w.at_limit = at_limit;
  }
}

void LimitWatcher::measure(const SessionReader& session) {
  for (Watched& w : watched_) {
    bool recorded = false;
    for (const ChannelInfo& channel : session.channels()) recorded |= channel.name == w.limit.channel;
    if (!recorded) continue;
    const ChannelSlice slice = session.read(w.limit.channel);
    const std::vector<double> values = session.physical(w.limit.channel, slice);
    w = Watched{w.limit};
    for (std::size_t i = 0; i < values.size(); ++i) {
      const bool at_limit = std::abs(values[i]) >= w.limit.limit;  // NaN (lost): not
      if (at_limit && !w.at_limit) {
        if (w.stretches == 0) w.first_s = slice.time_s[i];
        ++w.stretches;
      }
      if (at_limit && values.size() > 1) {
        const std::size_t next = i + 1 < values.size() ? i + 1 : i;
        const std::size_t previous = i + 1 < values.size() ? i : i - 1;
        w.total_s += slice.time_s[next] - slice.time_s[previous];
      }
      w.at_limit = at_limit;
    }
  }
}

std::string LimitWatcher::status_text() const {
  std::string text;
  for (const Watched& w : watched_) {
    if (w.stretches == 0) continue;
    text += "; AT LIMIT " + w.limit.channel + " (" + w.limit.sensor + " " + w.limit.range + ") " +
            (w.at_limit ? "now, " : "") + seconds(w.total_s) + " so far";
  }
  return text;
}

std::vector<std::string> LimitWatcher::summary() const {
  std::vector<std::string> lines;
  for (const Watched& w : watched_) {
    if (w.stretches == 0) continue;
    lines.push_back(w.limit.sensor + " " + w.limit.channel + " at its " + w.limit.range +
                    " limit for " + seconds(w.total_s) + " in all, " + std::to_string(w.stretches) +
                    (w.stretches == 1 ? " time" : " times") + " (first at " + seconds(w.first_s) +
                    ")");
  }
  return lines;
}

}  // namespace doorbench::app
