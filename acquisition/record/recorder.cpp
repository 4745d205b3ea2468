#include "acquisition/record/recorder.h"

#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>

#include "acquisition/record/journal.h"
#include "acquisition/record/recovery.h"

namespace doorbench {

ScanBlock::ScanBlock(std::size_t channels, std::size_t max_scans, std::size_t max_events)
    : counts(channels, std::vector<std::int32_t>(max_scans)) {
  events.reserve(max_events);
}

std::string RecordOptions::validate() const {
  if (!(duration_s > 0) || !std::isfinite(duration_s)) return "record duration_s must be > 0";
  if (!(flush_interval_s > 0) || !(flush_interval_s <= 10.0)) {
    return "record flush_interval_s must be > 0 and <= 10";
  }
  if (!(ring_s > 0) || !std::isfinite(ring_s)) return "record ring_s must be > 0";
  if (ring_events == 0) return "record ring_events must be >= 1";
  if (polled_batch == 0 || polled_batch > (1u << 20)) {
    return "record polled_batch must be >= 1 and <= 1048576";
  }
  if (trigger) {
    if (std::string problem = trigger->validate(); !problem.empty()) return problem;
  }
  return writer.validate();
}

std::string RecordSummary::brief_report() const {
  char text[256];
  std::snprintf(text, sizeof text, "%zu scans (%.3f s), %zu events; journal %.1f kB, %llu syncs",
                scans, duration_s, events, journal_bytes / 1000.0,
                static_cast<unsigned long long>(journal_syncs));
  std::string report = text;
  if (polled_samples > 0) report += "; " + std::to_string(polled_samples) + " polled samples";
  if (faults > 0) report += "; " + std::to_string(faults) + " faults";
  if (stopped_by_request) report += "; stopped by request";
  if (!trigger_report.empty()) report += "; " + trigger_report;
  if (dropped_scans > 0) {
    report += "; " + std::to_string(dropped_scans) + " scans lost to ring overflows";
  }
  if (dropped_events > 0) {
    report += "; " + std::to_string(dropped_events) + " events lost to a full event ring";
  }
  return report;
}

// ---------------------------------------------------------------------------------------
// The reading side

RecorderRings::RecorderRings(std::size_t channels, std::size_t block_scans, std::size_t scan_slots,
                             std::size_t event_slots)
    : scans(scan_slots,
            ScanSlot{0, 0, block_scans, std::vector<std::int32_t>(channels * block_scans)}),
      events(event_slots, EventSlot{}) {}

RealtimeReader::RealtimeReader(AcquisitionBackend& backend, RecorderRings& rings,
                               std::size_t channels, std::size_t block_scans,
                               std::uint64_t total_scans, RingFullPolicy when_full)
    : backend_(backend),
      rings_(rings),
      block_(channels, block_scans),
      channels_(channels),
      total_scans_(total_scans),
      when_full_(when_full),
      scan_rate_hz_(backend.scan_rate_hz()) {
  if (rings.scans.capacity() == 0 || rings.scans.consumer_slot() != nullptr ||  // must start empty
      block_scans > rings.scans.producer_slot()->capacity) {
    throw std::invalid_argument("the ring's blocks are smaller than the reader's");
  }
}

namespace {

std::int64_t clock_ns(clockid_t clock) {
  timespec now{};
  ::clock_gettime(clock, &now);
  return std::int64_t{now.tv_sec} * 1000000000 + now.tv_nsec;
}

// CLOCK_MONOTONIC and CLOCK_REALTIME of one moment: the realtime clock read on either side
// of the monotonic one, averaged (both reads take well under a microsecond).
struct ClockOrigin {
  std::int64_t monotonic_ns = 0;
  std::int64_t realtime_ns = 0;
};
ClockOrigin sample_clock_origin() {
  const std::int64_t before = clock_ns(CLOCK_REALTIME);
  const std::int64_t monotonic = clock_ns(CLOCK_MONOTONIC);
  const std::int64_t after = clock_ns(CLOCK_REALTIME);
  return {monotonic, before + (after - before) / 2};
}

}  // namespace

void RealtimeReader::start() {
  backend_.start();
  const ClockOrigin origin = sample_clock_origin();
  rings_.start_realtime_ns.store(origin.realtime_ns, std::memory_order_relaxed);
  rings_.start_monotonic_ns.store(origin.monotonic_ns, std::memory_order_release);
}

namespace {

// Copies `text` into `out` (size bytes, NUL-terminated); a text that does not fit ends
// in "...". No allocation.
void copy_text(char* out, std::size_t size, const char* text, std::size_t length) {
  if (length < size) {
    std::memcpy(out, text, length);
    out[length] = '\0';
    return;
  }
  std::memcpy(out, text, size - 4);
  std::memcpy(out + size - 4, "...", 4);
}

template <std::size_t N>
void copy_text(char (&out)[N], const std::string& text) {
  copy_text(out, N, text.data(), text.size());
}

template <std::size_t N>
void copy_text(char (&out)[N], const char* text) {
  copy_text(out, N, text, std::strlen(text));
}

}  // namespace

void RealtimeReader::push_event(double time_s, const char* kind, const char* channel,
                                const char* detail) {
  EventSlot* slot = rings_.events.producer_slot();
  if (slot == nullptr) {
    rings_.dropped_events.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  slot->time_s = time_s;
  copy_text(slot->kind, kind);
  copy_text(slot->channel, channel);
  copy_text(slot->detail, detail);
  rings_.events.publish();
}

bool RealtimeReader::step() {
  if (scans_ >= total_scans_ || rings_.stop.load(std::memory_order_relaxed)) return false;
  block_.events.clear();
  const std::size_t got = backend_.read(block_);
  if (got == 0) return false;
  const std::size_t keep =
      static_cast<std::size_t>(std::min<std::uint64_t>(got, total_scans_ - scans_));

  ScanSlot* slot = rings_.scans.producer_slot();
  while (slot == nullptr && when_full_ == RingFullPolicy::kWait) {
    // Only for sources that compute scans on demand: waiting costs them nothing.
    if (rings_.stop.load(std::memory_order_relaxed)) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    slot = rings_.scans.producer_slot();
  }
  if (slot != nullptr) {
    slot->first_scan = scans_;
    slot->scan_count = keep;
    for (std::size_t c = 0; c < channels_; ++c) {
      std::memcpy(slot->counts.data() + c * slot->capacity, block_.counts[c].data(),
                  keep * sizeof(std::int32_t));
    }
    rings_.scans.publish();
    overflowing_ = false;
  } else {
    rings_.dropped_scans.fetch_add(keep, std::memory_order_relaxed);
    if (!overflowing_) {
      // One fault per overflow; the session's gap event gives the exact extent.
      rings_.overflows.fetch_add(1, std::memory_order_relaxed);
      char detail[sizeof EventSlot::detail];
      std::snprintf(detail, sizeof detail,
                    "ring buffer overflow: the writer fell behind; scans from %llu dropped",
                    static_cast<unsigned long long>(scans_));
      push_event(static_cast<double>(scans_) / scan_rate_hz_, "fault", "", detail);
      overflowing_ = true;
    }
  }
  for (const SessionEvent& event : block_.events) {
    EventSlot* event_slot = rings_.events.producer_slot();
    if (event_slot == nullptr) {
      rings_.dropped_events.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    event_slot->time_s = event.time_s;
    copy_text(event_slot->kind, event.kind);
    copy_text(event_slot->channel, event.channel);
    copy_text(event_slot->detail, event.detail);
    rings_.events.publish();
  }
  scans_ += keep;
  rings_.scans_read.store(scans_, std::memory_order_relaxed);
  return true;
}

// ---------------------------------------------------------------------------------------
// The writer side

namespace {

// signal = raw_offset + raw_scale · raw, then the channel's calibration record (if the
// recording has it): the value a status display shows.
struct LiveConversion {
  double offset = 0.0;
  double scale = 1.0;
  const calibration::CalibrationRecord* record = nullptr;
  double operator()(double raw) const {
    const double signal = offset + scale * raw;
    if (record == nullptr) return signal;
    try {
      return record->apply(signal);
    } catch (const std::exception&) {
      return std::nan("");
    }
  }
};

LiveConversion live_conversion(const ChannelInfo& channel,
                               const std::vector<calibration::CalibrationRecord>& records,
                               std::string& unit) {
  LiveConversion conversion{channel.raw_offset, channel.raw_scale, nullptr};
  unit = channel.unit;
  if (channel.calibration_id.empty()) {
    if (unit.empty()) unit = channel.raw_type == RawType::kCounts ? "V" : channel.raw_unit;
    return conversion;
  }
  for (const calibration::CalibrationRecord& record : records) {
    if (record.id == channel.calibration_id) conversion.record = &record;
  }
  if (conversion.record == nullptr)
    unit = channel.raw_type == RawType::kCounts ? "V" : channel.raw_unit;
  return conversion;
}

// One polled channel's samples waiting for their timed frame.
struct TimedBatch {
  std::uint32_t journal_channel = 0;
  std::uint32_t stage_index = 0;  // among every polled value channel (the trigger stage's)
  std::size_t status_index = 0;
  std::vector<std::int64_t> time_ns;
  std::vector<std::int64_t> latency_ns;
  std::vector<double> raw;
  std::size_t count = 0;
  double first_time_s = 0.0;
  LiveConversion conversion;
};

struct PolledState {
  PolledSource* source = nullptr;
  std::vector<TimedBatch> batches;  // per channel of the source
};

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

}  // namespace

RecordSummary record_session(AcquisitionBackend& backend, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  RecordSources sources;
  sources.scans = &backend;
  return record_session(sources, metadata, path, options);
}

namespace {

// What the sources bring to a recording, checked: every channel (scan channels, then each
// polled channel followed by its latency channel), the calibration records, and the sizes
// that follow from the scan rate.
struct RecordingPlan {
  AcquisitionBackend* backend = nullptr;
  std::vector<ChannelInfo> channels;
  std::vector<calibration::CalibrationRecord> calibrations;
  std::string description;
  double rate_hz = 0.0;
  std::size_t scan_channels = 0;
  std::vector<PolledState> polled;
  std::size_t block_scans = 1;
  std::uint64_t total_scans = 0;
  std::int64_t duration_ns = 0;
  std::filesystem::path journal_path;
};

// The scan backend's channels (counts only), rate, calibrations and description.
void plan_scan_backend(AcquisitionBackend& backend, RecordingPlan& plan) {
  plan.channels = backend.channels();
  if (plan.channels.empty()) throw std::invalid_argument(backend.description() + ": no channels");
  plan.rate_hz = backend.scan_rate_hz();
  if (!(plan.rate_hz > 0) || !std::isfinite(plan.rate_hz)) {
    throw std::invalid_argument(backend.description() + ": scan rate must be > 0");
  }
  for (const ChannelInfo& channel : plan.channels) {
    if (channel.raw_type != RawType::kCounts) {
      throw std::invalid_argument(backend.description() + ": channel " + channel.name +
                                  " holds values; the recorder records counts");
    }
  }
  plan.scan_channels = plan.channels.size();
  plan.calibrations = backend.calibrations();
  plan.description = backend.description();
}

// The latency channel recorded next to polled channel `channel`.
ChannelInfo latency_channel(const ChannelInfo& channel) {
  ChannelInfo latency;
  latency.name = channel.name + "_latency";
  latency.sensor_kind = "poll_latency";
  latency.sensor_serial = channel.sensor_serial;
  latency.raw_type = RawType::kValues;
  latency.raw_unit = "s";
  latency.unit = "s";
  latency.range_min = 0.0;
  latency.range_max = 3600.0;
  latency.sample_rate_hz = 0.0;
  return latency;
}

// One polled source's channels (explicit-time values only), each followed by its latency
// channel, with a batch of `polled_batch` samples per channel.
void plan_polled_source(PolledSource& source, std::size_t polled_batch, RecordingPlan& plan) {
  PolledState state;
  state.source = &source;
  const std::vector<ChannelInfo> source_channels = source.channels();
  if (source_channels.empty()) throw std::invalid_argument(source.description() + ": no channels");
  for (const ChannelInfo& channel : source_channels) {
    if (channel.sample_rate_hz != 0 || channel.raw_type != RawType::kValues) {
      throw std::invalid_argument(source.description() + ": channel " + channel.name +
                                  " must hold values at explicit times (sample_rate_hz 0)");
    }
    TimedBatch batch;
    batch.journal_channel = static_cast<std::uint32_t>(plan.channels.size());
    plan.channels.push_back(channel);
    plan.channels.push_back(latency_channel(channel));
    batch.time_ns.resize(polled_batch);
    batch.latency_ns.resize(polled_batch);
    batch.raw.resize(polled_batch);
    state.batches.push_back(std::move(batch));
  }
  for (calibration::CalibrationRecord& record : source.calibrations()) {
    plan.calibrations.push_back(std::move(record));
  }
  if (!plan.description.empty()) plan.description += "; ";
  plan.description += source.description();
  plan.polled.push_back(std::move(state));
}

void check_unique_channel_names(const std::vector<ChannelInfo>& channels,
                                const std::filesystem::path& path) {
  std::set<std::string> names;
  for (const ChannelInfo& channel : channels) {
    if (!names.insert(channel.name).second) {
      throw std::invalid_argument(path.string() + ": channel name " + channel.name +
                                  " is used twice among the sources");
    }
  }
}

// Refused before recording, not after it.
void refuse_files_in_the_way(const std::filesystem::path& path,
                             const std::filesystem::path& journal_path) {
  if (std::filesystem::exists(path)) {
    throw SessionError(path.string() + ": already exists (sessions are never overwritten)");
  }
  if (std::filesystem::exists(journal_path)) {
    throw JournalError(journal_path.string() +
                       ": an unfinished recording's journal is in the way; recover it first "
                       "(doorbench recover " +
                       journal_path.string() + ")");
  }
}

RecordingPlan plan_recording(const RecordSources& sources, const std::filesystem::path& path,
                             const RecordOptions& options) {
  RecordingPlan plan;
  plan.backend = sources.scans;
  if (plan.backend == nullptr && sources.polled.empty()) {
    throw std::invalid_argument(path.string() +
                                ": nothing to record (no scan backend and no polled source)");
  }
  if (plan.backend != nullptr) plan_scan_backend(*plan.backend, plan);
  for (PolledSource* source : sources.polled) {
    if (source == nullptr) throw std::invalid_argument(path.string() + ": a polled source is null");
    plan_polled_source(*source, options.polled_batch, plan);
  }
  check_unique_channel_names(plan.channels, path);
  plan.block_scans =
      plan.backend == nullptr ? 1
      : options.block_scans > 0
          ? options.block_scans
          : std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(plan.rate_hz * 0.01)));
  plan.total_scans = static_cast<std::uint64_t>(std::llround(options.duration_s * plan.rate_hz));
  plan.duration_ns = static_cast<std::int64_t>(std::llround(options.duration_s * 1e9));
  plan.journal_path = journal_path_for(path);
  return plan;
}

JournalHeader journal_header(const RecordingPlan& plan, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  JournalHeader header;
  header.metadata = metadata;
  header.channels = plan.channels;
  header.calibrations = plan.calibrations;
  header.scan_rate_hz = plan.rate_hz;
  header.session_name = path.filename().string();
  header.flush_interval_s = options.flush_interval_s;
  header.backend = plan.description;
  return header;
}

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

// The live status: scan channels, then polled value channels.
void SessionRecording::set_up_live_status() {
  for (std::size_t c = 0; c < plan_.scan_channels; ++c) {
    ChannelStatus channel;
    channel.name = plan_.channels[c].name;
    scan_conversion_.push_back(
        live_conversion(plan_.channels[c], plan_.calibrations, channel.unit));
    status_.channels.push_back(channel);
  }
  for (PolledState& state : plan_.polled) {
    for (TimedBatch& batch : state.batches) {
      ChannelStatus channel;
      channel.name = plan_.channels[batch.journal_channel].name;
      channel.polled = true;
      batch.conversion =
          live_conversion(plan_.channels[batch.journal_channel], plan_.calibrations, channel.unit);
      batch.status_index = status_.channels.size();
      status_.channels.push_back(channel);
    }
  }
}

void SessionRecording::set_up_trigger() {
  std::vector<std::uint32_t> stage_to_journal;
  for (PolledState& state : plan_.polled) {
    for (TimedBatch& batch : state.batches) {
      batch.stage_index = static_cast<std::uint32_t>(polled_value_channels_.size());
      polled_value_channels_.push_back(plan_.channels[batch.journal_channel]);
      stage_to_journal.push_back(batch.journal_channel);
    }
  }
  if (!options_.trigger) return;
  sink_.emplace(journal_, stage_to_journal, options_.polled_batch, options_.trigger->pre_trigger_s,
                [this](double time_s, std::string_view kind, std::string_view channel,
                       std::string_view detail) { write_event(time_s, kind, channel, detail); });
  stage_.emplace(
      *options_.trigger, std::span<const ChannelInfo>(plan_.channels.data(), plan_.scan_channels),
      plan_.rate_hz, plan_.block_scans, polled_value_channels_, plan_.calibrations, *sink_);
  stage_time_s_.resize(options_.polled_batch);
  stage_latency_s_.resize(options_.polled_batch);
}

void SessionRecording::stop_polled() {
  std::exception_ptr first;
  for (; started_ > 0; --started_) {
    try {
      plan_.polled[started_ - 1].source->stop();
    } catch (...) {
      if (!first) first = std::current_exception();
    }
  }
  if (first) std::rethrow_exception(first);
}

void SessionRecording::start_polled_sources() {
  try {
    if (plan_.backend == nullptr) {
      const ClockOrigin origin = sample_clock_origin();
      origin_ns_ = origin.monotonic_ns;
      origin_realtime_ns_ = origin.realtime_ns;
    }
    for (PolledState& state : plan_.polled) {
      state.source->start();
      ++started_;
    }
  } catch (...) {
    try {
      stop_polled();
    } catch (...) {
      // The start's error is the one to report.
    }
    journal_.close();
    std::filesystem::remove(plan_.journal_path);
    throw;
  }
}

// The reading thread's body: reads until the end, then stops the backend; its error is
// kept for the writer.
void SessionRecording::read_scans() {
  try {
    reader_->start();
    while (reader_->step()) {
    }
  } catch (const std::exception& error) {
    read_error_ = std::current_exception();
    read_error_text_ = error.what();
  } catch (...) {
    read_error_ = std::current_exception();
    read_error_text_ = "unknown error";
  }
  try {
    plan_.backend->stop();
  } catch (const std::exception& error) {
    if (!read_error_) {
      read_error_ = std::current_exception();
      read_error_text_ = error.what();
    }
  }
  rings_->done.store(true, std::memory_order_release);
}

// The sync thread's body: fdatasync every flush interval, apart from the writer so that a
// slow sync never holds up write() (what is written survives a killed process; a sync is
// needed only against a power loss).
void SessionRecording::sync_journal_periodically() {
  std::uint64_t synced_bytes = journal_.bytes_written();
  auto next = std::chrono::steady_clock::now() + flush_interval_;
  while (!sync_stop_.load(std::memory_order_relaxed)) {
    const auto now = std::chrono::steady_clock::now();
    if (now < next) {
      std::this_thread::sleep_for(std::min<std::chrono::duration<double>>(next - now, poll_));
      continue;
    }
    next = now + flush_interval_;
    const std::uint64_t bytes = journal_.bytes_written();
    if (bytes == synced_bytes) continue;
    try {
      journal_.sync();
      synced_bytes = bytes;
    } catch (const std::exception& error) {
      sync_error_ = error.what();
      sync_failed_.store(true, std::memory_order_release);
      return;
    }
  }
}

void SessionRecording::start_threads() {
  const RecordingPlan& plan = plan_;
  const auto scan_slots =
      plan.backend == nullptr
          ? std::size_t{4}
          : std::max<std::size_t>(4, static_cast<std::size_t>(std::ceil(
                                         options_.ring_s * plan.rate_hz / plan.block_scans)));
  rings_.emplace(std::max<std::size_t>(plan.scan_channels, 1), plan.block_scans, scan_slots,
                 options_.ring_events);
  if (plan.backend != nullptr) {
    reader_.emplace(*plan.backend, *rings_, plan.scan_channels, plan.block_scans, plan.total_scans,
                    options_.when_ring_full);
    reading_ = std::thread([this] { read_scans(); });
  }
  syncing_ = std::thread([this] { sync_journal_periodically(); });
}

void SessionRecording::stop_syncing() {
  sync_stop_.store(true, std::memory_order_relaxed);
  if (syncing_.joinable()) syncing_.join();
}

void SessionRecording::join_reading() {
  if (reading_.joinable()) reading_.join();
}

void SessionRecording::write_event(double time_s, std::string_view kind, std::string_view channel,
                                   std::string_view detail) {
  journal_.append_event(time_s, kind, channel, detail);
  ++summary_.events;
  if (kind == "fault") ++summary_.faults;
}

// An event from a source: through the trigger stage when there is one.
void SessionRecording::forward_event(double time_s, const char* kind, const char* channel,
                                     const char* detail) {
  if (stage_) {
    stage_->event(time_s, kind, channel, detail);
  } else {
    write_event(time_s, kind, channel, detail);
  }
}

// With a trigger stage the journal's start waits for the first kept sample.
void SessionRecording::write_start(std::int64_t monotonic_ns, std::int64_t realtime_ns) {
  if (sink_) {
    sink_->attach(*stage_, monotonic_ns, realtime_ns);
  } else {
    journal_.append_start(monotonic_ns, realtime_ns);
  }
  start_written_ = true;
}

// Session time now: the monotonic clock since the origin (0 before it is known).
double SessionRecording::elapsed_s() const {
  return origin_ns_ < 0 ? 0.0 : static_cast<double>(monotonic_now_ns() - origin_ns_) * 1e-9;
}

// Session time recorded: the scans' clock, or the monotonic clock without scans.
double SessionRecording::recorded_s() const {
  if (plan_.backend != nullptr) return static_cast<double>(written_scans_) / plan_.rate_hz;
  return elapsed_s() - (sink_ ? sink_->offset_s() : 0.0);
}

bool SessionRecording::acquisition_over() {
  if (plan_.backend != nullptr) return rings_->done.load(std::memory_order_acquire);
  return monotonic_now_ns() - origin_ns_ >= plan_.duration_ns || summary_.stopped_by_request ||
         (stage_ && stage_->finished());
}

// The scan backend's start is session time 0.
void SessionRecording::write_start_once_scanning() {
  if (start_written_) return;
  const std::int64_t start_ns = rings_->start_monotonic_ns.load(std::memory_order_acquire);
  if (start_ns < 0) return;
  origin_ns_ = start_ns;
  write_start(start_ns, rings_->start_realtime_ns.load(std::memory_order_relaxed));
}

bool SessionRecording::drain_ring_events() {
  bool wrote = false;
  while (const EventSlot* event = rings_->events.consumer_slot()) {
    forward_event(event->time_s, event->kind, event->channel, event->detail);
    rings_->events.release();
    wrote = true;
  }
  return wrote;
}

void SessionRecording::show_latest_scan(const ScanSlot& slot) {
  if (slot.scan_count == 0) return;
  for (std::size_t c = 0; c < plan_.scan_channels; ++c) {
    const std::int32_t* counts = slot.counts.data() + c * slot.capacity;
    status_.channels[c].latest = scan_conversion_[c](counts[slot.scan_count - 1]);
    const auto [low, high] = std::minmax_element(counts, counts + slot.scan_count);
    status_.channels[c].largest_abs =
        std::max({status_.channels[c].largest_abs, std::abs(scan_conversion_[c](*low)),
                  std::abs(scan_conversion_[c](*high))});
  }
}

bool SessionRecording::drain_ring_scans() {
  bool wrote = false;
  while (const ScanSlot* slot = rings_->scans.consumer_slot()) {
    acquired_scans_ = slot->first_scan + slot->scan_count;
    if (stage_) {
      stage_->scans(slot->first_scan, slot->scan_count, slot->counts.data(), slot->capacity);
      written_scans_ = sink_->written_scans();
    } else {
      journal_.append_scans(slot->first_scan, slot->scan_count, slot->counts.data(),
                            slot->capacity);
      written_scans_ = acquired_scans_;
    }
    show_latest_scan(*slot);
    rings_->scans.release();
    wrote = true;
  }
  return wrote;
}

void SessionRecording::flush_batch(TimedBatch& batch) {
  if (batch.count == 0) return;
  if (stage_) {
    for (std::size_t i = 0; i < batch.count; ++i) {
      stage_time_s_[i] = static_cast<double>(batch.time_ns[i]) * 1e-9;
      stage_latency_s_[i] = static_cast<double>(batch.latency_ns[i]) * 1e-9;
    }
    stage_->timed_samples(batch.stage_index,
                          std::span<const double>(stage_time_s_.data(), batch.count),
                          std::span<const double>(stage_latency_s_.data(), batch.count),
                          std::span<const double>(batch.raw.data(), batch.count));
  } else {
    journal_.append_timed(batch.journal_channel, batch.count, batch.time_ns.data(),
                          batch.latency_ns.data(), batch.raw.data());
  }
  ChannelStatus& live = status_.channels[batch.status_index];
  if (live.samples == 0) batch.first_time_s = static_cast<double>(batch.time_ns[0]) * 1e-9;
  live.samples += batch.count;
  live.latest = batch.conversion(batch.raw[batch.count - 1]);
  live.largest_abs = std::max(live.largest_abs, std::abs(live.latest));
  const double span_s =
      static_cast<double>(batch.time_ns[batch.count - 1]) * 1e-9 - batch.first_time_s;
  if (live.samples > 1 && span_s > 0) {
    live.achieved_rate_hz = static_cast<double>(live.samples - 1) / span_s;
  }
  summary_.polled_samples += batch.count;
  batch.count = 0;
}

bool SessionRecording::drain_polled_events(PolledState& state) {
  bool any = false;
  for (;;) {
    const std::size_t got = state.source->take_events(polled_events_);
    for (std::size_t e = 0; e < got; ++e) {
      const PolledEvent& event = polled_events_[e];
      const double time_s = static_cast<double>(event.monotonic_ns - origin_ns_) * 1e-9;
      forward_event(time_s, event.kind[0] != '\0' ? event.kind : "mark", event.channel,
                    event.detail);
    }
    any |= got > 0;
    if (got < polled_events_.size()) return any;
  }
}

bool SessionRecording::drain_polled_samples(PolledState& state) {
  bool any = false;
  for (;;) {
    const std::size_t got = state.source->take_samples(samples_);
    for (std::size_t i = 0; i < got; ++i) {
      const PolledSample& sample = samples_[i];
      if (sample.channel >= state.batches.size()) continue;  // not the source's
      const std::int64_t time_ns = sample.midpoint_ns() - origin_ns_;
      if (time_ns < 0) {
        ++summary_.polled_before_origin;
        continue;
      }
      TimedBatch& batch = state.batches[sample.channel];
      batch.time_ns[batch.count] = time_ns;
      batch.latency_ns[batch.count] = sample.latency_ns();
      batch.raw[batch.count] = sample.raw;
      if (++batch.count == batch.raw.size()) flush_batch(batch);
    }
    any |= got > 0;
    if (got < samples_.size()) return any;
  }
}

// Takes every polled source's samples and events into the journal; true if any.
bool SessionRecording::drain_polled() {
  bool any = false;
  for (PolledState& state : plan_.polled) {
    any |= drain_polled_events(state);
    any |= drain_polled_samples(state);
    for (TimedBatch& batch : state.batches) flush_batch(batch);
  }
  return any;
}

void SessionRecording::report_dropped_events() {
  const std::uint64_t dropped_events = rings_->dropped_events.load(std::memory_order_relaxed);
  if (dropped_events <= reported_dropped_events_) return;
  write_event(recorded_s(), "fault", "",
              std::to_string(dropped_events - reported_dropped_events_) +
                  " events lost: the event ring was full");
  reported_dropped_events_ = dropped_events;
}

// A stop request or a finished trigger stage tells the reading thread to stop.
void SessionRecording::take_stop_request() {
  if (options_.stop_requested != nullptr &&
      options_.stop_requested->load(std::memory_order_relaxed) && !summary_.stopped_by_request) {
    summary_.stopped_by_request = true;
    rings_->stop.store(true, std::memory_order_relaxed);
  }
  if (stage_ && stage_->finished()) rings_->stop.store(true, std::memory_order_relaxed);
}

void SessionRecording::report_progress() {
  status_.recorded_s = stage_ && !sink_->begun() ? 0.0 : recorded_s();
  status_.scans = written_scans_;
  const double elapsed = elapsed_s();
  if (plan_.backend != nullptr && elapsed > 0) {
    status_.achieved_scan_rate_hz = static_cast<double>(acquired_scans_) / elapsed;
  }
  if (stage_) {
    status_.trigger_state = stage_->state() == TriggerStage::State::kArmed ? "armed"
                            : stage_->finished()                           ? "stopped"
                                                                           : "triggered";
  }
  for (std::size_t c = 0; c < plan_.scan_channels; ++c) {
    status_.channels[c].samples = acquired_scans_;
    status_.channels[c].achieved_rate_hz = status_.achieved_scan_rate_hz;
  }
  status_.faults = summary_.faults;
  options_.progress(status_);
  for (ChannelStatus& channel : status_.channels) channel.largest_abs = 0.0;
}

// The trigger's outcome, the closing events and the end frame, synced.
void SessionRecording::write_ending() {
  if (stage_) {
    summary_.triggered = stage_->state() != TriggerStage::State::kArmed;
    summary_.trigger_report = stage_->summary().brief_report();
    if (!sink_->begun()) {
      sink_->begin();
      write_event(
          0.0, "mark", "",
          "the start condition never fired: no samples kept (" + summary_.trigger_report + ")");
    }
    summary_.polled_samples = sink_->samples();
  }
  const double end_s = recorded_s();
  for (const PolledState& state : plan_.polled) {
    const PolledStatistics statistics = state.source->statistics();
    if (statistics.dropped_samples > 0) {
      write_event(end_s, "fault", "",
                  state.source->description() + ": " + std::to_string(statistics.dropped_samples) +
                      " polled samples lost (not taken in time)");
    }
  }
  if (summary_.polled_before_origin > 0) {
    write_event(0.0, "mark", "",
                std::to_string(summary_.polled_before_origin) +
                    " polled samples from before time 0 (the first scan) not kept");
  }
  if (summary_.stopped_by_request) {
    char detail[96];
    std::snprintf(detail, sizeof detail, "recording stopped by hand after %.3f s", end_s);
    write_event(end_s, "stop", "", detail);
  }
  if (read_error_) write_event(end_s, "fault", "", "the recording stopped: " + read_error_text_);
  summary_.duration_s = end_s;
  journal_.append_end(written_scans_);
  stop_syncing();
  journal_.sync();
}

// A failed write: stops every thread, keeps what was written and says how to recover it.
void SessionRecording::abandon(const std::exception& error) {
  rings_->stop.store(true, std::memory_order_relaxed);
  join_reading();
  stop_syncing();
  try {
    stop_polled();
  } catch (const std::exception&) {
    // The write error is the one to report.
  }
  try {
    journal_.sync();
  } catch (const std::exception&) {
    // The write error is the one to report.
  }
  char kept[200];
  std::snprintf(kept, sizeof kept,
                "; the recording stopped after %.3f s: the %llu scans and %llu polled samples ",
                recorded_s(), static_cast<unsigned long long>(written_scans_),
                static_cast<unsigned long long>(summary_.polled_samples));
  const std::string journal = plan_.journal_path.string();
  throw JournalError(std::string(error.what()) + kept + "written so far are kept in " + journal +
                     " (free space, then: doorbench recover " + journal + ")");
}

void SessionRecording::write_until_done() {
  try {
    if (plan_.backend == nullptr) write_start(origin_ns_, origin_realtime_ns_);
    for (;;) {
      // Read before draining: everything published before `done` is drained below; the
      // polled sources are stopped (joined) before their last drain.
      const bool done = acquisition_over();
      if (done) stop_polled();
      write_start_once_scanning();
      bool wrote = drain_ring_events();
      wrote |= drain_ring_scans();
      if (start_written_) wrote |= drain_polled();
      report_dropped_events();
      if (sync_failed_.load(std::memory_order_acquire)) throw JournalError(sync_error_);
      take_stop_request();
      if (wrote && options_.progress) report_progress();
      if (done) break;
      if (!wrote) std::this_thread::sleep_for(poll_);
    }
    write_ending();
  } catch (const std::exception& error) {
    abandon(error);
  }
}

RecordSummary SessionRecording::finish() {
  join_reading();
  summary_.scans = static_cast<std::size_t>(written_scans_);
  summary_.dropped_scans = rings_->dropped_scans.load();
  summary_.dropped_events = rings_->dropped_events.load();
  summary_.journal_bytes = journal_.bytes_written();
  summary_.journal_syncs = journal_.syncs();
  return summary_;
}

// The journal (kept open, and locked, until the session is complete, so that another
// doorbench does not take it for an unfinished recording meanwhile) into the session.
void convert_to_session(const RecordingPlan& plan, const std::filesystem::path& path,
                        const RecordOptions& options, double session_origin_s) {
  ConvertOptions convert;
  convert.writer = options.writer;
  if (AcquisitionBackend* const backend = plan.backend) {
    convert.extras = [backend, session_origin_s](SessionWriter& writer) {
      backend->write_extras(writer, session_origin_s);
    };
  }
  try {
    convert_journal(plan.journal_path, path, convert);
  } catch (const std::exception& error) {
    // E.g. the disk filled up during the conversion: the journal is whole and synced.
    const std::string journal = plan.journal_path.string();
    throw SessionError(std::string(error.what()) + "; the recording is kept in " + journal +
                       " (free space, then: doorbench recover " + journal + ")");
  }
  // This recording's own journal, whole, in a complete session that is synced under its
  // name: the one journal doorbench removes (recovery keeps those it converts).
  std::error_code ignored;
  std::filesystem::remove(plan.journal_path, ignored);
  const std::filesystem::path folder =
      plan.journal_path.parent_path().empty() ? "." : plan.journal_path.parent_path();
  if (const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

RecordSummary record_session(const RecordSources& sources, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  RecordingPlan plan = plan_recording(sources, path, options);
  refuse_files_in_the_way(path, plan.journal_path);
  JournalWriter journal(plan.journal_path, journal_header(plan, metadata, path, options),
                        plan.block_scans, options.polled_batch);
  SessionRecording recording(plan, journal, options);
  recording.start_polled_sources();
  recording.start_threads();
  recording.write_until_done();
  const RecordSummary summary = recording.finish();
  convert_to_session(plan, path, options, recording.session_origin_s());
  if (recording.read_error()) std::rethrow_exception(recording.read_error());
  return summary;
}

}  // namespace doorbench
