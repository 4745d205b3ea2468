#pragma once
// Records a session from a scan backend and/or polled sources, in two threads
// (docs/crash-safety.md, docs/synchronization.md):
//
// - the reading thread starts the backend, reads blocks of scans and copies them, and
//   the events they bring, into preallocated lock-free rings (ring_buffer.h). After the
//   start it allocates nothing, takes no lock and does no I/O;
// - the writer thread (the caller's) drains the rings into the recording journal
//   (journal.h, "SESSION.journal"), syncs it every flush interval, and when recording
//   ends converts it into the HDF5 session, which appears under its name only once it
//   is complete and closed; then the journal is removed.
//
// Polled sources (polled_source.h) poll on their own threads; the writer thread takes
// their samples every poll (a few ms) and journals them as timed frames. Every part is on
// one session clock, CLOCK_MONOTONIC: time 0 is scan 0 of the scan backend or, without
// one, the moment the polled sources were started; polled samples sit at the midpoint of
// request and reply, their latency kept in "<name>_latency".
//
// A recording killed at any moment (SIGKILL, power loss) leaves the journal, from which
// recover_session() (recovery.h) makes the session with every synced scan.
#include <atomic>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/record/backend.h"
#include "acquisition/record/polled_source.h"
#include "acquisition/record/ring_buffer.h"
#include "acquisition/session/session_file.h"
#include "acquisition/record/trigger.h"

