#pragma once
// Following a running recording (no GL, no ImGui): `doorbench record` writes S.h5.journal
// while it records (acquisition/record/journal.h, docs/crash-safety.md). A LiveJournal polls that
// file for frames appended since the last poll, converts them to physical values (the
// header's channels and calibration records; scans and polled timed samples) and keeps
// the last `capacity_samples` of each channel in a ring, so memory stays bounded however
// long the recording runs. An incomplete frame at the end is a frame still being written:
// the next poll resumes at the end of the last whole frame.
//
// States: waiting (no journal yet, or its header is not complete), recording, ended (the
// end frame was read), gone (the journal was converted to the session or removed; what had
// been written before is kept).
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "acquisition/record/journal.h"
#include "viewer/plot_view.h"

namespace doorbench::viewer {

struct LiveOptions {
  double window_s = 10.0;                  // the plots show the last window_s seconds
  std::size_t capacity_samples = 200'000;  // kept per channel (older ones are dropped)
  std::size_t max_events = 1000;           // kept (the oldest dropped first)
  // A channel's window with more samples than this is plotted as each bucket's min and max
  // (in time order), so a spike stays visible and a fast rig's update stays cheap.
  std::size_t max_plot_samples = 20'000;
  std::string validate() const;  // "" or one line naming the option
};

enum class LiveState { kWaiting, kRecording, kEnded, kGone };
const char* to_string(LiveState state);

// The last samples of one channel: a ring of (time, value), oldest first when read.
class SampleRing {
 public:
  explicit SampleRing(std::size_t capacity = 1);
  void push(double time_s, double value);
  std::size_t size() const { return size_; }
  std::size_t capacity() const { return time_.size(); }
  // The i-th oldest sample kept.
  double time(std::size_t i) const { return time_[(begin_ + i) % time_.size()]; }
  double value(std::size_t i) const { return value_[(begin_ + i) % time_.size()]; }
  std::uint64_t pushed() const { return pushed_; }  // ever, including dropped ones
  // Where the i-th oldest sample is in the storage below (which wraps at capacity()).
  std::size_t slot(std::size_t i) const { return (begin_ + i) % time_.size(); }
  const std::vector<double>& time_storage() const { return time_; }
  const std::vector<double>& value_storage() const { return value_; }

 private:
  std::vector<double> time_, value_;
  std::size_t begin_ = 0, size_ = 0;
  std::uint64_t pushed_ = 0;
};

// What one poll read.
struct LivePoll {
  std::size_t frames = 0;         // whole frames read
  std::size_t scans = 0;          // scans in them
  std::size_t timed_samples = 0;  // polled samples in them
  std::size_t events = 0;         // events in them
  bool state_changed = false;
};

class LiveJournal {
 public:
  // `path`: the journal, or the session being recorded (its journal is PATH.journal).
  // Throws std::invalid_argument for invalid options (the message names the option).
  LiveJournal(const std::filesystem::path& path, const LiveOptions& options = {});

  // Reads every whole frame appended since the last poll. Does not throw for a journal
  // that does not exist yet, a header still being written, or a torn last frame; throws
  // JournalError for a journal that is not one (wrong magic, a damaged header).
  LivePoll poll();

  LiveState state() const { return state_; }
  // One line for the status bar: state, time recorded, frames, and why it stopped or waits.
  std::string status() const;
  const std::filesystem::path& journal_path() const { return journal_; }
  bool has_header() const { return reader_ != nullptr; }
  const JournalHeader& header() const;  // only with has_header()

  // Per channel of the header (same order): the samples kept, physical units.
  const std::vector<SampleRing>& rings() const { return rings_; }
  const std::deque<SessionEvent>& events() const { return events_; }
  std::uint64_t frames_read() const { return frames_; }
  std::uint64_t scans_read() const { return scans_; }
  std::uint64_t valid_bytes() const;  // of the journal: the end of the last whole frame
  double latest_time_s() const { return latest_s_; }  // newest sample's session time
  // Why the reader waits at its offset ("" when it has read everything there is), e.g. an
  // incomplete frame or, if it persists, damage.
  const std::string& stop_reason() const { return stop_reason_; }
  // Bytes the rings and event list hold (bounded by the options).
  std::size_t memory_bytes() const;

  // One plot per channel (time axes linked) showing the last window_s seconds up to the
  // newest sample, events as markers; at most max_plot_samples points per channel. Rebuilds `plots`
  // when a poll brought something new (bumping each plot's revision) and keeps the user's y-range
  // otherwise. Returns whether it changed anything.
  bool update_plots(std::vector<PlotView>& plots) const;

 private:
  bool open();
  void read_frames(LivePoll& result);
  double physical(std::size_t channel, double raw) const;

  std::filesystem::path journal_;
  std::filesystem::path session_;  // the session that the journal becomes
  LiveOptions options_;
  LiveState state_ = LiveState::kWaiting;
  std::string waiting_reason_;
  std::unique_ptr<JournalReader> reader_;
  std::uint64_t inode_ = 0;  // of the journal opened, to notice a removal or replacement
  std::vector<SampleRing> rings_;
  std::vector<int> latency_channel_;             // per channel, -1 none
  std::vector<const CalibrationRecord*> calib_;  // per channel, null none
  std::vector<std::string> calibration_problems_;
  std::deque<SessionEvent> events_;
  std::uint64_t next_scan_ = 0;
  std::uint64_t frames_ = 0, scans_ = 0, revision_ = 0;
  double latest_s_ = 0.0;
  std::string stop_reason_;
  std::string gone_reason_;
  JournalFrame frame_;  // reused
};

}  // namespace doorbench::viewer
