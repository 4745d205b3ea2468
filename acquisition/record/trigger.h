#pragma once
// Triggering (docs/triggering.md): a stage between the recorder's rings and its journal
// that decides which of the acquired data becomes the session. It is armed at the start
// and keeps the last `pre_trigger_s` seconds in preallocated buffers; when the start
// condition fires (at once, an external line, a level crossing with hysteresis on any
// channel, or by hand) it forwards that pre-trigger data, a "trigger" event and then
// everything live, until the stop condition (a duration, a level, by hand) forwards a
// "stop" event and ends the session. Optional stroke markers (stroke_start / stroke_end
// events from a level condition) are added to what is forwarded.
//
// Threads: the stage is used by one thread (the recorder's writer thread). It is not the
// real-time thread, but it still allocates nothing after construction: every buffer and
// every event text is made in the constructor (tests/acquisition/test_trigger.cpp counts).
#include <atomic>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/session_file.h"

namespace doorbench {

struct RigDefinition;

// Where the stage forwards what it keeps. Scan numbers start at 0 with the first
// forwarded scan; gaps in the input's scan numbers (ring overflows) stay gaps.
class RecordingSink {
 public:
  virtual ~RecordingSink() = default;
  // `count` scans from `first_scan`: counts[c * stride + s] is channel c, scan s.
  virtual void scans(std::uint64_t first_scan, std::size_t count, const std::int32_t* counts,
                     std::size_t stride) = 0;
  // Samples of polled channel `channel` (an index into the stage's polled channels), on the
  // session clock, in time order.
  virtual void timed_samples(std::uint32_t channel, std::span<const double> time_s,
                             std::span<const double> latency_s, std::span<const double> raw) = 0;
  virtual void event(double time_s, std::string_view kind, std::string_view channel,
                     std::string_view detail) = 0;
};

// A level condition on one channel, in the channel's physical unit.
struct LevelCondition {
  enum class Direction { kRising, kFalling };
  std::string channel;  // a scan or polled channel of the session
  Direction direction = Direction::kRising;
  double level = 0.0;
  // Rising: fires when the value reaches `level` (>=), and may fire again only after it
  // went below level - hysteresis. Falling: fires at <= level, re-arms above level +
  // hysteresis. A value that starts beyond the level does not fire until it came back.
  double hysteresis = 0.0;
  // As a stop condition: the value must stay on the fired side (within the hysteresis)
  // for this long; the stop is at the sample where the hold completes. Ignored elsewhere.
  double hold_s = 0.0;
  bool absolute = false;  // compare |value| (e.g. a gyroscope's rate either way)
  std::string validate(std::string_view what) const;  // "" or one line naming `what`
  // "force > 2 N" (with the unit given), "|gyro| > 0.2 rad/s", "force < 0.5 N".
  std::string describe(std::string_view unit) const;
};

struct TriggerOptions {
  enum class Start { kImmediate, kLevel, kManual, kExternal };
  enum class Stop { kNone, kLevel, kManual };

  Start start = Start::kImmediate;
  LevelCondition start_level;   // for kLevel
  std::string external_source;  // for kExternal: the DAQ's start line, e.g. "PFI0"
  Stop stop = Stop::kNone;
  LevelCondition stop_level;  // for Stop::kLevel
  // > 0: stop this long after the trigger (also with a level or manual stop: whichever
  // comes first); 0: no duration.
  double duration_s = 0.0;
  double pre_trigger_s = 1.0;  // 0 … kMaxPreTriggerS
  // Stroke markers: a rising crossing (falling for kFalling) starts a stroke, the crossing
  // back beyond the hysteresis ends it; strokes shorter than min_stroke_s are ignored.
  std::optional<LevelCondition> strokes;
  double min_stroke_s = 0.2;
  // Set by the command line (e.g. the Enter key); read at every scans() call (or
  // timed_samples() call in a session without scan channels); the stage never writes
  // them. Two different flags: the command line sets manual_start at the first Enter and
  // manual_stop at the next one.
  const std::atomic<bool>* manual_start = nullptr;
  const std::atomic<bool>* manual_stop = nullptr;
  // Sizes the polled channels' pre-trigger buffers: samples per channel =
  // ceil(max_poll_rate_hz * (pre_trigger_s + lookahead_s)) + 16. Faster polling keeps a
  // shorter pre-trigger history (counted in TriggerSummary::timed_overwritten).
  double max_poll_rate_hz = 1000.0;
  // Extra history the scan buffer keeps beyond pre_trigger_s and one block, because the
  // writer may see scans up to this long before a polled sample that triggers.
  double lookahead_s = 0.5;