namespace doorbench {

// What the reading thread does when the ring is full (the writer fell behind).
enum class RingFullPolicy {
  // A source that runs on its own clock (a DAQ): the block is dropped and a fault event
  // recorded; the session marks the lost scans as a gap (docs/session-format.md).
  kDropAndRecordFault,
  // A source that computes scans on demand (the simulated bench unpaced): wait for room.
  kWait,
};

// The live state of a recording, for a status display.
struct ChannelStatus {
  std::string name;
  std::string unit;     // of `latest`: the physical unit, else the signal's unit
  double latest = 0.0;  // the latest sample, physical where a record or scale gives it
  // The largest |value| (as `latest`) since the previous status: scan channels over every
  // scan (the extremes of the counts, converted), polled channels over their latest values.
  double largest_abs = 0.0;
  std::uint64_t samples = 0;
  double achieved_rate_hz = 0.0;  // scan channels: the scans'; polled: its own samples'
  bool polled = false;
};

struct RecordStatus {
  double recorded_s = 0.0;  // session time written so far
  std::uint64_t scans = 0;
  double achieved_scan_rate_hz = 0.0;   // scans / monotonic time since the origin (0: none)
  std::vector<ChannelStatus> channels;  // scan channels, then polled (no latency channels)
  std::uint64_t faults = 0;             // fault events recorded so far
  std::string trigger_state;            // with a trigger: armed | triggered | stopped
};

struct RecordOptions {
  double duration_s = 10.0;
  std::size_t block_scans = 0;  // scans per read; 0: about 10 ms of scans (at least 1)
  // The journal is synced (fdatasync) at least this often while scans arrive: a power
  // loss costs at most this plus one block and one writer poll (docs/crash-safety.md).
  double flush_interval_s = 0.05;
  double ring_s = 2.0;  // seconds of scans the ring holds between the threads
  std::size_t ring_events = 1024;
  RingFullPolicy when_ring_full = RingFullPolicy::kWait;
  SessionWriterOptions writer;
  // Set (e.g. by a SIGINT handler) to end the recording early; it still ends cleanly
  // with a complete session and a "stop" event.
  const std::atomic<bool>* stop_requested = nullptr;
  // Called by the writer thread after it wrote blocks or samples (for a status line). It
  // may take its time: the reading thread and the polling threads do not wait for it.
  std::function<void(const RecordStatus& status)> progress;
  // Timed samples per journal frame and per take_samples() call.
  std::size_t polled_batch = 1024;
  // Triggering (docs/triggering.md). When set, a TriggerStage between the sources and the
  // journal decides what is kept: the start condition (with `pre_trigger_s` before it),
  // the stop condition, stroke markers. duration_s then bounds the whole acquisition,
  // armed time included, and session time 0 is the first kept sample (not the
  // acquisition's start). Unset: everything from the start is kept.
  std::optional<TriggerOptions> trigger;
  std::string validate() const;  // empty when usable
};

struct RecordSummary {
  std::size_t scans = 0;
  std::size_t events = 0;
  double duration_s = 0.0;
  std::size_t dropped_scans = 0;   // lost to ring overflows (each one a fault event)
  std::size_t dropped_events = 0;  // lost to a full event ring (one fault event says so)
  bool stopped_by_request = false;
  std::uint64_t journal_bytes = 0;
  std::uint64_t journal_syncs = 0;
  std::uint64_t polled_samples = 0;
  std::uint64_t polled_before_origin = 0;  // polled samples from before time 0: not kept
  std::uint64_t faults = 0;                // fault events recorded
  // With RecordOptions::trigger: whether the start condition fired, and what the stage did.
  bool triggered = false;
  std::string trigger_report;
  std::string brief_report() const;
};

// The sources of one recording: zero or one scan backend, any number of polled sources;
// at least one source.
struct RecordSources {
  AcquisitionBackend* scans = nullptr;
  std::vector<PolledSource*> polled;
};

// Records until `options.duration_s`, the end of the backend's scans, or a stop request.
// `path` must not exist (nor its journal). Throws std::invalid_argument for options,
// JournalError/SessionError naming the file when writing fails: a failed journal write
// (e.g. a full disk) stops the recording and keeps the journal, which the message says
// how to recover.
// With a scan backend the recording ends with its scans; polled sources only, after
// duration_s of monotonic time. Polled channels must be explicit-time value channels
// (sample_rate_hz 0); names must be unique over all sources (with "<name>_latency").
RecordSummary record_session(const RecordSources& sources, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options);
RecordSummary record_session(AcquisitionBackend& backend, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options);

// ---------------------------------------------------------------------------------------
// The parts shared by the two threads, public so that tests can drive the reading side
// on its own (tests/acquisition/test_recorder.cpp proves it allocates nothing).

// One block of scans in the ring: counts[c * capacity + s].
struct ScanSlot {
  std::uint64_t first_scan = 0;
  std::size_t scan_count = 0;
  std::size_t capacity = 0;
  std::vector<std::int32_t> counts;
};

// One event in the ring: texts cut to fit (a cut detail ends in "...").
struct EventSlot {
  double time_s = 0.0;
  char kind[32] = {};
  char channel[64] = {};
  char detail[256] = {};
};

struct RecorderRings {
  RecorderRings(std::size_t channels, std::size_t block_scans, std::size_t scan_slots,
                std::size_t event_slots);
  SpscRing<ScanSlot> scans;
  SpscRing<EventSlot> events;
  std::atomic<std::int64_t> start_monotonic_ns{-1};  // set once the backend started
  std::atomic<std::int64_t> start_realtime_ns{0};    // CLOCK_REALTIME at that moment
  std::atomic<std::uint64_t> scans_read{0};
  std::atomic<std::uint64_t> dropped_scans{0};
  std::atomic<std::uint64_t> dropped_events{0};
  std::atomic<std::uint64_t> overflows{0};
  std::atomic<bool> stop{false};  // writer → reader: stop reading
  std::atomic<bool> done{false};  // reader → writer: nothing more will come
};

// The reading side: start() once, then step() until it returns false.
class RealtimeReader {
 public:
  RealtimeReader(AcquisitionBackend& backend, RecorderRings& rings, std::size_t channels,
                 std::size_t block_scans, std::uint64_t total_scans, RingFullPolicy when_full);
  void start();  // starts the backend and notes the monotonic (and UTC) time
  // One read of the backend and its copy into the rings; false when recording is over
  // (duration reached, backend exhausted, stop requested). Never allocates, locks or
  // does I/O itself (the backend's read must not either).
  bool step();
  std::uint64_t scans() const { return scans_; }

 private:
  void push_event(double time_s, const char* kind, const char* channel, const char* detail);
  AcquisitionBackend& backend_;
  RecorderRings& rings_;
  ScanBlock block_;
  std::size_t channels_;
  std::uint64_t total_scans_;
  RingFullPolicy when_full_;
  double scan_rate_hz_;
  std::uint64_t scans_ = 0;
  bool overflowing_ = false;
};

}  // namespace doorbench
