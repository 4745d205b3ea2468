// A recording's writer side (internal/session_recording.h): the live status, the trigger
// stage, the polled sources' threads, the reading and sync threads, and the loop that
// drains the sources into the journal until the recording is over, then writes its ending.
#include "acquisition/record/internal/session_recording.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "acquisition/record/recovery.h"

namespace doorbench::record_detail {

namespace {

LiveConversion live_conversion(const ChannelInfo& channel,
                               const std::vector<CalibrationRecord>& records, std::string& unit) {
  LiveConversion conversion{channel.raw_offset, channel.raw_scale, nullptr};
  unit = channel.unit;
  if (channel.calibration_id.empty()) {
    if (unit.empty()) unit = channel.raw_type == RawType::kCounts ? "V" : channel.raw_unit;
    return conversion;
  }
  for (const CalibrationRecord& record : records) {
    if (record.id == channel.calibration_id) conversion.record = &record;
  }
  if (conversion.record == nullptr)
    unit = channel.raw_type == RawType::kCounts ? "V" : channel.raw_unit;
  return conversion;
}

}  // namespace

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

}  // namespace doorbench::record_detail