  static constexpr double kMaxPreTriggerS = 60.0;
  std::string validate() const;  // "" or one line naming the option
};

// The options of a rig's [recording] table and its [[triggers]] (docs/rig-format.md).
// The manual flags are left null for the caller to set.
TriggerOptions trigger_options_from_rig(const RigDefinition& rig);

// Maps one channel's raw values to its physical unit without allocating: signal =
// raw_offset + raw_scale * raw, then the calibration record's polynomial (none: the signal
// is the physical value). The record's delay_s is not applied (see docs/triggering.md).
class PhysicalConverter {
 public:
  // Throws std::invalid_argument when the channel's calibration_id is not in `records`.
  PhysicalConverter(const ChannelInfo& channel, std::span<const CalibrationRecord> records);
  double operator()(double raw) const {
    const double signal = offset_ + scale_ * raw;
    double value = 0.0;
    if (coefficients_.empty()) return signal;
    for (auto it = coefficients_.rbegin(); it != coefficients_.rend(); ++it) {
      value = value * signal + *it;
    }
    return value;
  }

 private:
  double offset_ = 0.0;
  double scale_ = 1.0;
  std::vector<double> coefficients_;
};

// Edge detection with hysteresis (and an optional hold), one sample at a time.
class LevelDetector {
 public:
  LevelDetector() = default;
  explicit LevelDetector(const LevelCondition& condition);
  // True at the sample where the condition fires (hold not included).
  bool fire(double value);
  // True while the value is on the fired side, within the hysteresis.
  bool on_fired_side(double value) const;
  // True when the value is back beyond the hysteresis (the end of a stroke).
  bool released(double value) const;

 private:
  double magnitude(double value) const { return absolute_ && value < 0 ? -value : value; }
  bool rising_ = true;
  bool absolute_ = false;
  double level_ = 0.0;
  double hysteresis_ = 0.0;
  bool armed_ = false;
};

struct TriggerSummary {
  std::string state;  // armed | triggered | stopped
  double trigger_time_s = std::numeric_limits<double>::quiet_NaN();
  double stop_time_s = std::numeric_limits<double>::quiet_NaN();
  std::uint64_t first_forwarded_scan = 0;  // in the acquisition's numbering
  std::uint64_t forwarded_scans = 0;
  std::uint64_t forwarded_timed_samples = 0;
  std::uint64_t forwarded_events = 0;
  std::uint64_t strokes = 0;
  std::uint64_t timed_overwritten = 0;   // polled pre-trigger samples lost to a full buffer
  std::uint64_t events_overwritten = 0;  // pre-trigger events lost to a full buffer
  std::uint64_t buffer_bytes = 0;        // the stage's preallocated buffers
  std::string brief_report() const;
};

class TriggerStage {
 public:
  enum class State { kArmed, kTriggered, kStopped };
  static constexpr std::size_t kEventSlots = 256;  // events kept back while armed

  // `scan_channels`: the uniform channels, in the rings' order (may be empty, then
  // scans() must not be called); `polled_channels`: the explicit-time channels, indexed
  // by timed_samples()'s `channel`; `calibrations`: the records the channels name.
  // Throws std::invalid_argument for bad options, an unknown channel in a condition, a
  // missing calibration record.
  TriggerStage(const TriggerOptions& options, std::span<const ChannelInfo> scan_channels,
               double scan_rate_hz, std::size_t max_block_scans,
               std::span<const ChannelInfo> polled_channels,
               std::span<const CalibrationRecord> calibrations, RecordingSink& sink);
  TriggerStage(const TriggerStage&) = delete;
  TriggerStage& operator=(const TriggerStage&) = delete;

  // The input, in the rings' layout; first_scan counts from the acquisition's start.
  // count <= max_block_scans. Allocates nothing.
  void scans(std::uint64_t first_scan, std::size_t count, const std::int32_t* counts,
             std::size_t stride);
  void timed_samples(std::uint32_t channel, std::span<const double> time_s,
                     std::span<const double> latency_s, std::span<const double> raw);
  // An event of the backend or the recorder. Faults and gaps are forwarded at once in
  // every state but stopped; the backend's own "trigger" (the acquisition's start)
  // becomes a "mark" "acquisition started (DETAIL)"; the others wait for the trigger
  // like the data (forwarded when in the pre-trigger window).
  void event(double time_s, std::string_view kind, std::string_view channel,
             std::string_view detail);

  State state() const { return state_; }
  // The recording is over (the stop condition fired): the recorder should end.
  bool finished() const { return state_ == State::kStopped; }
  // Once triggered: the acquisition's scan number that became the session's scan 0, and
  // its time (first_forwarded_scan / scan_rate_hz) on the acquisition's clock. Session
  // time 0 stays the acquisition's start: the uniform channels' first_sample_time_s are
  // their acquisition values plus first_forwarded_time_s() (docs/triggering.md).
  std::optional<std::uint64_t> first_forwarded_scan() const;
  std::optional<double> first_forwarded_time_s() const;
  std::optional<double> trigger_time_s() const;
  TriggerSummary summary() const;

