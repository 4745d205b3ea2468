#pragma once
// One recording, from the polled sources' start to the journal's end frame
// (acquisition/record/ only; session_recording.cpp, used by record_session() in
// recorder.cpp), and the trigger stage's sink into the journal. Thread safety: a
// SessionRecording is driven from one thread (the writer, record_session's caller); it
// starts and joins its reading and sync threads itself.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "acquisition/record/internal/recorder_common.h"
#include "acquisition/record/internal/recording_plan.h"
#include "acquisition/record/journal.h"
#include "acquisition/record/recorder.h"
#include "acquisition/record/trigger.h"

namespace doorbench::record_detail {

// Where the trigger stage's output goes: the journal, on a session clock whose time 0 is
// the first kept sample. The start frame is written when the stage fired (the first kept
// sample's time is known only then); faults forwarded while armed wait for it in
// preallocated slots.
class JournalSink final : public RecordingSink {
 public:
  using WriteEvent =
      std::function<void(double, std::string_view, std::string_view, std::string_view)>;
  JournalSink(JournalWriter& journal, std::vector<std::uint32_t> journal_channels,
              std::size_t batch, double pre_trigger_s, WriteEvent write_event)
      : journal_(journal),
        journal_channels_(std::move(journal_channels)),
        time_ns_(batch),
        latency_ns_(batch),
        held_(kHeldEvents),
        pre_trigger_s_(pre_trigger_s),
        write_event_(std::move(write_event)) {}

  void attach(const TriggerStage& stage, std::int64_t origin_ns, std::int64_t origin_realtime_ns) {
    stage_ = &stage;
    origin_ns_ = origin_ns;
    origin_realtime_ns_ = origin_realtime_ns;
  }
  bool begun() const { return begun_; }
  double offset_s() const { return offset_s_; }
  std::uint64_t written_scans() const { return written_scans_; }
  std::uint64_t samples() const { return samples_; }

  // Writes the start frame: at the first kept sample once the stage fired, else (the
  // recording ends armed) at the acquisition's start. Then the events held back.
  void begin() {
    if (begun_) return;
    if (stage_->state() != TriggerStage::State::kArmed) {
      if (const std::optional<double> first = stage_->first_forwarded_time_s()) {
        offset_s_ = *first;
      } else if (const std::optional<double> trigger = stage_->trigger_time_s()) {
        offset_s_ = std::max(0.0, *trigger - pre_trigger_s_);
      }
    }
    const auto offset_ns = static_cast<std::int64_t>(std::llround(offset_s_ * 1e9));
    journal_.append_start(origin_ns_ + offset_ns,
                          origin_realtime_ns_ == 0 ? 0 : origin_realtime_ns_ + offset_ns);
    begun_ = true;
    for (std::size_t i = 0; i < held_count_; ++i) {
      const EventSlot& event = held_[i];
      write_event_(event.time_s - offset_s_, event.kind, event.channel, event.detail);
    }
    if (held_lost_ > 0) {
      write_event_(0.0, "fault", "",
                   std::to_string(held_lost_) + " faults while armed not kept (too many)");
    }
    held_count_ = 0;
  }

  void scans(std::uint64_t first_scan, std::size_t count, const std::int32_t* counts,
             std::size_t stride) override {
    begin();
    journal_.append_scans(first_scan, count, counts, stride);
    written_scans_ = first_scan + count;
  }
  void timed_samples(std::uint32_t channel, std::span<const double> time_s,
                     std::span<const double> latency_s, std::span<const double> raw) override {
    begin();
    for (std::size_t from = 0; from < time_s.size();) {
      const std::size_t n = std::min(time_s.size() - from, time_ns_.size());
      for (std::size_t i = 0; i < n; ++i) {
        time_ns_[i] = std::llround((time_s[from + i] - offset_s_) * 1e9);
        latency_ns_[i] = std::llround(latency_s[from + i] * 1e9);
      }
      journal_.append_timed(journal_channels_[channel], n, time_ns_.data(), latency_ns_.data(),
                            raw.data() + from);
      samples_ += n;
      from += n;
    }
  }
  void event(double time_s, std::string_view kind, std::string_view channel,
             std::string_view detail) override {
    if (!begun_ && stage_->state() != TriggerStage::State::kArmed) begin();
    if (begun_) {
      write_event_(time_s - offset_s_, kind, channel, detail);
      return;
    }
    if (held_count_ == held_.size()) {
      ++held_lost_;
      return;
    }
    EventSlot& slot = held_[held_count_++];
    slot.time_s = time_s;
    copy_text(slot.kind, sizeof slot.kind, kind.data(), kind.size());
    copy_text(slot.channel, sizeof slot.channel, channel.data(), channel.size());
    copy_text(slot.detail, sizeof slot.detail, detail.data(), detail.size());
  }

