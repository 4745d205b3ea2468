// Rig definition files (docs/rig-format.md): the shipped simulated bench parses, from
// rigs/ and from the built-in copy, and every rule rejects a small inline rig with its
// exact message `FILE:LINE: KEY: what is wrong`.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/rig/rig_file.h"
#include "fixtures/temp_dir.h"
#include "sensors/sensor_models.h"
#include "tests/support/files.h"
#include "tests/support/trigger_test_rig.h"

using doorbench::testing::read_file;

using doorbench::parse_rig;
using doorbench::read_rig_file;
using doorbench::RigDefinition;
using doorbench::RigError;
namespace fs = std::filesystem;

#ifndef DOORBENCH_SOURCE_DIR
#error "tests/CMakeLists.txt defines DOORBENCH_SOURCE_DIR"
#endif

namespace {

// The smallest valid rig; the line numbers in the expected messages refer to it.
constexpr std::string_view kMinimal =
    "[bench]\n"                    // 1
    "name = \"test bench\"\n"      // 2
    "[daq]\n"                      // 3
    "device = \"sim0\"\n"          // 4
    "[[channels]]\n"               // 5
    "name = \"force\"\n"           // 6
    "sensor = \"load_cell\"\n"     // 7
    "serial = \"LC-1\"\n"          // 8
    "backend = \"simulated\"\n"    // 9
    "address = \"sim0/ai0\"\n"     // 10
    "calibration = \"nominal\"\n"  // 11
    "unit = \"N\"\n"               // 12
    "[simulation]\n";              // 13

// A second channel, appended to kMinimal: lines 14 … 21.
constexpr std::string_view kAngleChannel =
    "[[channels]]\n"               // 14
    "name = \"angle\"\n"           // 15
    "sensor = \"inclinometer\"\n"  // 16
    "serial = \"INC-1\"\n"         // 17
    "backend = \"simulated\"\n"    // 18
    "address = \"sim0/ai1\"\n"     // 19
    "calibration = \"nominal\"\n"  // 20
    "unit = \"rad\"\n";            // 21

std::string minimal() {
  return std::string(kMinimal);
}
std::string two_channels() {
  return std::string(kMinimal) + std::string(kAngleChannel);
}

// `text` with its one occurrence of `from` replaced by `to`.
std::string edit(std::string text, std::string_view from, std::string_view to) {
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  REQUIRE(text.find(from, at + 1) == std::string::npos);
  return text.replace(at, from.size(), to);
}

RigDefinition parse(const std::string& text, const fs::path& base_dir = {}) {
  return parse_rig(text, "rig.toml", base_dir);
}

// The message parsing `text` as "rig.toml" fails with, or "(parsed)".
std::string error_of(const std::string& text, const fs::path& base_dir = {}) {
  try {
    parse(text, base_dir);
  } catch (const RigError& error) {
    return error.what();
  }
  return "(parsed)";
}

using doorbench::testing::TempDir;

template <class Parameters>
std::vector<std::string> field_names() {
  std::vector<std::string> names;
  for (const auto& field : Parameters::fields()) names.emplace_back(field.name);
  return names;
}

std::vector<std::string> names_of(const doorbench::RigChannel& channel) {
  std::vector<std::string> names;
  for (const auto& [name, value] : channel.parameters) names.push_back(name);
  return names;
}

double parameter(const doorbench::RigChannel& channel, std::string_view name) {
  for (const auto& [key, value] : channel.parameters) {
    if (key == name) return value;
  }
  FAIL("no parameter " << name << " in channel " << channel.name);
  return 0;
}

void check_shipped_rig(const RigDefinition& rig) {
  CHECK(rig.name == "simulated-dishwasher");
  CHECK_FALSE(rig.description.empty());
  CHECK(rig.sample_rate_hz == 1000.0);
  CHECK(rig.convert_interval_s == 10e-6);
  CHECK(rig.daq_backend == "simulated");
  CHECK(rig.daq_device == "sim0");
  CHECK(rig.daq_range_min_V == -10.0);
  CHECK(rig.daq_range_max_V == 10.0);
  CHECK(rig.daq_resolution_bits == 16);

  REQUIRE(rig.channels.size() == 3);
  const std::string names[] = {"force", "angle", "rate"};
  const std::string sensors[] = {"load_cell", "inclinometer", "gyroscope"};
  const std::string units[] = {"N", "rad", "rad/s"};
  for (std::size_t i = 0; i < 3; ++i) {
    const doorbench::RigChannel& channel = rig.channels[i];
    CHECK(channel.name == names[i]);
    CHECK(channel.sensor == sensors[i]);
    CHECK(channel.unit == units[i]);
    CHECK(channel.backend == "simulated");
    CHECK(channel.address == "sim0/ai" + std::to_string(i));
    CHECK(channel.serial.rfind("SIM-", 0) == 0);
    CHECK(channel.calibration == "nominal");
    CHECK(channel.range_min_V == -10.0);
    CHECK(channel.range_max_V == 10.0);
    CHECK(rig.find_channel(names[i]) == &channel);
  }
  // Every parameter of each sensor model is written out, in the struct's order, with the
  // reference bench's figures (reference-door.json "bench").
  CHECK(names_of(rig.channels[0]) == field_names<doorbench::LoadCellParameters>());
  CHECK(names_of(rig.channels[1]) == field_names<doorbench::InclinometerParameters>());
  CHECK(names_of(rig.channels[2]) == field_names<doorbench::GyroscopeParameters>());
  CHECK(parameter(rig.channels[0], "full_scale_N") == 445.0);
  CHECK(parameter(rig.channels[0], "noise_rms_N") == 0.2);
  CHECK(parameter(rig.channels[1], "range_deg") == 10.0);
  CHECK(parameter(rig.channels[1], "bandwidth_hz") == 10.0);
  CHECK(parameter(rig.channels[1], "noise_rms_deg") == 0.01);
  CHECK(parameter(rig.channels[2], "range_dps") == 100.0);
  CHECK(parameter(rig.channels[2], "noise_rms_dps") == 0.05);
  CHECK(parameter(rig.channels[2], "bias_dps") == 0.2);

  REQUIRE(rig.triggers.size() == 1);
  CHECK(rig.triggers[0].name == "start");
  CHECK(rig.triggers[0].kind == "software");
  CHECK(rig.triggers[0].source.empty());

  REQUIRE(rig.simulation);
  CHECK(rig.simulation->door == "reference");
  CHECK(rig.simulation->model == "physical");
  CHECK(rig.simulation->effects.empty());
  CHECK(rig.simulation->realtime == false);
  CHECK(rig.simulation->hand_cycles == 3);
  CHECK(rig.simulation->hand_target_deg == 80.0);
  CHECK(rig.simulation->hand_cycle_duration_s == 6.0);
}

const fs::path kShippedRig = fs::path(DOORBENCH_SOURCE_DIR) / "rigs" / "simulated-dishwasher.toml";

}  // namespace

// ---------------------------------------------------------------------------------------
TEST_CASE("Rig file: the shipped simulated bench parses from rigs/", "[rig_file]") {
  const RigDefinition rig = read_rig_file(kShippedRig);
  check_shipped_rig(rig);
  CHECK(rig.source == kShippedRig.string());
  CHECK(rig.base_dir == kShippedRig.parent_path());
  CHECK(rig.text == read_file(kShippedRig));
  CHECK(rig.channels[0].line > 0);
  CHECK(rig.channels[0].line < rig.channels[1].line);
  CHECK(rig.channels[1].line < rig.channels[2].line);
  CHECK(rig.triggers[0].line > rig.channels[2].line);
  CHECK(rig.simulation->line > rig.triggers[0].line);
}