 private:
  struct Target {  // a condition's channel
    bool polled = false;
    std::size_t index = 0;
    const PhysicalConverter* convert = nullptr;
    double first_time_s = 0.0;  // scan channels: the channel's skew
  };
  Target resolve(const LevelCondition& condition, std::string_view what) const;
  double scan_time_s(std::uint64_t scan) const { return static_cast<double>(scan) / rate_hz_; }

  void buffer_scans(std::uint64_t first_scan, std::size_t count, const std::int32_t* counts,
                    std::size_t stride);
  void buffer_timed(std::uint32_t channel, std::span<const double> time_s,
                    std::span<const double> latency_s, std::span<const double> raw);
  void fire_trigger(double time_s, std::uint64_t trigger_scan, std::string_view detail);
  // Forwards scans [first_scan, first_scan + count) of a block, clipped to the kept range,
  // checking the stop and marking strokes on the way.
  void forward_scans(std::uint64_t first_scan, std::size_t count, const std::int32_t* counts,
                     std::size_t stride);
  void forward_timed(std::uint32_t channel, std::span<const double> time_s,
                     std::span<const double> latency_s, std::span<const double> raw);
  // The stop condition and strokes on one kept sample of `channel` (scan or polled).
  // Returns true when the stop fired at this sample (stop event sent).
  bool stop_at(bool polled, std::size_t channel, double time_s, double raw, bool live);
  void strokes_at(bool polled, std::size_t channel, double time_s, double raw);
  // `inclusive`: polled samples at time_s are still kept (a level's crossing sample).
  void stop_now(double time_s, std::string_view detail, std::string_view channel, bool inclusive);
  void send_event(double time_s, std::string_view kind, std::string_view channel,
                  std::string_view detail);
  bool manual(const std::atomic<bool>* flag) const {
    return flag != nullptr && flag->load(std::memory_order_relaxed);
  }

  TriggerOptions options_;
  RecordingSink& sink_;
  std::vector<ChannelInfo> scan_channels_;
  std::vector<ChannelInfo> polled_channels_;
  double rate_hz_;
  std::size_t max_block_scans_;
  std::vector<PhysicalConverter> scan_convert_;
  std::vector<PhysicalConverter> polled_convert_;
  State state_ = State::kArmed;

  Target start_target_{}, stop_target_{}, stroke_target_{};
  LevelDetector start_detector_, stop_detector_, stroke_detector_;
  std::string trigger_detail_, stop_detail_, stop_channel_, stroke_channel_;
  std::string duration_detail_;

  // Scans while armed: per channel a circular buffer of scan_capacity_ scans; scan i is at
  // i % scan_capacity_.
  std::size_t pre_scans_ = 0;  // round(pre_trigger_s * rate)
  std::size_t scan_capacity_ = 0;
  std::vector<std::int32_t> scan_buffer_;  // [c * scan_capacity_ + i % scan_capacity_]
  std::uint64_t buffer_first_ = 0;         // oldest buffered scan
  std::size_t buffer_count_ = 0;
  std::uint64_t next_scan_ = 0;  // expected next input scan

  // Polled samples while armed: per channel a circular buffer.
  std::size_t timed_capacity_ = 0;
  std::vector<double> timed_time_, timed_latency_, timed_raw_;  // [c * capacity + slot]
  std::vector<std::size_t> timed_head_, timed_count_;

  struct EventSlot {
    double time_s = 0.0;
    char kind[32] = {};
    char channel[64] = {};
    char detail[256] = {};
  };
  std::vector<EventSlot> event_buffer_;
  std::size_t event_head_ = 0, event_count_ = 0;

  // Once triggered.
  static constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t duration_scan_ = kNever;  // the first scan after the duration
  double duration_end_s_ = std::numeric_limits<double>::infinity();
  double stop_end_s_ = 0.0;  // polled samples kept once stopped: time < this
  double trigger_time_ = 0.0;
  std::uint64_t trigger_scan_ = 0;
  std::uint64_t first_kept_scan_ = 0;
  double first_kept_time_ = 0.0;      // polled samples and events: from trigger - pre_trigger
  std::uint64_t stop_scan_ = kNever;  // the first scan not kept
  double stop_time_ = std::numeric_limits<double>::infinity();
  bool holding_ = false;
  double hold_since_ = 0.0;

  bool in_stroke_ = false, stroke_announced_ = false;
  double stroke_start_ = 0.0;
  std::uint64_t strokes_ = 0;

  TriggerSummary counters_;
};

}  // namespace doorbench
