#include "acquisition/recorder.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>

#include "acquisition/journal.h"
#include "acquisition/recovery.h"

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

RecordSummary record_session(const RecordSources& sources, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  AcquisitionBackend* const backend = sources.scans;
  if (backend == nullptr && sources.polled.empty()) {
    throw std::invalid_argument(path.string() +
                                ": nothing to record (no scan backend and no polled source)");
  }
  std::vector<ChannelInfo> channels;
  std::vector<calibration::CalibrationRecord> calibrations;
  std::string description;
  double rate_hz = 0.0;
  std::size_t scan_channels = 0;
  if (backend != nullptr) {
    channels = backend->channels();
    if (channels.empty()) throw std::invalid_argument(backend->description() + ": no channels");
    rate_hz = backend->scan_rate_hz();
    if (!(rate_hz > 0) || !std::isfinite(rate_hz)) {
      throw std::invalid_argument(backend->description() + ": scan rate must be > 0");
    }
    for (const ChannelInfo& channel : channels) {
      if (channel.raw_type != RawType::kCounts) {
        throw std::invalid_argument(backend->description() + ": channel " + channel.name +
                                    " holds values; the recorder records counts");
      }
    }
    scan_channels = channels.size();
    calibrations = backend->calibrations();
    description = backend->description();
  }
  // Polled channels, each followed by its latency channel.
  std::vector<PolledState> polled;
  for (PolledSource* source : sources.polled) {
    if (source == nullptr) throw std::invalid_argument(path.string() + ": a polled source is null");
    PolledState state;
    state.source = source;
    const std::vector<ChannelInfo> source_channels = source->channels();
    if (source_channels.empty()) {
      throw std::invalid_argument(source->description() + ": no channels");
    }
    for (const ChannelInfo& channel : source_channels) {
      if (channel.sample_rate_hz != 0 || channel.raw_type != RawType::kValues) {
        throw std::invalid_argument(source->description() + ": channel " + channel.name +
                                    " must hold values at explicit times (sample_rate_hz 0)");
      }
      TimedBatch batch;
      batch.journal_channel = static_cast<std::uint32_t>(channels.size());
      channels.push_back(channel);
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
      channels.push_back(latency);
      batch.time_ns.resize(options.polled_batch);
      batch.latency_ns.resize(options.polled_batch);
      batch.raw.resize(options.polled_batch);
      state.batches.push_back(std::move(batch));
    }
    for (calibration::CalibrationRecord& record : source->calibrations()) {
      calibrations.push_back(std::move(record));
    }
    if (!description.empty()) description += "; ";
    description += source->description();
    polled.push_back(std::move(state));
  }
  {
    std::set<std::string> names;
    for (const ChannelInfo& channel : channels) {
      if (!names.insert(channel.name).second) {
        throw std::invalid_argument(path.string() + ": channel name " + channel.name +
                                    " is used twice among the sources");
      }
    }
  }
  const std::size_t block_scans =
      backend == nullptr ? 1
      : options.block_scans > 0
          ? options.block_scans
          : std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(rate_hz * 0.01)));
  const auto total_scans = static_cast<std::uint64_t>(std::llround(options.duration_s * rate_hz));
  const auto duration_ns = static_cast<std::int64_t>(std::llround(options.duration_s * 1e9));
  const std::filesystem::path journal_path = journal_path_for(path);
  // Refused before recording, not after it.
  if (std::filesystem::exists(path)) {
    throw SessionError(path.string() + ": already exists (sessions are never overwritten)");
  }
  if (std::filesystem::exists(journal_path)) {
    throw JournalError(journal_path.string() +
                       ": an unfinished recording's journal is in the way; recover it first "
                       "(doorbench recover " +
                       journal_path.string() + ")");
  }

  JournalHeader header;
  header.metadata = metadata;
  header.channels = channels;
  header.calibrations = calibrations;
  header.scan_rate_hz = rate_hz;
  header.session_name = path.filename().string();
  header.flush_interval_s = options.flush_interval_s;
  header.backend = description;
  JournalWriter journal(journal_path, header, block_scans, options.polled_batch);

  // The live status: scan channels, then polled value channels.
  RecordStatus status;
  std::vector<LiveConversion> scan_conversion;
  for (std::size_t c = 0; c < scan_channels; ++c) {
    ChannelStatus channel;
    channel.name = channels[c].name;
    scan_conversion.push_back(live_conversion(channels[c], calibrations, channel.unit));
    status.channels.push_back(channel);
  }
  for (PolledState& state : polled) {
    for (TimedBatch& batch : state.batches) {
      ChannelStatus channel;
      channel.name = channels[batch.journal_channel].name;
      channel.polled = true;
      batch.conversion =
          live_conversion(channels[batch.journal_channel], calibrations, channel.unit);
      batch.status_index = status.channels.size();
      status.channels.push_back(channel);
    }
  }

  // Triggering: the stage between the sources and the journal, and its sink.
  std::vector<ChannelInfo> polled_value_channels;
  std::vector<std::uint32_t> stage_to_journal;
  for (PolledState& state : polled) {
    for (TimedBatch& batch : state.batches) {
      batch.stage_index = static_cast<std::uint32_t>(polled_value_channels.size());
      polled_value_channels.push_back(channels[batch.journal_channel]);
      stage_to_journal.push_back(batch.journal_channel);
    }
  }
  RecordSummary summary;
  const auto write_event = [&](double time_s, std::string_view kind, std::string_view channel,
                               std::string_view detail) {
    journal.append_event(time_s, kind, channel, detail);
    ++summary.events;
    if (kind == "fault") ++summary.faults;
  };
  std::optional<JournalSink> sink;
  std::optional<TriggerStage> stage;
  if (options.trigger) {
    sink.emplace(journal, stage_to_journal, options.polled_batch, options.trigger->pre_trigger_s,
                 write_event);
    stage.emplace(*options.trigger, std::span<const ChannelInfo>(channels.data(), scan_channels),
                  rate_hz, block_scans, polled_value_channels, calibrations, *sink);
  }
  std::vector<double> stage_time_s(stage ? options.polled_batch : 0);
  std::vector<double> stage_latency_s(stage ? options.polled_batch : 0);

  // Polled sources start first (a source that cannot start stops the recording before it
  // began); without a scan backend their start is the session's time 0.
  std::int64_t origin_ns = -1;
  std::int64_t origin_realtime_ns = 0;
  std::size_t started = 0;
  const auto stop_polled = [&] {
    std::exception_ptr first;
    for (; started > 0; --started) {
      try {
        polled[started - 1].source->stop();
      } catch (...) {
        if (!first) first = std::current_exception();
      }
    }
    if (first) std::rethrow_exception(first);
  };
  try {
    if (backend == nullptr) {
      const ClockOrigin origin = sample_clock_origin();
      origin_ns = origin.monotonic_ns;
      origin_realtime_ns = origin.realtime_ns;
    }
    for (PolledState& state : polled) {
      state.source->start();
      ++started;
    }
  } catch (...) {
    try {
      stop_polled();
    } catch (...) {
      // The start's error is the one to report.
    }
    journal.close();
    std::filesystem::remove(journal_path);
    throw;
  }
  // Whatever happens below, the polling threads end with this function.
  struct PolledGuard {
    const std::function<void()> stop;
    ~PolledGuard() {
      try {
        stop();
      } catch (...) {
        // Already ending with another error, or stopped before.
      }
    }
  } polled_guard{stop_polled};

  const auto scan_slots =
      backend == nullptr
          ? std::size_t{4}
          : std::max<std::size_t>(
                4, static_cast<std::size_t>(std::ceil(options.ring_s * rate_hz / block_scans)));
  RecorderRings rings(std::max<std::size_t>(scan_channels, 1), block_scans, scan_slots,
                      options.ring_events);
  std::optional<RealtimeReader> reader;
  if (backend != nullptr) {
    reader.emplace(*backend, rings, scan_channels, block_scans, total_scans,
                   options.when_ring_full);
  }

  std::exception_ptr read_error;
  std::string read_error_text;
  std::thread reading;
  if (backend != nullptr) {
    reading = std::thread([&] {
      try {
        reader->start();
        while (reader->step()) {
        }
      } catch (const std::exception& error) {
        read_error = std::current_exception();
        read_error_text = error.what();
      } catch (...) {
        read_error = std::current_exception();
        read_error_text = "unknown error";
      }
      try {
        backend->stop();
      } catch (const std::exception& error) {
        if (!read_error) {
          read_error = std::current_exception();
          read_error_text = error.what();
        }
      }
      rings.done.store(true, std::memory_order_release);
    });
  }
  const auto join_reading = [&] {
    if (reading.joinable()) reading.join();
  };

  std::uint64_t written_scans = 0;
  std::uint64_t acquired_scans = 0;
  std::uint64_t reported_dropped_events = 0;
  const auto flush_interval = std::chrono::duration<double>(options.flush_interval_s);
  const auto poll = std::chrono::duration<double>(std::min(0.005, options.flush_interval_s / 4));
  // The sync thread: fdatasync every flush interval, apart from the writer so that a slow
  // sync never holds up write() (what is written survives a killed process; a sync is
  // needed only against a power loss).
  std::atomic<bool> sync_stop{false};
  std::atomic<bool> sync_failed{false};
  std::string sync_error;
  std::thread syncing([&] {
    std::uint64_t synced_bytes = journal.bytes_written();
    auto next = std::chrono::steady_clock::now() + flush_interval;
    while (!sync_stop.load(std::memory_order_relaxed)) {
      const auto now = std::chrono::steady_clock::now();
      if (now < next) {
        std::this_thread::sleep_for(std::min<std::chrono::duration<double>>(next - now, poll));
        continue;
      }
      next = now + flush_interval;
      const std::uint64_t bytes = journal.bytes_written();
      if (bytes == synced_bytes) continue;
      try {
        journal.sync();
        synced_bytes = bytes;
      } catch (const std::exception& error) {
        sync_error = error.what();
        sync_failed.store(true, std::memory_order_release);
        return;
      }
    }
  });
  const auto stop_syncing = [&] {
    sync_stop.store(true, std::memory_order_relaxed);
    if (syncing.joinable()) syncing.join();
  };
  // Session time now / at the end: the scans' clock, or the monotonic clock without scans.
  const auto elapsed_s = [&] {
    return origin_ns < 0 ? 0.0 : static_cast<double>(monotonic_now_ns() - origin_ns) * 1e-9;
  };
  const auto recorded_s = [&] {
    if (backend != nullptr) return static_cast<double>(written_scans) / rate_hz;
    return elapsed_s() - (sink ? sink->offset_s() : 0.0);
  };
  std::vector<PolledSample> samples(options.polled_batch);
  std::vector<PolledEvent> polled_events(64);
  const auto flush_batch = [&](TimedBatch& batch) {
    if (batch.count == 0) return;
    if (stage) {
      for (std::size_t i = 0; i < batch.count; ++i) {
        stage_time_s[i] = static_cast<double>(batch.time_ns[i]) * 1e-9;
        stage_latency_s[i] = static_cast<double>(batch.latency_ns[i]) * 1e-9;
      }
      stage->timed_samples(batch.stage_index,
                           std::span<const double>(stage_time_s.data(), batch.count),
                           std::span<const double>(stage_latency_s.data(), batch.count),
                           std::span<const double>(batch.raw.data(), batch.count));
    } else {
      journal.append_timed(batch.journal_channel, batch.count, batch.time_ns.data(),
                           batch.latency_ns.data(), batch.raw.data());
    }
    ChannelStatus& live = status.channels[batch.status_index];
    if (live.samples == 0) batch.first_time_s = static_cast<double>(batch.time_ns[0]) * 1e-9;
    live.samples += batch.count;
    live.latest = batch.conversion(batch.raw[batch.count - 1]);
    live.largest_abs = std::max(live.largest_abs, std::abs(live.latest));
    const double span_s =
        static_cast<double>(batch.time_ns[batch.count - 1]) * 1e-9 - batch.first_time_s;
    if (live.samples > 1 && span_s > 0) {
      live.achieved_rate_hz = static_cast<double>(live.samples - 1) / span_s;
    }
    summary.polled_samples += batch.count;
    batch.count = 0;
  };
  // Takes every polled source's samples and events into the journal; true if any.
  const auto drain_polled = [&] {
    bool any = false;
    for (PolledState& state : polled) {
      for (;;) {
        const std::size_t got = state.source->take_events(polled_events);
        for (std::size_t e = 0; e < got; ++e) {
          const PolledEvent& event = polled_events[e];
          const double time_s = static_cast<double>(event.monotonic_ns - origin_ns) * 1e-9;
          const char* kind = event.kind[0] != '\0' ? event.kind : "mark";
          if (stage) {
            stage->event(time_s, kind, event.channel, event.detail);
          } else {
            write_event(time_s, kind, event.channel, event.detail);
          }
        }
        any |= got > 0;
        if (got < polled_events.size()) break;
      }
      for (;;) {
        const std::size_t got = state.source->take_samples(samples);
        for (std::size_t i = 0; i < got; ++i) {
          const PolledSample& sample = samples[i];
          if (sample.channel >= state.batches.size()) continue;  // not the source's
          const std::int64_t time_ns = sample.midpoint_ns() - origin_ns;
          if (time_ns < 0) {
            ++summary.polled_before_origin;
            continue;
          }
          TimedBatch& batch = state.batches[sample.channel];
          batch.time_ns[batch.count] = time_ns;
          batch.latency_ns[batch.count] = sample.latency_ns();
          batch.raw[batch.count] = sample.raw;
          if (++batch.count == batch.raw.size()) flush_batch(batch);
        }
        any |= got > 0;
        if (got < samples.size()) break;
      }
      for (TimedBatch& batch : state.batches) flush_batch(batch);
    }
    return any;
  };
  try {
    bool start_written = false;
    if (backend == nullptr) {
      // With a trigger stage the journal's start waits for the first kept sample.
      if (sink) {
        sink->attach(*stage, origin_ns, origin_realtime_ns);
      } else {
        journal.append_start(origin_ns, origin_realtime_ns);
      }
      start_written = true;
    }
    for (;;) {
      // Read before draining: everything published before `done` is drained below; the
      // polled sources are stopped (joined) before their last drain.
      const bool done = backend != nullptr
                            ? rings.done.load(std::memory_order_acquire)
                            : monotonic_now_ns() - origin_ns >= duration_ns ||
                                  summary.stopped_by_request || (stage && stage->finished());
      if (done) stop_polled();
      bool wrote = false;
      if (!start_written) {
        const std::int64_t start_ns = rings.start_monotonic_ns.load(std::memory_order_acquire);
        if (start_ns >= 0) {
          origin_ns = start_ns;
          const std::int64_t realtime_ns = rings.start_realtime_ns.load(std::memory_order_relaxed);
          if (sink) {
            sink->attach(*stage, start_ns, realtime_ns);
          } else {
            journal.append_start(start_ns, realtime_ns);
          }
          start_written = true;
        }
      }
      while (const EventSlot* event = rings.events.consumer_slot()) {
        if (stage) {
          stage->event(event->time_s, event->kind, event->channel, event->detail);
        } else {
          write_event(event->time_s, event->kind, event->channel, event->detail);
        }
        rings.events.release();
        wrote = true;
      }
      while (const ScanSlot* slot = rings.scans.consumer_slot()) {
        acquired_scans = slot->first_scan + slot->scan_count;
        if (stage) {
          stage->scans(slot->first_scan, slot->scan_count, slot->counts.data(), slot->capacity);
          written_scans = sink->written_scans();
        } else {
          journal.append_scans(slot->first_scan, slot->scan_count, slot->counts.data(),
                               slot->capacity);
          written_scans = acquired_scans;
        }
        if (slot->scan_count > 0) {
          for (std::size_t c = 0; c < scan_channels; ++c) {
            const std::int32_t* counts = slot->counts.data() + c * slot->capacity;
            status.channels[c].latest = scan_conversion[c](counts[slot->scan_count - 1]);
            const auto [low, high] = std::minmax_element(counts, counts + slot->scan_count);
            status.channels[c].largest_abs =
                std::max({status.channels[c].largest_abs, std::abs(scan_conversion[c](*low)),
                          std::abs(scan_conversion[c](*high))});
          }
        }
        rings.scans.release();
        wrote = true;
      }
      if (start_written) wrote |= drain_polled();
      const std::uint64_t dropped_events = rings.dropped_events.load(std::memory_order_relaxed);
      if (dropped_events > reported_dropped_events) {
        write_event(recorded_s(), "fault", "",
                    std::to_string(dropped_events - reported_dropped_events) +
                        " events lost: the event ring was full");
        reported_dropped_events = dropped_events;
      }
      if (sync_failed.load(std::memory_order_acquire)) throw JournalError(sync_error);
      if (options.stop_requested != nullptr &&
          options.stop_requested->load(std::memory_order_relaxed) && !summary.stopped_by_request) {
        summary.stopped_by_request = true;
        rings.stop.store(true, std::memory_order_relaxed);
      }
      if (stage && stage->finished()) rings.stop.store(true, std::memory_order_relaxed);
      if (wrote && options.progress) {
        status.recorded_s = stage && !sink->begun() ? 0.0 : recorded_s();
        status.scans = written_scans;
        const double elapsed = elapsed_s();
        if (backend != nullptr && elapsed > 0) {
          status.achieved_scan_rate_hz = static_cast<double>(acquired_scans) / elapsed;
        }
        if (stage) {
          status.trigger_state = stage->state() == TriggerStage::State::kArmed ? "armed"
                                 : stage->finished()                           ? "stopped"
                                                                               : "triggered";
        }
        for (std::size_t c = 0; c < scan_channels; ++c) {
          status.channels[c].samples = acquired_scans;
          status.channels[c].achieved_rate_hz = status.achieved_scan_rate_hz;
        }
        status.faults = summary.faults;
        options.progress(status);
        for (ChannelStatus& channel : status.channels) channel.largest_abs = 0.0;
      }
      if (done) break;
      if (!wrote) std::this_thread::sleep_for(poll);
    }
    if (stage) {
      summary.triggered = stage->state() != TriggerStage::State::kArmed;
      summary.trigger_report = stage->summary().brief_report();
      if (!sink->begun()) {
        sink->begin();
        write_event(
            0.0, "mark", "",
            "the start condition never fired: no samples kept (" + summary.trigger_report + ")");
      }
      summary.polled_samples = sink->samples();
    }
    const double end_s = recorded_s();
    for (const PolledState& state : polled) {
      const PolledStatistics statistics = state.source->statistics();
      if (statistics.dropped_samples > 0) {
        write_event(end_s, "fault", "",
                    state.source->description() + ": " +
                        std::to_string(statistics.dropped_samples) +
                        " polled samples lost (not taken in time)");
      }
    }
    if (summary.polled_before_origin > 0) {
      write_event(0.0, "mark", "",
                  std::to_string(summary.polled_before_origin) +
                      " polled samples from before time 0 (the first scan) not kept");
    }
    if (summary.stopped_by_request) {
      char detail[96];
      std::snprintf(detail, sizeof detail, "recording stopped by hand after %.3f s", end_s);
      write_event(end_s, "stop", "", detail);
    }
    if (read_error) {
      write_event(end_s, "fault", "", "the recording stopped: " + read_error_text);
    }
    summary.duration_s = end_s;
    journal.append_end(written_scans);
    stop_syncing();
    journal.sync();
  } catch (const std::exception& error) {
    rings.stop.store(true, std::memory_order_relaxed);
    join_reading();
    stop_syncing();
    try {
      stop_polled();
    } catch (const std::exception&) {
      // The write error is the one to report.
    }
    try {
      journal.sync();
    } catch (const std::exception&) {
      // The write error is the one to report.
    }
    char kept[200];
    std::snprintf(kept, sizeof kept,
                  "; the recording stopped after %.3f s: the %llu scans and %llu polled samples ",
                  recorded_s(), static_cast<unsigned long long>(written_scans),
                  static_cast<unsigned long long>(summary.polled_samples));
    throw JournalError(std::string(error.what()) + kept + "written so far are kept in " +
                       journal_path.string() + " (free space, then: doorbench recover " +
                       journal_path.string() + ")");
  }
  join_reading();

  summary.scans = static_cast<std::size_t>(written_scans);
  summary.dropped_scans = rings.dropped_scans.load();
  summary.dropped_events = rings.dropped_events.load();
  summary.journal_bytes = journal.bytes_written();
  summary.journal_syncs = journal.syncs();

  // The journal stays open (and locked) until the session is complete, so that another
  // doorbench does not take it for an unfinished recording meanwhile.
  ConvertOptions convert;
  convert.writer = options.writer;
  if (backend != nullptr) {
    const double session_origin_s = sink ? sink->offset_s() : 0.0;
    convert.extras = [backend, session_origin_s](SessionWriter& writer) {
      backend->write_extras(writer, session_origin_s);
    };
  }
  try {
    convert_journal(journal_path, path, convert);
  } catch (const std::exception& error) {
    // E.g. the disk filled up during the conversion: the journal is whole and synced.
    throw SessionError(std::string(error.what()) + "; the recording is kept in " +
                       journal_path.string() + " (free space, then: doorbench recover " +
                       journal_path.string() + ")");
  }
  if (read_error) std::rethrow_exception(read_error);
  return summary;
}

}  // namespace doorbench