TEST_CASE("Rig file: the built-in simulated bench is the file in rigs/", "[rig_file]") {
  const std::string_view text = doorbench::simulated_dishwasher_rig_text();
  CHECK(text == read_file(kShippedRig));
  const RigDefinition rig = parse_rig(text, "simulated-dishwasher.toml", {});
  check_shipped_rig(rig);
  CHECK(rig.text == text);
}

TEST_CASE("Rig file: defaults for everything optional", "[rig_file]") {
  const RigDefinition rig = parse(minimal());
  CHECK(rig.source == "rig.toml");
  CHECK(rig.name == "test bench");
  CHECK(rig.description.empty());
  CHECK(rig.sample_rate_hz == 1000.0);
  CHECK(rig.convert_interval_s == 10e-6);
  CHECK(rig.daq_backend == "simulated");
  CHECK(rig.daq_device == "sim0");
  CHECK(rig.daq_range_min_V == -10.0);
  CHECK(rig.daq_range_max_V == 10.0);
  CHECK(rig.daq_resolution_bits == 16);
  REQUIRE(rig.channels.size() == 1);
  CHECK(rig.channels[0].line == 5);
  CHECK(rig.channels[0].range_min_V == -10.0);
  CHECK(rig.channels[0].range_max_V == 10.0);
  CHECK(rig.channels[0].parameters.empty());
  CHECK(rig.triggers.empty());
  REQUIRE(rig.simulation);
  CHECK(rig.simulation->line == 13);
  CHECK(rig.simulation->door == "reference");
  CHECK(rig.simulation->model == "physical");
  CHECK(rig.simulation->seed == 1u);
  CHECK(rig.simulation->realtime == false);
  CHECK(rig.simulation->hand_cycles == 3);
  CHECK(rig.simulation->hand_target_deg == 80.0);
  CHECK(rig.simulation->hand_cycle_duration_s == 6.0);

  // A channel's range defaults to the DAQ's.
  const RigDefinition narrow =
      parse(edit(minimal(), "device = \"sim0\"\n", "device = \"sim0\"\nrange_V = [-5, 5.5]\n"));
  CHECK(narrow.channels[0].range_min_V == -5.0);
  CHECK(narrow.channels[0].range_max_V == 5.5);
}

TEST_CASE("Rig file: find_channel and resolve", "[rig_file]") {
  RigDefinition rig = parse(two_channels(), "/bench/rigs");
  REQUIRE(rig.find_channel("angle") != nullptr);
  CHECK(rig.find_channel("angle")->sensor == "inclinometer");
  CHECK(rig.find_channel("angl") == nullptr);
  CHECK(rig.resolve("doors/d.json") == fs::path("/bench/rigs/doors/d.json"));
  CHECK(rig.resolve("/elsewhere/d.json") == fs::path("/elsewhere/d.json"));
  rig.base_dir.clear();
  CHECK(rig.resolve("doors/d.json") == fs::path("doors/d.json"));
}

// --- syntax, missing and unknown keys, types ---------------------------------------------
TEST_CASE("Rig file: TOML syntax errors give toml++'s message and line", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "device = \"sim0\"", "device = ")) ==
        "rig.toml:4: syntax: Error while parsing key-value pair: expected value, saw '\\n'");
  CHECK(error_of(edit(minimal(), "serial = \"LC-1\"\n", "serial = \"LC-1\"\nname = \"x\"\n")) ==
        "rig.toml:9: syntax: Error while parsing key-value pair: cannot redefine existing "
        "string 'name' (given twice: lines 6 and 9; a file says each thing once)");
}

TEST_CASE("Rig file: a key or a table given twice is refused with both lines", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "[simulation]\n", "[simulation]\n[daq]\ndevice = \"x\"\n")) ==
        "rig.toml:14: syntax: Error while parsing table header: cannot redefine existing table "
        "'daq' (given twice: lines 3 and 14; a file says each thing once)");
  CHECK(error_of(edit(minimal(), "name = \"test bench\"\n",
                      "name = \"test bench\"\nname = \"other\"\n")) ==
        "rig.toml:3: syntax: Error while parsing key-value pair: cannot redefine existing "
        "string 'name' (given twice: lines 2 and 3; a file says each thing once)");
}

TEST_CASE("Rig file: [bench] and its name are required", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "[bench]\nname = \"test bench\"\n", "")) ==
        "rig.toml:1: bench: missing required table [bench]");
  CHECK(error_of(edit(minimal(), "name = \"test bench\"", "description = \"no name\"")) ==
        "rig.toml:1: bench.name: missing required key");
  CHECK(error_of(edit(minimal(), "name = \"test bench\"", "name = \"\"")) ==
        "rig.toml:2: bench.name: must not be empty");
  CHECK(error_of(edit(minimal(), "name = \"test bench\"", "name = 3")) ==
        "rig.toml:2: bench.name: must be a string, not an integer");
  CHECK(error_of("bench = \"x\"\n" + edit(minimal(), "[bench]\nname = \"test bench\"\n", "")) ==
        "rig.toml:1: bench: must be a table, not a string");
}

TEST_CASE("Rig file: unknown keys are errors everywhere", "[rig_file]") {
  CHECK(error_of("colour = 1\n" + minimal()) ==
        "rig.toml:1: colour: unknown key; valid keys: bench, clock, daq, modbus, channels, "
        "triggers, recording, simulation");
  CHECK(error_of(edit(minimal(), "name = \"test bench\"", "nmae = \"test bench\"")) ==
        "rig.toml:2: bench.nmae: unknown key; valid keys: name, description");
  CHECK(error_of(edit(minimal(), "device = \"sim0\"", "device = \"sim0\"\nbits = 16")) ==
        "rig.toml:5: daq.bits: unknown key; valid keys: backend, device, range_V, "
        "resolution_bits, start_trigger");
  CHECK(error_of(edit(minimal(), "sensor = ", "sensr = ")) ==
        "rig.toml:7: channels[0].sensr: unknown key; valid keys: name, sensor, serial, backend, "
        "address, range_V, aref, calibration, unit, parameters, modbus");
  CHECK(error_of(minimal() + "door_model = \"physical\"\n") ==
        "rig.toml:14: simulation.door_model: unknown key; valid keys: door, model, effects, "
        "force, seed, realtime, hand");
  CHECK(error_of(minimal() + "[simulation.hand]\ncycle = 2\n") ==
        "rig.toml:15: simulation.hand.cycle: unknown key; valid keys: cycles, target_deg, "
        "cycle_duration_s");
  CHECK(error_of(minimal() + "[[triggers]]\nname = \"go\"\nkind = \"software\"\nline = 1\n") ==
        "rig.toml:17: triggers[0].line: unknown key; valid keys: name, kind, source, channel, "
        "direction, level, hysteresis, hold_s, absolute, unit");
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nrate_hz = 500\n[daq]")) ==
        "rig.toml:4: clock.rate_hz: unknown key; valid keys: sample_rate_hz, convert_interval_s");
}

TEST_CASE("Rig file: numbers must be finite numbers", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nsample_rate_hz = \"1000\"\n[daq]")) ==
        "rig.toml:4: clock.sample_rate_hz: must be a number, not a string");
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nsample_rate_hz = inf\n[daq]")) ==
        "rig.toml:4: clock.sample_rate_hz: must be a finite number (got inf)");
  // Integers are numbers too.
  CHECK(parse(edit(minimal(), "[daq]", "[clock]\nsample_rate_hz = 500\n[daq]")).sample_rate_hz ==
        500.0);
}

