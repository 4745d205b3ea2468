#pragma once
// What the recorder needs from a source of samples: the simulated bench today, comedi
// and Modbus devices later. A backend delivers whole scans (one sample of every channel)
// into buffers the recorder allocated beforehand, so reading allocates nothing.
#include <cstdint>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/session_file.h"

namespace doorbench {

// Scans read in one call: counts[channel][scan], and the events they brought.
struct ScanBlock {
  std::vector<std::vector<std::int32_t>> counts;
  std::size_t scan_count = 0;
  std::vector<SessionEvent> events;  // capacity reserved by the recorder

  // Buffers for `channels` channels of up to `max_scans` scans and `max_events` events.
  ScanBlock(std::size_t channels, std::size_t max_scans, std::size_t max_events = 64);
  std::size_t capacity() const { return counts.empty() ? 0 : counts.front().size(); }
};

class AcquisitionBackend {
 public:
  virtual ~AcquisitionBackend() = default;
  virtual std::string description() const = 0;
  // As they go into the session (sample times from the backend's own clock).
  virtual std::vector<ChannelInfo> channels() const = 0;
  virtual std::vector<CalibrationRecord> calibrations() const = 0;
  virtual double scan_rate_hz() const = 0;
  virtual void start() = 0;
  // Fills block.counts[·][0 … n) with the next n ≤ block.capacity() scans and appends
  // their events; returns n (0 when the backend has no more).
  virtual std::size_t read(ScanBlock& block) = 0;
  virtual void stop() = 0;
  // Side data for the session once recording ends (the simulated bench's truth).
  // `session_origin_s`: the time on the backend's clock that became session time 0 (not
  // 0 when a trigger kept only part of the acquisition), for side data with times.
  virtual void write_extras(SessionWriter& writer, double session_origin_s) {
    (void)writer;
    (void)session_origin_s;
  }
};

}  // namespace doorbench
