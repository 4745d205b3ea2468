#pragma once
// Live sensor-limit warnings for `doorbench record`: which channel sits at the
// end of its sensor's range, since when and for how long, from the recorder's status
// callback (RecordOptions::progress: each channel's largest |value| since the previous
// call, ChannelStatus::largest_abs, and its latest value), for
// the status line and for the summary after the recording. The limits come from the rig
// (sensors/channel_limits.h: the sensor's range less 1 %).
// `doorbench info` checks every sample afterwards (calibration/range_warnings.h). Live,
// this counts time per status call (several a second on a running DAQ; an unpaced simulated
// bench makes few), so the status line's times are approximate: the time since the previous
// status counts as at the limit when the channel reached it in between. The summary's are
// exact: measure() counts the recorded samples at the limit once the session is written.
//
// Thread safety: one thread calls update() (the recorder's writer thread); the text
// functions may be called from it or after the recording ended, not concurrently.
#include <string>
#include <vector>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"
#include "sensors/channel_limits.h"

namespace doorbench::app {

// The limits' definition, shared with the viewer's shaded stretches: sensors/channel_limits.h.
using sensors::ChannelLimit;
using sensors::rig_channel_limits;

class LimitWatcher {
 public:
  explicit LimitWatcher(std::vector<ChannelLimit> limits);
  bool empty() const { return watched_.empty(); }
  // One status of the recording: a channel whose latest value is at its limit counts the
  // time since the previous status as time at the limit; a new stretch starts when the
  // previous status found it below.
  void update(const RecordStatus& status);
  // For the status line: "" when no channel has been at its limit, else e.g. "; AT LIMIT
  // rate (gyroscope ±100 deg/s) now, 1.2 s so far".
  std::string status_text() const;
  // After the recording: each watched channel's time at its limit, its stretches and the
  // first time, from every recorded sample (|physical value| >= limit; a sample stands for
  // the time to the next one, the last for the one before it). Replaces the live figures.
  // Throws SessionError for a session that cannot be read.
  void measure(const SessionReader& session);
  // One line per channel that reached its limit, e.g. "gyroscope rate at its ±100 deg/s
  // limit for 2.3 s in all, 3 times (first at 1.1 s)".
  std::vector<std::string> summary() const;

 private:
  struct Watched {
    ChannelLimit limit;
    bool at_limit = false;
    int stretches = 0;
    double first_s = 0.0;
    double total_s = 0.0;
  };
  std::vector<Watched> watched_;
  double last_recorded_s_ = 0.0;
};

}  // namespace doorbench::app