// --- [clock] and [daq] --------------------------------------------------------------------
TEST_CASE("Rig file: clock.sample_rate_hz must be from 1 Hz to 200 kHz", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nsample_rate_hz = 0\n[daq]")) ==
        "rig.toml:4: clock.sample_rate_hz: must be from 1 to 200000 Hz (got 0)");
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nsample_rate_hz = -2.5\n[daq]")) ==
        "rig.toml:4: clock.sample_rate_hz: must be from 1 to 200000 Hz (got -2.5)");
  // Neither 1e9 Hz (std::bad_alloc) nor 1e-9 Hz (a "successful" empty recording) gets through.
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nsample_rate_hz = 1e9\n[daq]")) ==
        "rig.toml:4: clock.sample_rate_hz: must be from 1 to 200000 Hz (got 1e+09)");
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nsample_rate_hz = 1e-9\n[daq]")) ==
        "rig.toml:4: clock.sample_rate_hz: must be from 1 to 200000 Hz (got 1e-09)");
  CHECK(parse(edit(minimal(), "[daq]", "[clock]\nsample_rate_hz = 200000\n[daq]")).sample_rate_hz ==
        200000.0);
}

TEST_CASE("Rig file: clock.convert_interval_s must be >= 0", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nconvert_interval_s = -1e-6\n[daq]")) ==
        "rig.toml:4: clock.convert_interval_s: must be from 0 to 1 s (got -1e-06)");
  CHECK(error_of(edit(minimal(), "[daq]", "[clock]\nconvert_interval_s = 2\n[daq]")) ==
        "rig.toml:4: clock.convert_interval_s: must be from 0 to 1 s (got 2)");
  CHECK(parse(edit(minimal(), "[daq]", "[clock]\nconvert_interval_s = 0\n[daq]"))
            .convert_interval_s == 0.0);
}

TEST_CASE("Rig file: a scan must fit in one sample period", "[rig_file]") {
  const std::string too_slow =
      edit(two_channels(), "[daq]", "[clock]\nconvert_interval_s = 0.001\n[daq]");
  CHECK(error_of(too_slow) ==
        "rig.toml:4: clock.convert_interval_s: (channels - 1) * convert_interval_s = (2 - 1) * "
        "0.001 s = 0.001 s must be less than the sample period 1 / sample_rate_hz = 0.001 s");
  CHECK(parse(edit(two_channels(), "[daq]", "[clock]\nconvert_interval_s = 0.0009\n[daq]"))
            .channels.size() == 2);
  // One channel: no skew, whatever the interval.
  CHECK(parse(edit(minimal(), "[daq]", "[clock]\nconvert_interval_s = 0.5\n[daq]"))
            .convert_interval_s == 0.5);
}

TEST_CASE("Rig file: [daq] and its device are required", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "[daq]\ndevice = \"sim0\"\n", "")) ==
        "rig.toml:1: daq: missing required table [daq]");
  CHECK(error_of(edit(minimal(), "device = \"sim0\"\n", "")) ==
        "rig.toml:3: daq.device: missing required key");
}

TEST_CASE("Rig file: daq.backend is simulated or comedi", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "device = \"sim0\"", "device = \"sim0\"\nbackend = \"modbus\"")) ==
        "rig.toml:5: daq.backend: \"modbus\" is not a DAQ backend; valid: simulated, comedi, "
        "none");
}

TEST_CASE("Rig file: daq.resolution_bits is an integer from 8 to 24", "[rig_file]") {
  auto with_bits = [](std::string_view bits) {
    return edit(minimal(), "device = \"sim0\"",
                "device = \"sim0\"\nresolution_bits = " + std::string(bits));
  };
  CHECK(error_of(with_bits("7")) ==
        "rig.toml:5: daq.resolution_bits: must be an integer from 8 to 24 (got 7)");
  CHECK(error_of(with_bits("25")) ==
        "rig.toml:5: daq.resolution_bits: must be an integer from 8 to 24 (got 25)");
  CHECK(error_of(with_bits("16.0")) ==
        "rig.toml:5: daq.resolution_bits: must be an integer, not a float");
  CHECK(parse(with_bits("8")).daq_resolution_bits == 8);
  CHECK(parse(with_bits("24")).daq_resolution_bits == 24);
}

TEST_CASE("Rig file: daq.range_V is [min, max] with min < max", "[rig_file]") {
  auto with_range = [](std::string_view range) {
    return edit(minimal(), "device = \"sim0\"",
                "device = \"sim0\"\nrange_V = " + std::string(range));
  };
  CHECK(error_of(with_range("[1, 1]")) == "rig.toml:5: daq.range_V: min 1 V must be below max 1 V");
  CHECK(error_of(with_range("[-5]")) ==
        "rig.toml:5: daq.range_V: must be [min, max], two numbers in volts");
  CHECK(error_of(with_range("[-5, \"5\"]")) ==
        "rig.toml:5: daq.range_V: must be [min, max], two numbers in volts");
  const RigDefinition rig = parse(with_range("[0, 5]"));
  CHECK(rig.daq_range_min_V == 0.0);
  CHECK(rig.daq_range_max_V == 5.0);
}

// --- [[channels]] -------------------------------------------------------------------------
TEST_CASE("Rig file: at least one channel", "[rig_file]") {
  const std::string no_channels = "[bench]\nname = \"b\"\n[daq]\ndevice = \"sim0\"\n";
  CHECK(error_of(no_channels) ==
        "rig.toml:1: channels: at least one [[channels]] table is required");
  CHECK(error_of("channels = []\n" + no_channels) ==
        "rig.toml:1: channels: at least one [[channels]] table is required");
  CHECK(error_of(no_channels + "channels = 3\n") ==
        "rig.toml:5: daq.channels: unknown key; valid keys: backend, device, range_V, "
        "resolution_bits, start_trigger");
  CHECK(error_of("channels = 3\n" + no_channels) ==
        "rig.toml:1: channels: must be an array of tables ([[channels]]), not an integer");
  CHECK(error_of("channels = [3]\n" + no_channels) ==
        "rig.toml:1: channels[0]: must be a table, not an integer");
}

TEST_CASE("Rig file: channel names are [A-Za-z0-9_]+", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "name = \"force\"", "name = \"for ce\"")) ==
        "rig.toml:6: channels[0].name: \"for ce\" must consist of letters, digits and _ only");
  CHECK(error_of(edit(minimal(), "name = \"force\"", "name = \"force-N\"")) ==
        "rig.toml:6: channels[0].name: \"force-N\" must consist of letters, digits and _ only");
  CHECK(error_of(edit(minimal(), "name = \"force\"\n", "")) ==
        "rig.toml:5: channels[0].name: missing required key");
  CHECK(parse(edit(minimal(), "name = \"force\"", "name = \"Force_2\"")).channels[0].name ==
        "Force_2");
}

TEST_CASE("Rig file: channel names are unique", "[rig_file]") {
  CHECK(error_of(edit(two_channels(), "name = \"angle\"", "name = \"force\"")) ==
        "rig.toml:15: channels[1].name: \"force\" is already the name of channels[0] (line 5)");
}

TEST_CASE("Rig file: sensor is load_cell, inclinometer or gyroscope", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "sensor = \"load_cell\"", "sensor = \"loadcell\"")) ==
        "rig.toml:7: channels[0].sensor: \"loadcell\" is not a sensor kind; valid: load_cell, "
        "inclinometer, gyroscope");
  CHECK(error_of(edit(minimal(), "sensor = \"load_cell\"\n", "")) ==
        "rig.toml:5: channels[0].sensor: missing required key");
}

TEST_CASE("Rig file: serial is required", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "serial = \"LC-1\"\n", "")) ==
        "rig.toml:5: channels[0].serial: missing required key");
  CHECK(error_of(edit(minimal(), "serial = \"LC-1\"", "serial = \"\"")) ==
        "rig.toml:8: channels[0].serial: must not be empty");
}

TEST_CASE("Rig file: backend is simulated, comedi or modbus", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "backend = \"simulated\"", "backend = \"sim\"")) ==
        "rig.toml:9: channels[0].backend: \"sim\" is not a backend; valid: simulated, comedi, "
        "modbus");
}

