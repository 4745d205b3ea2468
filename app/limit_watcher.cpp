#include "app/limit_watcher.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/number_format.h"

namespace doorbench::app {

namespace {

std::string seconds(double s) {
  return printf_text("%.1f s", s);
}

}  // namespace

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
    for (const ChannelInfo& channel : session.channels())
      recorded |= channel.name == w.limit.channel;
    if (!recorded) continue;
    const ChannelSlice slice = session.read(w.limit.channel);
    const std::vector<double> values = session.physical(w.limit.channel, slice);
    w = Watched{w.limit};
    for (const sensors::SampleStretch& stretch : sensors::limit_stretches(values, w.limit.limit)) {
      if (w.stretches == 0) w.first_s = slice.time_s[stretch.begin];
      ++w.stretches;
      for (std::size_t i = stretch.begin; i < stretch.end && values.size() > 1; ++i) {
        const std::size_t next = i + 1 < values.size() ? i + 1 : i;
        const std::size_t previous = i + 1 < values.size() ? i : i - 1;
        w.total_s += slice.time_s[next] - slice.time_s[previous];
      }
      w.at_limit = stretch.end == values.size();
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
