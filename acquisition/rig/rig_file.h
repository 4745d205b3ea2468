#pragma once
// Rig definition files (TOML, in rigs/): the bench's name, its sample clock and DAQ, its
// channels (sensor kind, backend and device address, range, calibration, sensor-model
// parameters), its triggers and, for the simulated backend, the door and the hand.
// See docs/rig-format.md. Every error is a RigError whose text is
// `FILE:LINE: KEY: what is wrong` (LINE and KEY as close to the cause as TOML allows).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace doorbench {

class RigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A Modbus device (one connection: a TCP server or a serial line), `[[modbus.devices]]`.
struct RigModbusDevice {
  std::string name;             // unique, [A-Za-z0-9_]+; channels name it
  std::string transport;        // tcp | rtu
  std::string host;             // tcp
  int port = 502;               // tcp
  std::string device;           // rtu: the serial device, e.g. /dev/ttyUSB0
  int baud = 19200;             // rtu
  std::string parity = "none";  // rtu: none | even | odd
  int data_bits = 8;            // rtu: 5..8
  int stop_bits = 1;            // rtu: 1 | 2
  double response_timeout_s = 0.1;
  double reconnect_min_s = 0.1;  // back-off after a lost connection, doubling up to max
  double reconnect_max_s = 5.0;
  int line = 0;
};

// Where a Modbus channel's value is and how to read it, `[channels.modbus]`.
// signal (the channel's unit) = offset + scale · decoded register value.
struct RigModbusChannel {
  std::string device;      // a [[modbus.devices]] name
  int unit_id = 1;         // 0..247
  std::string kind;        // holding | input (the register table)
  int address = 0;         // first register, 0-based as on the wire
  std::string type;        // int16 | uint16 | int32 | uint32 | float32
  std::string byte_order;  // big | little: the bytes within each register
  std::string word_order;  // big | little: the registers of a 32-bit value ("" for 16-bit)
  double scale = 1.0;
  double offset = 0.0;
  double range_min = 0.0;  // the signal's valid range, in the channel's unit
  double range_max = 0.0;
  double poll_rate_hz = 0.0;
  int line = 0;
};

struct RigChannel {
  std::string name;            // unique within the rig, [A-Za-z0-9_]+
  std::string sensor;          // load_cell | inclinometer | gyroscope
  std::string serial;          // the sensor's serial number
  std::string backend;         // simulated | comedi | modbus
  std::string address;         // device address in the backend's own notation
  double range_min_V = -10.0;  // the DAQ input range used for this channel
  double range_max_V = 10.0;
  std::string calibration;  // "nominal" (datasheet figures) or a calibration record id;
                            // "" for modbus channels (scale/offset give the physical value)
  std::string unit;         // physical unit after calibration: N (load_cell), rad
                            // (inclinometer), rad/s (gyroscope)
  std::string aref;         // comedi channels: ground | common | diff | other (default
                            // ground); empty for other backends
  // Sensor-model parameters by the names of sensors::*Parameters::fields(), file order.
  std::vector<std::pair<std::string, double>> parameters;
  std::optional<RigModbusChannel> modbus;  // modbus channels only
  int line = 0;                            // of this channel's [[channels]] header
};

struct RigTrigger {
  std::string name;
  std::string kind;    // software | external | level | manual
  std::string source;  // for external: the digital line, e.g. "PFI0"
  // For level (docs/triggering.md): a channel's physical value crossing `level`.
  std::string channel;
  std::string direction;  // rising | falling
  double level = 0.0;
  double hysteresis = 0.0;
  double hold_s = 0.0;    // only for the stop trigger
  bool absolute = false;  // compare |value|
  int line = 0;
};

// [recording]: which triggers start and stop a recording (docs/triggering.md).
struct RigRecording {
  std::string start = "immediate";  // "immediate" or a [[triggers]] name
  std::string stop;                 // a level or manual trigger's name, or empty
  double duration_s = 0.0;          // after the trigger; 0: no duration
  double pre_trigger_s = 1.0;
  std::string strokes;  // a level trigger's name for stroke markers, or empty
  double min_stroke_s = 0.2;
  int line = 0;  // of the [recording] header (0: the table is absent)
};

// The simulated backend's door and virtual hand.
struct RigSimulation {
  std::string door = "reference";  // "reference" (built in) or a parameter file
  std::string model = "physical";  // sensory | physical
  std::string effects;             // optional effects file
  // Optional: a recording (CSV exchange format, with a stroke column) whose force_N drives
  // the door instead of the virtual hand; then [simulation.hand] must be absent.
  std::string force;
  std::uint64_t seed = 1;
  bool realtime = false;  // pace samples in real time, or as fast as possible
  int hand_cycles = 3;    // openings and closings by the virtual hand
  double hand_target_deg = 80.0;
  double hand_cycle_duration_s = 6.0;
  int line = 0;
};

struct RigDefinition {
  std::string source;              // the path (or name) it was read from
  std::string text;                // the whole file, stored in every session
  std::filesystem::path base_dir;  // relative paths inside resolve against this
  // Where channels' calibration ids are looked up (not a key of the file): empty means
  // $DOORBENCH_CALIBRATIONS, else base_dir/calibrations (docs/calibration.md).
  std::filesystem::path calibration_store;

  std::string name;
  std::string description;
  double sample_rate_hz = 1000.0;         // [clock]
  double convert_interval_s = 10e-6;      // [clock], the multiplexed converter's skew step
  std::string daq_backend = "simulated";  // [daq]; "none" when every channel is modbus
  std::string daq_device;
  double daq_range_min_V = -10.0;
  double daq_range_max_V = 10.0;
  int daq_resolution_bits = 16;
  // The [[triggers]] entry that starts the DAQ's acquisition; empty: software start.
  std::string daq_start_trigger;
  std::vector<RigChannel> channels;
  std::vector<RigTrigger> triggers;
  RigRecording recording;                       // defaults when [recording] is absent
  std::vector<RigModbusDevice> modbus_devices;  // [[modbus.devices]]
  std::optional<RigSimulation> simulation;      // required when a channel is simulated

  const RigChannel* find_channel(std::string_view name) const;
  const RigModbusDevice* find_modbus_device(std::string_view name) const;
  // `path` as written in the file, resolved against base_dir unless absolute.
  std::filesystem::path resolve(const std::string& path) const;
};

RigDefinition parse_rig(std::string_view text, std::string_view source,
                        const std::filesystem::path& base_dir);
RigDefinition read_rig_file(const std::filesystem::path& path);

// A rig definition a session stores (SessionMetadata::rig_definition), as the session's
// readers need it: only its channels and their parameters. Relative paths inside resolve
// against the working directory. nullopt when `text` is empty or this build cannot read it
// (a rig key it does not know, a door file no longer where it was): the caller then knows
// no rig, which readers of old sessions must cope with anyway. `source` names it in errors.
std::optional<RigDefinition> parse_stored_rig(std::string_view text, std::string_view source);

// The simulated reference bench (rigs/simulated-dishwasher.toml), built in like the
// reference door, so that `doorbench record` and the demo run without the rigs folder.
std::string_view simulated_dishwasher_rig_text();

}  // namespace doorbench