TEST_CASE("Rig file: analog channels use the DAQ's backend", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "backend = \"simulated\"", "backend = \"comedi\"")) ==
        "rig.toml:9: channels[0].backend: \"comedi\" does not match daq.backend \"simulated\" "
        "(simulated and comedi channels are sampled by the rig's DAQ)");
  // A Modbus sensor is read on its own, beside any DAQ.
  const RigDefinition rig = parse(
      "[modbus]\n[[modbus.devices]]\nname = \"line\"\ntransport = \"rtu\"\ndevice = "
      "\"/dev/ttyUSB0\"\n" +
      edit(edit(two_channels(), "backend = \"simulated\"\naddress = \"sim0/ai1\"",
                "backend = \"modbus\""),
           "calibration = \"nominal\"\nunit = \"rad\"\n",
           "unit = \"rad\"\n[channels.modbus]\ndevice = \"line\"\nregister = \"input\"\n"
           "address = 0\ntype = \"int16\"\nbyte_order = \"big\"\nrange = [-1, 1]\n"
           "poll_rate_hz = 10\n"));
  CHECK(rig.channels[1].backend == "modbus");
}

TEST_CASE("Rig file: addresses are unique per backend", "[rig_file]") {
  CHECK(error_of(edit(two_channels(), "address = \"sim0/ai1\"", "address = \"sim0/ai0\"")) ==
        "rig.toml:19: channels[1].address: \"sim0/ai0\" is already the address of channels[0] "
        "(line 5)");
  CHECK(error_of(edit(minimal(), "address = \"sim0/ai0\"\n", "")) ==
        "rig.toml:5: channels[0].address: missing required key");
}

TEST_CASE("Rig file: unit matches the sensor kind", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "unit = \"N\"", "unit = \"kg\"")) ==
        "rig.toml:12: channels[0].unit: \"kg\" does not fit sensor load_cell, whose unit is \"N\"");
  CHECK(error_of(edit(two_channels(), "unit = \"rad\"", "unit = \"deg\"")) ==
        "rig.toml:21: channels[1].unit: \"deg\" does not fit sensor inclinometer, whose unit is "
        "\"rad\"");
  CHECK(error_of(edit(two_channels(), "unit = \"rad\"", "unit = \"rad/s\"")) ==
        "rig.toml:21: channels[1].unit: \"rad/s\" does not fit sensor inclinometer, whose unit "
        "is \"rad\"");
  CHECK(error_of(edit(minimal(), "unit = \"N\"\n", "")) ==
        "rig.toml:5: channels[0].unit: missing required key");
}

TEST_CASE("Rig file: channel range_V is [min, max] inside the DAQ's range", "[rig_file]") {
  auto with_range = [](std::string_view range) {
    return edit(minimal(),
                "calibration = ", "range_V = " + std::string(range) + "\ncalibration = ");
  };
  CHECK(error_of(with_range("[5, -5]")) ==
        "rig.toml:11: channels[0].range_V: min 5 V must be below max -5 V");
  CHECK(error_of(with_range("5")) ==
        "rig.toml:11: channels[0].range_V: must be [min, max], two numbers in volts");
  CHECK(error_of(with_range("[-12, 12]")) ==
        "rig.toml:11: channels[0].range_V: [-12, 12] V must lie inside the DAQ's range [-10, 10] "
        "V (daq.range_V)");
  CHECK(error_of(with_range("[-10, 10.5]")) ==
        "rig.toml:11: channels[0].range_V: [-10, 10.5] V must lie inside the DAQ's range [-10, "
        "10] V (daq.range_V)");
  const RigDefinition rig = parse(with_range("[-5, 10]"));
  CHECK(rig.channels[0].range_min_V == -5.0);
  CHECK(rig.channels[0].range_max_V == 10.0);
}

TEST_CASE("Rig file: calibration is required and not empty", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "calibration = \"nominal\"", "calibration = \"\"")) ==
        "rig.toml:11: channels[0].calibration: must not be empty");
  CHECK(error_of(edit(minimal(), "calibration = \"nominal\"\n", "")) ==
        "rig.toml:5: channels[0].calibration: missing required key");
  CHECK(parse(edit(minimal(), "\"nominal\"", "\"cal-2024-03-lc445\"")).channels[0].calibration ==
        "cal-2024-03-lc445");
}

namespace {
// kMinimal with a [channels.parameters] table on line 13 and `lines` from line 14.
std::string with_parameters(std::string_view lines) {
  return edit(minimal(), "unit = \"N\"\n",
              "unit = \"N\"\n[channels.parameters]\n" + std::string(lines) + "\n");
}
}  // namespace

TEST_CASE("Rig file: parameters are the sensor model's fields, in file order", "[rig_file]") {
  const RigDefinition rig =
      parse(with_parameters("zero_offset_N = 1.5\nfull_scale_N = 200\ncompression_only = 0"));
  const std::vector<std::pair<std::string, double>> expected = {
      {"zero_offset_N", 1.5}, {"full_scale_N", 200.0}, {"compression_only", 0.0}};
  CHECK(rig.channels[0].parameters == expected);
  // An inline table works as well.
  const RigDefinition inline_table = parse(
      edit(minimal(), "unit = \"N\"\n", "unit = \"N\"\nparameters = { noise_rms_N = 0.5 }\n"));
  CHECK(inline_table.channels[0].parameters ==
        std::vector<std::pair<std::string, double>>{{"noise_rms_N", 0.5}});
}

TEST_CASE("Rig file: an unknown parameter is named with the valid ones", "[rig_file]") {
  CHECK(error_of(with_parameters("noise_rms = 0.3")) ==
        "rig.toml:14: channels[0].parameters.noise_rms: not a parameter of load_cell; valid: "
        "full_scale_N, sensitivity_mV_per_V, excitation_V, amplifier_gain, noise_rms_N, "
        "nonlinearity_fraction_fs, hysteresis_fraction_fs, overload_fraction_fs, zero_offset_N, "
        "compression_only");
  // A load cell's parameter is not an inclinometer's.
  CHECK(error_of(two_channels() + "[channels.parameters]\nnoise_rms_N = 0.3\n") ==
        "rig.toml:23: channels[1].parameters.noise_rms_N: not a parameter of inclinometer; valid: "
        "range_deg, bandwidth_hz, noise_rms_deg, offset_deg, output_V_per_deg");
}

TEST_CASE("Rig file: parameter values are numbers", "[rig_file]") {
  CHECK(error_of(with_parameters("noise_rms_N = \"0.3\"")) ==
        "rig.toml:14: channels[0].parameters.noise_rms_N: must be a number, not a string");
  CHECK(error_of(with_parameters("compression_only = true")) ==
        "rig.toml:14: channels[0].parameters.compression_only: must be a number, not a boolean");
  CHECK(error_of(with_parameters("noise_rms_N = nan")) ==
        "rig.toml:14: channels[0].parameters.noise_rms_N: must be a finite number (got nan)");
  CHECK(error_of(edit(minimal(), "unit = \"N\"\n", "unit = \"N\"\nparameters = 3\n")) ==
        "rig.toml:13: channels[0].parameters: must be a table, not an integer");
}

