#pragma once
// What the recorder needs from a polled source (Modbus sensors today): channels read one
// value at a time by a request and its reply, on the source's own thread(s), each value
// time-stamped on CLOCK_MONOTONIC at the request and at the reply. The recorder places
// them on the session clock at the midpoint and keeps the latency (docs/session-format.md).
//
// Thread safety: start(), stop(), take_samples(), take_events() and statistics() are
// called from one thread (the recorder's writer thread); the source's polling threads
// are its own business. Polling threads must not allocate, lock or log per poll: they
// hand samples over through preallocated lock-free rings (acquisition/record/ring_buffer.h).
#include <time.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/session_file.h"

namespace doorbench {

// CLOCK_MONOTONIC in ns: the one clock every part of a recording is stamped with.
inline std::int64_t monotonic_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

// One polled value.
struct PolledSample {
  std::uint32_t channel = 0;     // index into the source's channels()
  std::int64_t request_ns = 0;   // CLOCK_MONOTONIC just before the request was sent
  std::int64_t response_ns = 0;  // just after its complete reply arrived
  double raw = 0.0;              // the decoded register value; the channel's raw_offset and
                                 // raw_scale make the signal of it
  std::int64_t midpoint_ns() const { return request_ns + (response_ns - request_ns) / 2; }
  std::int64_t latency_ns() const { return response_ns - request_ns; }
};

// A fault or note from a polling thread (timeout, exception reply, CRC error, lost
// connection, reconnected). Fixed-size texts so that making one allocates nothing; a cut
// detail ends in "...".
struct PolledEvent {
  std::int64_t monotonic_ns = 0;
  char kind[32] = {};     // "fault" or "mark"
  char channel[64] = {};  // a channel's name, or empty for the whole device
  char detail[256] = {};
};

struct PolledStatistics {
  std::uint64_t polls = 0;            // requests sent
  std::uint64_t samples = 0;          // values delivered
  std::uint64_t faults = 0;           // fault events raised
  std::uint64_t reconnects = 0;       // successful reconnections
  std::uint64_t dropped_samples = 0;  // lost because nobody took them in time
};

class PolledSource {
 public:
  virtual ~PolledSource() = default;
  virtual std::string description() const = 0;
  // Explicit-time channels as they go into the session (sample_rate_hz 0, RawType::kValues).
  virtual std::vector<ChannelInfo> channels() const = 0;
  virtual std::vector<CalibrationRecord> calibrations() const = 0;
  // Starts polling on the source's own thread(s); returns once they run. Throws (naming
  // the device) when the source cannot start at all; faults after the start are events.
  virtual void start() = 0;
  // Moves up to out.size() samples (in time order per channel) / events gathered since
  // the last call into `out`; returns how many. Never blocks.
  virtual std::size_t take_samples(std::span<PolledSample> out) = 0;
  virtual std::size_t take_events(std::span<PolledEvent> out) = 0;
  // Stops polling and joins the threads; what was gathered before may still be taken.
  virtual void stop() = 0;
  virtual PolledStatistics statistics() const = 0;
};

}  // namespace doorbench
