#pragma once
// Modbus sensors (load-cell transmitters, inclinometers, ...) over libmodbus, TCP or RTU,
// as a doorbench::PolledSource (acquisition/record/polled_source.h). docs/modbus.md.
//
// One polling thread per device (connection). Each channel is polled at its own rate on
// absolute deadlines (clock_nanosleep, CLOCK_MONOTONIC); after a slow reply the latest
// missed deadline is polled at once and earlier ones are skipped (no catch-up burst). Every sample
// is stamped just before the request and just after the reply. Timeouts, exception replies, CRC and
// framing errors become fault events (one per run of the same error on a channel, and a
// mark when the channel answers again); a lost connection is a fault, the thread
// reconnects with exponential back-off (reconnect_min_s doubling up to reconnect_max_s)
// and raises a mark when connected again. The polling threads allocate, lock and log
// nothing per poll: samples and events go through preallocated SpscRings.
#include <atomic>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/record/polled_source.h"
#include "acquisition/rig/rig_file.h"

namespace doorbench::sensors {

class ModbusError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ModbusSourceOptions {
  std::size_t sample_ring_slots = 65536;  // per device: 65 s of 1 kHz if nobody takes them
  std::size_t event_ring_slots = 1024;    // per device
  std::string validate() const;           // "" or one line naming the option
};

// "modbus device NAME (tcp HOST:PORT)" or "modbus device NAME (rtu DEVICE 19200 8N1)".
std::string modbus_device_label(const RigModbusDevice& device);

class ModbusSource : public PolledSource {
 public:
  // The rig's modbus channels (in file order) on its [[modbus.devices]]; throws
  // ModbusError when the rig has none or the options are unusable.
  explicit ModbusSource(const RigDefinition& rig, ModbusSourceOptions options = {});
  ~ModbusSource() override;
  ModbusSource(const ModbusSource&) = delete;
  ModbusSource& operator=(const ModbusSource&) = delete;

  std::string description() const override;
  std::vector<ChannelInfo> channels() const override;
  std::vector<CalibrationRecord> calibrations() const override { return {}; }
  void start() override;
  std::size_t take_samples(std::span<PolledSample> out) override;
  std::size_t take_events(std::span<PolledEvent> out) override;
  void stop() override;
  PolledStatistics statistics() const override;

  struct Device;  // one connection and its thread (modbus_source.cpp)

 private:
  std::vector<ChannelInfo> channels_;
  std::vector<std::unique_ptr<Device>> devices_;
  std::atomic<bool> stop_requested_{false};
  bool running_ = false;
};

// `doorbench devices --rig`: connects to each Modbus device of the rig, reads each of its
// channels once and reports value, unit and latency, or the error, one line per channel.
std::string modbus_probe_report(const RigDefinition& rig);

}  // namespace doorbench::sensors