TEST_CASE("Rig file: parameters must pass the sensor model's validation", "[rig_file]") {
  doorbench::LoadCellParameters load_cell;
  load_cell.noise_rms_N = -1.0;
  const std::string message = load_cell.validate();
  REQUIRE_FALSE(message.empty());
  CHECK(error_of(with_parameters("full_scale_N = 445\nnoise_rms_N = -1.0")) ==
        "rig.toml:15: channels[0].parameters.noise_rms_N: " + message);

  doorbench::GyroscopeParameters gyroscope;
  gyroscope.range_dps = 0.0;
  const std::string gyroscope_message = gyroscope.validate();
  REQUIRE_FALSE(gyroscope_message.empty());
  const std::string gyroscope_rig =
      edit(edit(two_channels(), "\"inclinometer\"", "\"gyroscope\""), "\"rad\"", "\"rad/s\"") +
      "[channels.parameters]\nrange_dps = 0\n";
  CHECK(error_of(gyroscope_rig) ==
        "rig.toml:23: channels[1].parameters.range_dps: " + gyroscope_message);
}

// --- [[triggers]] -------------------------------------------------------------------------
TEST_CASE("Rig file: trigger kind is software, external, level or manual", "[rig_file]") {
  const std::string rig = minimal() + "[[triggers]]\nname = \"start\"\nkind = \"hardware\"\n";
  CHECK(error_of(rig) ==
        "rig.toml:16: triggers[0].kind: \"hardware\" is not a trigger kind; valid: software, "
        "external, level, manual");
  CHECK(error_of(minimal() + "[[triggers]]\nname = \"start\"\n") ==
        "rig.toml:14: triggers[0].kind: missing required key");
}

TEST_CASE("Rig file: an external trigger needs a source, only it", "[rig_file]") {
  CHECK(error_of(minimal() + "[[triggers]]\nname = \"door_switch\"\nkind = \"external\"\n") ==
        "rig.toml:14: triggers[0].source: missing required key (an external trigger needs its "
        "input line, e.g. \"PFI0\")");
  CHECK(error_of(minimal() +
                 "[[triggers]]\nname = \"start\"\nkind = \"software\"\nsource = \"PFI0\"\n") ==
        "rig.toml:17: triggers[0].source: only external triggers have a source");
  const RigDefinition rig =
      parse(minimal() + "[[triggers]]\nname = \"start\"\nkind = \"software\"\n" +
            "[[triggers]]\nname = \"door_switch\"\nkind = \"external\"\nsource = \"PFI0\"\n");
  REQUIRE(rig.triggers.size() == 2);
  CHECK(rig.triggers[1].name == "door_switch");
  CHECK(rig.triggers[1].kind == "external");
  CHECK(rig.triggers[1].source == "PFI0");
  CHECK(rig.triggers[1].line == 17);
}

TEST_CASE("Rig file: trigger names are unique [A-Za-z0-9_]+", "[rig_file]") {
  CHECK(error_of(minimal() + "[[triggers]]\nname = \"go now\"\nkind = \"software\"\n") ==
        "rig.toml:15: triggers[0].name: \"go now\" must consist of letters, digits and _ only");
  CHECK(error_of(minimal() + "[[triggers]]\nname = \"go\"\nkind = \"software\"\n" +
                 "[[triggers]]\nname = \"go\"\nkind = \"software\"\n") ==
        "rig.toml:18: triggers[1].name: \"go\" is already the name of triggers[0] (line 14)");
}

// --- [simulation] -------------------------------------------------------------------------
TEST_CASE("Rig file: [simulation] is required iff a channel is simulated", "[rig_file]") {
  CHECK(error_of(edit(minimal(), "[simulation]\n", "")) ==
        "rig.toml:9: simulation: missing table [simulation], required because "
        "channels[0].backend is \"simulated\"");

  const std::string comedi =
      edit(edit(minimal(), "device = \"sim0\"", "backend = \"comedi\"\ndevice = \"/dev/comedi0\""),
           "backend = \"simulated\"", "backend = \"comedi\"");
  CHECK(error_of(comedi) ==
        "rig.toml:14: simulation: only for rigs with simulated channels (no channel's backend is "
        "\"simulated\")");
  const RigDefinition rig = parse(edit(comedi, "[simulation]\n", ""));
  CHECK(rig.daq_backend == "comedi");
  CHECK_FALSE(rig.simulation.has_value());
}

TEST_CASE("Rig file: simulation.model is sensory or physical", "[rig_file]") {
  CHECK(error_of(minimal() + "model = \"full\"\n") ==
        "rig.toml:14: simulation.model: \"full\" is not a door model; valid: sensory, physical");
  CHECK(parse(minimal() + "model = \"sensory\"\n").simulation->model == "sensory");
}

TEST_CASE("Rig file: simulation.seed is a non-negative integer", "[rig_file]") {
  CHECK(error_of(minimal() + "seed = -1\n") ==
        "rig.toml:14: simulation.seed: must be >= 0 (got -1)");
  CHECK(error_of(minimal() + "seed = 1.5\n") ==
        "rig.toml:14: simulation.seed: must be an integer, not a float");
  CHECK(parse(minimal() + "seed = 9223372036854775807\n").simulation->seed ==
        9223372036854775807ULL);
  CHECK(parse(minimal() + "seed = 0\n").simulation->seed == 0u);
}

TEST_CASE("Rig file: simulation.realtime is a boolean", "[rig_file]") {
  CHECK(error_of(minimal() + "realtime = \"no\"\n") ==
        "rig.toml:14: simulation.realtime: must be true or false, not a string");
  CHECK(parse(minimal() + "realtime = true\n").simulation->realtime);
}

TEST_CASE("Rig file: the virtual hand's settings", "[rig_file]") {
  const std::string hand = minimal() + "[simulation.hand]\n";  // keys from line 15
  CHECK(error_of(hand + "cycles = 0\n") ==
        "rig.toml:15: simulation.hand.cycles: must be >= 1 (got 0)");
  CHECK(error_of(hand + "cycles = 2.0\n") ==
        "rig.toml:15: simulation.hand.cycles: must be an integer, not a float");
  CHECK(error_of(hand + "target_deg = 0\n") ==
        "rig.toml:15: simulation.hand.target_deg: must be > 0 and < 180 (got 0)");
  CHECK(error_of(hand + "target_deg = 180\n") ==
        "rig.toml:15: simulation.hand.target_deg: must be > 0 and < 180 (got 180)");
  CHECK(error_of(hand + "cycle_duration_s = 0\n") ==
        "rig.toml:15: simulation.hand.cycle_duration_s: must be > 0 (got 0)");
  // 1e300 s is refused, not recorded "successfully" as nothing.
  CHECK(error_of(hand + "cycle_duration_s = 1e300\n") ==
        "rig.toml:15: simulation.hand.cycle_duration_s: cycles * cycle_duration_s = 3 * 1e+300 s "
        "= 3e+300 s must be <= 86400 s (a day)");
  CHECK(error_of(hand + "cycles = 100000\n") ==
        "rig.toml:15: simulation.hand.cycles: cycles * cycle_duration_s = 100000 * 6 s = 6e+05 s "
        "must be <= 86400 s (a day)");
  const RigDefinition rig = parse(hand + "cycles = 1\ntarget_deg = 45.5\ncycle_duration_s = 2\n");
  CHECK(rig.simulation->hand_cycles == 1);
  CHECK(rig.simulation->hand_target_deg == 45.5);
  CHECK(rig.simulation->hand_cycle_duration_s == 2.0);
  // The dotted form is the same table.
  CHECK(parse(minimal() + "hand.cycles = 5\n").simulation->hand_cycles == 5);
}

