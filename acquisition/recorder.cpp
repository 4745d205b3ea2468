#include "acquisition/recorder.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
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
  return writer.validate();
}

std::string RecordSummary::brief_report() const {
  char text[256];
  std::snprintf(text, sizeof text, "%zu scans (%.3f s), %zu events; journal %.1f kB, %llu syncs",
                scans, duration_s, events, journal_bytes / 1000.0,
                static_cast<unsigned long long>(journal_syncs));
  std::string report = text;
  if (stopped_by_request) report += "; stopped by request";
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

void RealtimeReader::start() {
  backend_.start();
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  rings_.start_monotonic_ns.store(std::int64_t{now.tv_sec} * 1000000000 + now.tv_nsec,
                                  std::memory_order_release);
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

RecordSummary record_session(AcquisitionBackend& backend, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  const std::vector<ChannelInfo> channels = backend.channels();
  if (channels.empty()) throw std::invalid_argument(backend.description() + ": no channels");
  const double rate_hz = backend.scan_rate_hz();
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument(backend.description() + ": scan rate must be > 0");
  }
  for (const ChannelInfo& channel : channels) {
    if (channel.raw_type != RawType::kCounts) {
      throw std::invalid_argument(backend.description() + ": channel " + channel.name +
                                  " holds values; the recorder records counts");
    }
  }
  const std::size_t block_scans =
      options.block_scans > 0
          ? options.block_scans
          : std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(rate_hz * 0.01)));
  const auto total_scans = static_cast<std::uint64_t>(std::llround(options.duration_s * rate_hz));
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
  header.calibrations = backend.calibrations();
  header.scan_rate_hz = rate_hz;
  header.session_name = path.filename().string();
  header.flush_interval_s = options.flush_interval_s;
  header.backend = backend.description();
  JournalWriter journal(journal_path, header, block_scans);

  const auto scan_slots = std::max<std::size_t>(
      4, static_cast<std::size_t>(std::ceil(options.ring_s * rate_hz / block_scans)));
  RecorderRings rings(channels.size(), block_scans, scan_slots, options.ring_events);
  RealtimeReader reader(backend, rings, channels.size(), block_scans, total_scans,
                        options.when_ring_full);

  std::exception_ptr read_error;
  std::string read_error_text;
  std::thread reading([&] {
    try {
      reader.start();
      while (reader.step()) {
      }
    } catch (const std::exception& error) {
      read_error = std::current_exception();
      read_error_text = error.what();
    } catch (...) {
      read_error = std::current_exception();
      read_error_text = "unknown error";
    }
    try {
      backend.stop();
    } catch (const std::exception& error) {
      if (!read_error) {
        read_error = std::current_exception();
        read_error_text = error.what();
      }
    }
    rings.done.store(true, std::memory_order_release);
  });

  RecordSummary summary;
  std::uint64_t written_scans = 0;
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
  try {
    bool start_written = false;
    for (;;) {
      // Read before draining: everything published before `done` is drained below.
      const bool done = rings.done.load(std::memory_order_acquire);
      bool wrote = false;
      if (!start_written) {
        const std::int64_t start_ns = rings.start_monotonic_ns.load(std::memory_order_acquire);
        if (start_ns >= 0) {
          journal.append_start(start_ns);
          start_written = true;
        }
      }
      while (const EventSlot* event = rings.events.consumer_slot()) {
        journal.append_event(event->time_s, event->kind, event->channel, event->detail);
        rings.events.release();
        ++summary.events;
        wrote = true;
      }
      while (const ScanSlot* slot = rings.scans.consumer_slot()) {
        journal.append_scans(slot->first_scan, slot->scan_count, slot->counts.data(),
                             slot->capacity);
        written_scans = slot->first_scan + slot->scan_count;
        rings.scans.release();
        wrote = true;
      }
      const std::uint64_t dropped_events = rings.dropped_events.load(std::memory_order_relaxed);
      if (dropped_events > reported_dropped_events) {
        journal.append_event(static_cast<double>(written_scans) / rate_hz, "fault", "",
                             std::to_string(dropped_events - reported_dropped_events) +
                                 " events lost: the event ring was full");
        ++summary.events;
        reported_dropped_events = dropped_events;
      }
      if (sync_failed.load(std::memory_order_acquire)) throw JournalError(sync_error);
      if (options.stop_requested != nullptr &&
          options.stop_requested->load(std::memory_order_relaxed) && !summary.stopped_by_request) {
        summary.stopped_by_request = true;
        rings.stop.store(true, std::memory_order_relaxed);
      }
      if (wrote && options.progress) {
        options.progress(static_cast<double>(written_scans) / rate_hz,
                         static_cast<std::size_t>(written_scans));
      }
      if (done) break;
      if (!wrote) std::this_thread::sleep_for(poll);
    }
    const double end_s = static_cast<double>(written_scans) / rate_hz;
    if (summary.stopped_by_request) {
      char detail[96];
      std::snprintf(detail, sizeof detail, "recording stopped by hand after %.3f s", end_s);
      journal.append_event(end_s, "stop", "", detail);
      ++summary.events;
    }
    if (read_error) {
      journal.append_event(end_s, "fault", "", "the recording stopped: " + read_error_text);
      ++summary.events;
    }
    journal.append_end(written_scans);
    stop_syncing();
    journal.sync();
  } catch (const std::exception& error) {
    rings.stop.store(true, std::memory_order_relaxed);
    reading.join();
    stop_syncing();
    try {
      journal.sync();
    } catch (const std::exception&) {
      // The write error is the one to report.
    }
    char kept[160];
    std::snprintf(kept, sizeof kept, "; the recording stopped after %.3f s: the %llu scans ",
                  static_cast<double>(written_scans) / rate_hz,
                  static_cast<unsigned long long>(written_scans));
    throw JournalError(std::string(error.what()) + kept + "written so far are kept in " +
                       journal_path.string() + " (free space, then: doorbench recover " +
                       journal_path.string() + ")");
  }
  reading.join();

  summary.scans = static_cast<std::size_t>(written_scans);
  summary.duration_s = static_cast<double>(written_scans) / rate_hz;
  summary.dropped_scans = rings.dropped_scans.load();
  summary.dropped_events = rings.dropped_events.load();
  summary.journal_bytes = journal.bytes_written();
  summary.journal_syncs = journal.syncs();

  // The journal stays open (and locked) until the session is complete, so that another
  // doorbench does not take it for an unfinished recording meanwhile.
  ConvertOptions convert;
  convert.writer = options.writer;
  convert.extras = [&backend](SessionWriter& writer) { backend.write_extras(writer); };
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