 private:
  static constexpr std::size_t kHeldEvents = 256;
  JournalWriter& journal_;
  std::vector<std::uint32_t> journal_channels_;  // stage's polled index → journal channel
  std::vector<std::int64_t> time_ns_, latency_ns_;
  std::vector<EventSlot> held_;
  std::size_t held_count_ = 0;
  std::uint64_t held_lost_ = 0;
  double pre_trigger_s_;
  WriteEvent write_event_;
  const TriggerStage* stage_ = nullptr;
  std::int64_t origin_ns_ = 0;
  std::int64_t origin_realtime_ns_ = 0;
  bool begun_ = false;
  double offset_s_ = 0.0;
  std::uint64_t written_scans_ = 0;
  std::uint64_t samples_ = 0;
};

// One recording from the polled sources' start to the journal's end frame, on the
// caller's thread (the writer), with the reading thread and the sync thread it starts.
// Not copyable or movable: the threads and the trigger stage's sink refer to it.
class SessionRecording {
 public:
  SessionRecording(RecordingPlan& plan, JournalWriter& journal, const RecordOptions& options)
      : plan_(plan),
        options_(options),
        journal_(journal),
        flush_interval_(options.flush_interval_s),
        poll_(std::min(0.005, options.flush_interval_s / 4)),
        samples_(options.polled_batch),
        polled_events_(64) {
    set_up_live_status();
    set_up_trigger();
  }
  SessionRecording(const SessionRecording&) = delete;
  SessionRecording& operator=(const SessionRecording&) = delete;
  // Whatever happened, the polling threads end with the recording.
  ~SessionRecording() {
    try {
      stop_polled();
    } catch (...) {
      // Already ending with another error, or stopped before.
    }
  }

  // Polled sources start first (a source that cannot start stops the recording before
  // it began: the journal is removed); without a scan backend their start is the
  // session's time 0.
  void start_polled_sources();
  // The reading thread (with a scan backend) and the sync thread.
  void start_threads();
  // Drains the sources into the journal until the recording is over, then writes its
  // ending. A failed write throws JournalError saying what is kept and how to recover it.
  void write_until_done();
  // After write_until_done: joins the reading thread, completes the summary.
  RecordSummary finish();
  // The start of session time 0 relative to the acquisition's start (the trigger's).
  double session_origin_s() const { return sink_ ? sink_->offset_s() : 0.0; }
  const std::exception_ptr& read_error() const { return read_error_; }

 private:
  void set_up_live_status();
  void set_up_trigger();
  void stop_polled();
  void read_scans();
  void sync_journal_periodically();
  void stop_syncing();
  void join_reading();
  void write_event(double time_s, std::string_view kind, std::string_view channel,
                   std::string_view detail);
  void forward_event(double time_s, const char* kind, const char* channel, const char* detail);
  void write_start(std::int64_t monotonic_ns, std::int64_t realtime_ns);
  bool acquisition_over();
  void write_start_once_scanning();
  bool drain_ring_events();
  bool drain_ring_scans();
  void show_latest_scan(const ScanSlot& slot);
  bool drain_polled();
  bool drain_polled_events(PolledState& state);
  bool drain_polled_samples(PolledState& state);
  void flush_batch(TimedBatch& batch);
  void report_dropped_events();
  void take_stop_request();
  void report_progress();
  void write_ending();
  [[noreturn]] void abandon(const std::exception& error);
  double elapsed_s() const;
  double recorded_s() const;

  RecordingPlan& plan_;
  const RecordOptions& options_;
  JournalWriter& journal_;
  const std::chrono::duration<double> flush_interval_;
  const std::chrono::duration<double> poll_;
  RecordSummary summary_;
  RecordStatus status_;
  std::vector<LiveConversion> scan_conversion_;
  // Triggering: the stage between the sources and the journal, and its sink.
  std::vector<ChannelInfo> polled_value_channels_;
  std::optional<JournalSink> sink_;
  std::optional<TriggerStage> stage_;
  std::vector<double> stage_time_s_;
  std::vector<double> stage_latency_s_;
  // The session clock's origin (CLOCK_MONOTONIC; -1 until known) and UTC at that moment.
  std::int64_t origin_ns_ = -1;
  std::int64_t origin_realtime_ns_ = 0;
  std::size_t started_ = 0;  // polled sources started (and not stopped)
  std::optional<RecorderRings> rings_;
  std::optional<RealtimeReader> reader_;
  std::exception_ptr read_error_;
  std::string read_error_text_;
  std::thread reading_;
  // The sync thread's.
  std::atomic<bool> sync_stop_{false};
  std::atomic<bool> sync_failed_{false};
  std::string sync_error_;
  std::thread syncing_;
  // The writer's.
  bool start_written_ = false;
  std::uint64_t written_scans_ = 0;
  std::uint64_t acquired_scans_ = 0;
  std::uint64_t reported_dropped_events_ = 0;
  std::vector<PolledSample> samples_;
  std::vector<PolledEvent> polled_events_;
};

}  // namespace doorbench::record_detail