TEST_CASE("Rig file: a door file resolves against the rig file's folder", "[rig_file]") {
  const TempDir dir;
  const fs::path door = dir.write("doors/door.json", "{}");
  const fs::path rig_path = dir.write("rig.toml", minimal() + "door = \"doors/door.json\"\n");

  const RigDefinition rig = read_rig_file(rig_path);
  CHECK(rig.base_dir == dir.path);
  CHECK(rig.source == rig_path.string());
  REQUIRE(rig.simulation);
  CHECK(rig.simulation->door == "doors/door.json");  // as written
  CHECK(rig.resolve(rig.simulation->door) == door);
  CHECK(fs::equivalent(rig.resolve(rig.simulation->door), door));

  // The same text from elsewhere does not find the door.
  const fs::path elsewhere = dir.path / "elsewhere";
  fs::create_directories(elsewhere);
  CHECK(error_of(minimal() + "door = \"doors/door.json\"\n", elsewhere) ==
        "rig.toml:14: simulation.door: \"doors/door.json\" resolves to " +
            (elsewhere / "doors/door.json").string() + ", which does not exist");

  // Missing file, from a file on disk: the message names the file and the resolved path.
  const fs::path missing_rig =
      dir.write("missing.toml", minimal() + "door = \"doors/nope.json\"\n");
  try {
    read_rig_file(missing_rig);
    FAIL("no error");
  } catch (const RigError& error) {
    CHECK(std::string(error.what()) ==
          missing_rig.string() + ":14: simulation.door: \"doors/nope.json\" resolves to " +
              (dir.path / "doors/nope.json").string() + ", which does not exist");
  }

  // An absolute path is used as it is; a folder is not a door file.
  CHECK(parse(minimal() + "door = \"" + door.string() + "\"\n", elsewhere).simulation->door ==
        door.string());
  CHECK(error_of(minimal() + "door = \"doors\"\n", dir.path) ==
        "rig.toml:14: simulation.door: \"doors\" resolves to " + (dir.path / "doors").string() +
            ", which is not a file");
}

TEST_CASE("Rig file: an effects file must exist too", "[rig_file]") {
  const TempDir dir;
  dir.write("effects.json", "{}");
  CHECK(parse(minimal() + "effects = \"effects.json\"\n", dir.path).simulation->effects ==
        "effects.json");
  CHECK(error_of(minimal() + "effects = \"stiff.json\"\n", dir.path) ==
        "rig.toml:14: simulation.effects: \"stiff.json\" resolves to " +
            (dir.path / "stiff.json").string() + ", which does not exist");
  CHECK(error_of(minimal() + "effects = \"\"\n", dir.path) ==
        "rig.toml:14: simulation.effects: must not be empty");
}

TEST_CASE("Rig file: a scripted force file replaces the virtual hand", "[rig_file]") {
  const TempDir dir;
  dir.write("push.csv", "time_s,force_N,rate_rad_s,stroke\n0,1,0,1\n1,2,0,1\n");
  CHECK(parse(minimal() + "force = \"push.csv\"\n", dir.path).simulation->force == "push.csv");
  CHECK(error_of(minimal() + "force = \"pull.csv\"\n", dir.path) ==
        "rig.toml:14: simulation.force: \"pull.csv\" resolves to " +
            (dir.path / "pull.csv").string() + ", which does not exist");
  CHECK(error_of(minimal() + "force = \"push.csv\"\n[simulation.hand]\ncycles = 2\n", dir.path) ==
        "rig.toml:14: simulation.force: a scripted force replaces the virtual hand: remove "
        "[simulation.hand]");
}

TEST_CASE("Rig file: a missing or unreadable file", "[rig_file]") {
  const TempDir dir;
  const fs::path missing = dir.path / "no-such-rig.toml";
  try {
    read_rig_file(missing);
    FAIL("no error");
  } catch (const RigError& error) {
    CHECK(std::string(error.what()) ==
          missing.string() + ": cannot read the rig file: No such file or directory");
  }
  try {
    read_rig_file(dir.path);
    FAIL("no error");
  } catch (const RigError& error) {
    CHECK(std::string(error.what()) ==
          dir.path.string() + ": cannot read the rig file: it is a directory");
  }
}

TEST_CASE("Rig file: the example in docs/rig-format.md parses", "[rig_file]") {
  const std::string doc = read_file(fs::path(DOORBENCH_SOURCE_DIR) / "docs" / "rig-format.md");
  const std::size_t begin = doc.find("```toml\n");
  REQUIRE(begin != std::string::npos);
  const std::size_t end = doc.find("```\n", begin + 8);
  REQUIRE(end != std::string::npos);
  const RigDefinition rig = parse(doc.substr(begin + 8, end - begin - 8));
  CHECK(rig.name == "lab-2-dishwasher");
  CHECK(rig.daq_backend == "comedi");
  REQUIRE(rig.channels.size() == 2);
  CHECK(rig.channels[0].range_min_V == 0.0);
  CHECK(rig.channels[1].backend == "modbus");
  CHECK(rig.triggers.at(0).source == "PFI0");
  CHECK_FALSE(rig.simulation.has_value());
}

// --- level and manual triggers, [recording] (docs/triggering.md) -------------------------
using doorbench::testing::kTriggerRig;

TEST_CASE("Rig file: level and manual triggers, the recording table, and their errors",
          "[rig_file]") {
  CHECK(error_of(edit(kTriggerRig, "channel = \"force\"\nlevel = 2.0",
                      "channel = \"forse\"\nlevel = 2.0")) ==
        "rig.toml:30: triggers[1].channel: \"forse\" is not a channel of the rig (they are force, "
        "rate)");
  CHECK(error_of(edit(kTriggerRig, "level = 2.0\n", "")) ==
        "rig.toml:27: triggers[1].level: missing required key (in the channel's unit, N)");
  CHECK(error_of(edit(kTriggerRig, "hysteresis = 0.5", "hysteresis = -0.5")) ==
        "rig.toml:32: triggers[1].hysteresis: must be >= 0 (got -0.5)");
  CHECK(error_of(edit(kTriggerRig, "hold_s = 1.5", "hold_s = -1")) ==
        "rig.toml:40: triggers[2].hold_s: must be from 0 to 3600 s (got -1)");
  CHECK(error_of(edit(kTriggerRig, "unit = \"N\"\n[[triggers]]", "unit = \"kN\"\n[[triggers]]")) ==
        "rig.toml:33: triggers[1].unit: \"kN\" is not the unit of channel force, which is \"N\"");
  CHECK(error_of(edit(kTriggerRig, "direction = \"falling\"", "direction = \"down\"")) ==
        "rig.toml:38: triggers[2].direction: \"down\" is not a direction; valid: rising, falling");
  CHECK(error_of(edit(kTriggerRig, "hysteresis = 0.05", "hysteresis = 0.2")) ==
        "rig.toml:46: triggers[3].hysteresis: must be below level 0.2 for an absolute rising "
        "level (got 0.2)");
  CHECK(error_of(edit(kTriggerRig, "kind = \"manual\"\n", "kind = \"manual\"\nlevel = 3\n")) ==
        "rig.toml:51: triggers[4].level: only level triggers have a level");
  CHECK(error_of(edit(kTriggerRig, "name = \"enter\"", "name = \"immediate\"")) ==
        "rig.toml:49: triggers[4].name: \"immediate\" is reserved (recording.start = "
        "\"immediate\")");
  CHECK(error_of(edit(kTriggerRig, "start = \"push\"", "start = \"pusch\"")) ==
        "rig.toml:52: recording.start: \"pusch\" is not the name of a [[triggers]] table (they "
        "are door_switch, push, release, moving, enter)");
  CHECK(error_of(edit(kTriggerRig, "start = \"push\"", "start = \"release\"")) ==
        "rig.toml:52: recording.start: \"release\" has hold_s (line 34), which only a stop "
        "trigger uses");
  CHECK(error_of(edit(kTriggerRig, "stop = \"release\"", "stop = \"push\"")) ==
        "rig.toml:53: recording.stop: \"push\" is also recording.start; a level stop needs a "
        "trigger of its own (e.g. the falling edge)");
  CHECK(error_of(edit(kTriggerRig, "stop = \"release\"", "stop = \"door_switch\"")) ==
        "rig.toml:53: recording.stop: \"door_switch\" is an external trigger; a stop must be a "
        "level or manual trigger");
  CHECK(error_of(edit(kTriggerRig, "duration_s = 30", "duration_s = 0")) ==
        "rig.toml:54: recording.duration_s: must be > 0 and <= 86400 s (got 0)");
  CHECK(error_of(edit(kTriggerRig, "duration_s = 30", "duration_s = 1e300")) ==
        "rig.toml:54: recording.duration_s: must be > 0 and <= 86400 s (got 1e+300)");
  CHECK(error_of(edit(kTriggerRig, "pre_trigger_s = 2", "pre_trigger_s = 61")) ==
        "rig.toml:55: recording.pre_trigger_s: must be from 0 to 60 s (got 61)");
  CHECK(error_of(edit(kTriggerRig, "strokes = \"moving\"", "strokes = \"enter\"")) ==
        "rig.toml:56: recording.strokes: \"enter\" is a manual trigger; stroke markers need a "
        "level trigger");
  CHECK(error_of(kTriggerRig + "min_stroke_s = -0.1\n") ==
        "rig.toml:57: recording.min_stroke_s: must be from 0 to 86400 s (got -0.1)");
  CHECK(error_of(kTriggerRig + "begin = \"push\"\n") ==
        "rig.toml:57: recording.begin: unknown key; valid keys: start, stop, duration_s, "
        "pre_trigger_s, strokes, min_stroke_s");
  // An external start must be the DAQ's start trigger too.
  CHECK(error_of(edit(edit(kTriggerRig, "start_trigger = \"door_switch\"\n", ""),
                      "start = \"push\"", "start = \"door_switch\"")) ==
        "rig.toml:51: recording.start: \"door_switch\" is an external trigger: it must also be "
        "daq.start_trigger, so that the DAQ starts on its line");
}

// ---------------------------------------------------------------------------------------
// Modbus devices and channels (docs/modbus.md)

namespace {

// A rig of Modbus channels only; line numbers in the expected messages refer to it.
constexpr std::string_view kModbusRig =
    "[bench]\n"                  // 1
    "name = \"mb\"\n"            // 2
    "[daq]\n"                    // 3
    "backend = \"none\"\n"       // 4
    "[[modbus.devices]]\n"       // 5
    "name = \"tx\"\n"            // 6
    "transport = \"tcp\"\n"      // 7
    "host = \"10.0.0.5\"\n"      // 8
    "[[channels]]\n"             // 9
    "name = \"force\"\n"         // 10
    "sensor = \"load_cell\"\n"   // 11
    "serial = \"LC-1\"\n"        // 12
    "backend = \"modbus\"\n"     // 13
    "unit = \"N\"\n"             // 14
    "[channels.modbus]\n"        // 15
    "device = \"tx\"\n"          // 16
    "unit_id = 3\n"              // 17
    "register = \"holding\"\n"   // 18
    "address = 100\n"            // 19
    "type = \"float32\"\n"       // 20
    "byte_order = \"big\"\n"     // 21
    "word_order = \"little\"\n"  // 22
    "range = [-700.0, 700.0]\n"  // 23
    "poll_rate_hz = 100\n";      // 24

std::string modbus_rig() {
  return std::string(kModbusRig);
}

}  // namespace

TEST_CASE("Rig file: a Modbus rig with its defaults", "[rig_file][modbus]") {
  const RigDefinition rig = parse(modbus_rig());
  CHECK(rig.daq_backend == "none");
  CHECK(rig.daq_device.empty());
  REQUIRE(rig.modbus_devices.size() == 1);
  const doorbench::RigModbusDevice& device = rig.modbus_devices[0];
  CHECK(device.name == "tx");
  CHECK(device.transport == "tcp");
  CHECK(device.host == "10.0.0.5");
  CHECK(device.port == 502);
  CHECK(device.response_timeout_s == 0.1);
  CHECK(device.reconnect_min_s == 0.1);
  CHECK(device.reconnect_max_s == 5.0);
  CHECK(device.line == 5);
  CHECK(rig.find_modbus_device("tx") == &device);
  CHECK(rig.find_modbus_device("rx") == nullptr);
  const doorbench::RigChannel& channel = rig.channels[0];
  CHECK(channel.calibration.empty());
  CHECK(channel.address == "tx/3/holding/100");
  REQUIRE(channel.modbus);
  CHECK(channel.modbus->device == "tx");
  CHECK(channel.modbus->unit_id == 3);
  CHECK(channel.modbus->kind == "holding");
  CHECK(channel.modbus->address == 100);
  CHECK(channel.modbus->type == "float32");
  CHECK(channel.modbus->byte_order == "big");
  CHECK(channel.modbus->word_order == "little");
  CHECK(channel.modbus->scale == 1.0);
  CHECK(channel.modbus->offset == 0.0);
  CHECK(channel.modbus->range_min == -700.0);
  CHECK(channel.modbus->range_max == 700.0);
  CHECK(channel.modbus->poll_rate_hz == 100.0);
  CHECK(channel.modbus->line == 15);
  // "none" says the same as leaving calibration out.
  CHECK(parse(edit(modbus_rig(), "unit = \"N\"\n", "unit = \"N\"\ncalibration = \"none\"\n"))
            .channels[0]
            .calibration.empty());
}

TEST_CASE("Rig file: an RTU device's serial settings", "[rig_file][modbus]") {
  const RigDefinition rig =
      parse(edit(modbus_rig(), "transport = \"tcp\"\nhost = \"10.0.0.5\"\n",
                 "transport = \"rtu\"\ndevice = \"/dev/ttyUSB0\"\nbaud = 9600\nparity = \"even\"\n"
                 "data_bits = 7\nstop_bits = 2\nresponse_timeout_s = 0.5\nreconnect_min_s = 1\n"
                 "reconnect_max_s = 30\n"));
  const doorbench::RigModbusDevice& device = rig.modbus_devices[0];
  CHECK(device.device == "/dev/ttyUSB0");
  CHECK(device.baud == 9600);
  CHECK(device.parity == "even");
  CHECK(device.data_bits == 7);
  CHECK(device.stop_bits == 2);
  CHECK(device.response_timeout_s == 0.5);
  CHECK(device.reconnect_min_s == 1.0);
  CHECK(device.reconnect_max_s == 30.0);
}

TEST_CASE("Rig file: Modbus device errors name file, line and key", "[rig_file][modbus]") {
  CHECK(error_of(edit(modbus_rig(), "host = ", "hots = ")) ==
        "rig.toml:8: modbus.devices[0].hots: unknown key; valid keys: name, transport, host, "
        "port, device, baud, parity, data_bits, stop_bits, response_timeout_s, reconnect_min_s, "
        "reconnect_max_s");
  CHECK(error_of(edit(modbus_rig(), "transport = \"tcp\"", "transport = \"udp\"")) ==
        "rig.toml:7: modbus.devices[0].transport: \"udp\" is not a transport; valid: tcp, rtu");
  CHECK(error_of(edit(modbus_rig(), "host = \"10.0.0.5\"\n", "")) ==
        "rig.toml:5: modbus.devices[0].host: missing required key");
  CHECK(error_of(edit(modbus_rig(), "host = \"10.0.0.5\"", "host = \"h\"\nport = 70000")) ==
        "rig.toml:9: modbus.devices[0].port: must be an integer from 1 to 65535 (got 70000)");
  CHECK(error_of(edit(modbus_rig(), "host = \"10.0.0.5\"", "host = \"h\"\nbaud = 9600")) ==
        "rig.toml:9: modbus.devices[0].baud: only rtu devices have a baud");
  CHECK(error_of(edit(modbus_rig(), "transport = \"tcp\"\nhost = \"10.0.0.5\"",
                      "transport = \"rtu\"\nhost = \"10.0.0.5\"")) ==
        "rig.toml:8: modbus.devices[0].host: only tcp devices have a host");
  CHECK(error_of(edit(modbus_rig(), "transport = \"tcp\"\nhost = \"10.0.0.5\"",
                      "transport = \"rtu\"\ndevice = \"/dev/ttyS0\"\nparity = \"mark\"")) ==
        "rig.toml:9: modbus.devices[0].parity: \"mark\" is not a parity; valid: none, even, odd");
  CHECK(
      error_of(edit(modbus_rig(), "host = \"10.0.0.5\"", "host = \"h\"\nresponse_timeout_s = 0")) ==
      "rig.toml:9: modbus.devices[0].response_timeout_s: must be > 0 (got 0)");
  CHECK(error_of(edit(modbus_rig(), "host = \"10.0.0.5\"",
                      "host = \"h\"\nreconnect_min_s = 2\nreconnect_max_s = 1")) ==
        "rig.toml:10: modbus.devices[0].reconnect_max_s: must be >= reconnect_min_s 2 (got 1)");
  CHECK(error_of(edit(modbus_rig(), "[[channels]]",
                      "[[modbus.devices]]\nname = \"tx\"\ntransport = \"tcp\"\nhost = \"b\"\n"
                      "[[channels]]")) ==
        "rig.toml:10: modbus.devices[1].name: \"tx\" is already the name of the device at line 5");
  CHECK(error_of(edit(modbus_rig(), "backend = \"none\"", "backend = \"none\"\ndevice = \"x\"")) ==
        "rig.toml:5: daq.device: a rig without a DAQ (backend \"none\") has no device");
}

TEST_CASE("Rig file: Modbus channel errors name file, line and key", "[rig_file][modbus]") {
  CHECK(error_of(edit(modbus_rig(), "[channels.modbus]\n", "")) !=
        "(parsed)");  // the keys would land in [[channels]] itself
  CHECK(error_of(edit(modbus_rig(), "unit = \"N\"\n", "unit = \"N\"\naddress = \"x\"\n")) ==
        "rig.toml:15: channels[0].address: modbus channels give it in [channels.modbus] (device, "
        "unit_id, register, address; range)");
  CHECK(error_of(edit(modbus_rig(), "device = \"tx\"", "device = \"rx\"")) ==
        "rig.toml:16: channels[0].modbus.device: \"rx\" is not the name of a [[modbus.devices]] "
        "table (they are tx)");
  CHECK(error_of(edit(modbus_rig(), "unit_id = 3", "unit_id = 300")) ==
        "rig.toml:17: channels[0].modbus.unit_id: must be an integer from 0 to 247 (got 300)");
  CHECK(error_of(edit(modbus_rig(), "register = \"holding\"", "register = \"coil\"")) ==
        "rig.toml:18: channels[0].modbus.register: \"coil\" is not a register kind; valid: "
        "holding, input");
  CHECK(error_of(edit(modbus_rig(), "address = 100\n", "")) ==
        "rig.toml:15: channels[0].modbus.address: missing required key");
  CHECK(error_of(edit(modbus_rig(), "address = 100", "address = 65535")) ==
        "rig.toml:19: channels[0].modbus.address: a 32-bit value needs two registers; 65535 is "
        "the last one");
  CHECK(error_of(edit(modbus_rig(), "type = \"float32\"", "type = \"float64\"")) ==
        "rig.toml:20: channels[0].modbus.type: \"float64\" is not a register type; valid: int16, "
        "uint16, int32, uint32, float32");
  CHECK(error_of(edit(modbus_rig(), "byte_order = \"big\"\n", "")) ==
        "rig.toml:15: channels[0].modbus.byte_order: missing required key");
  CHECK(error_of(edit(modbus_rig(), "word_order = \"little\"", "word_order = \"middle\"")) ==
        "rig.toml:22: channels[0].modbus.word_order: \"middle\" is not a word order; valid: big, "
        "little");
  CHECK(error_of(edit(modbus_rig(), "word_order = \"little\"\n", "")) ==
        "rig.toml:15: channels[0].modbus.word_order: missing required key");
  CHECK(error_of(edit(modbus_rig(), "type = \"float32\"", "type = \"int16\"")) ==
        "rig.toml:22: channels[0].modbus.word_order: only 32-bit types (int32, uint32, float32) "
        "have a word order");
  CHECK(error_of(edit(modbus_rig(), "range = [-700.0, 700.0]\n", "scale = 0\n")) ==
        "rig.toml:23: channels[0].modbus.scale: must not be 0");
  CHECK(error_of(edit(modbus_rig(), "range = [-700.0, 700.0]", "range = [1, -1]")) ==
        "rig.toml:23: channels[0].modbus.range: min 1 must be below max -1");
  CHECK(error_of(edit(modbus_rig(), "poll_rate_hz = 100", "poll_rate_hz = 0")) ==
        "rig.toml:24: channels[0].modbus.poll_rate_hz: must be > 0 (got 0)");
  CHECK(
      error_of(edit(modbus_rig(), "unit = \"N\"\n", "unit = \"N\"\ncalibration = \"nominal\"\n")) ==
      "rig.toml:15: channels[0].calibration: \"nominal\": modbus channels take no calibration "
      "record (scale and offset in [channels.modbus] give the physical value); write \"none\" "
      "or leave the key out");
  CHECK(error_of(edit(modbus_rig(), "backend = \"modbus\"", "backend = \"comedi\"")) ==
        "rig.toml:13: channels[0].backend: \"comedi\" does not match daq.backend \"none\" "
        "(simulated and comedi channels are sampled by the rig's DAQ)");
  CHECK(error_of(minimal() + "[channels.modbus]\ndevice = \"x\"\n") ==
        "rig.toml:14: channels[0].modbus: only modbus channels have a [channels.modbus]");
  // Two channels on the same register of the same unit.
  const std::string second(kModbusRig.substr(kModbusRig.find("[[channels]]")));
  CHECK(error_of(modbus_rig() + edit(second, "name = \"force\"", "name = \"force2\"")) ==
        "rig.toml:25: channels[1].address: \"tx/3/holding/100\" is already the address of "
        "channels[0] (line 9)");
}

TEST_CASE("Rig file: rigs/modbus-bench.toml parses", "[rig_file][modbus]") {
  const RigDefinition rig =
      read_rig_file(fs::path(DOORBENCH_SOURCE_DIR) / "rigs" / "modbus-bench.toml");
  CHECK(rig.name == "modbus-bench");
  CHECK(rig.daq_backend == "none");
  REQUIRE(rig.modbus_devices.size() == 1);
  CHECK(rig.modbus_devices[0].transport == "tcp");
  REQUIRE(rig.channels.size() == 3);
  for (const auto& channel : rig.channels) {
    INFO(channel.name);
    CHECK(channel.backend == "modbus");
    REQUIRE(channel.modbus);
    CHECK(channel.modbus->device == rig.modbus_devices[0].name);
  }
  CHECK(rig.channels[0].sensor == "load_cell");
  CHECK(rig.channels[1].sensor == "inclinometer");
  CHECK(rig.channels[2].sensor == "gyroscope");
}

TEST_CASE("Rig file: a session's stored rig text parses, or is no rig when empty or unreadable",
          "[rig_file]") {
  const std::optional<doorbench::RigDefinition> built_in = doorbench::parse_stored_rig(
      doorbench::simulated_dishwasher_rig_text(), "session.h5 (rig_definition)");
  REQUIRE(built_in.has_value());
  CHECK(built_in->find_channel("angle") != nullptr);
  CHECK_FALSE(doorbench::parse_stored_rig("", "session.h5 (rig_definition)").has_value());
  CHECK_FALSE(
      doorbench::parse_stored_rig("[rig\nname = ", "session.h5 (rig_definition)").has_value());
}
