// Rig definition files (TOML): parsing and every rule of docs/rig-format.md. The first
// broken rule ends the parse with a RigError `FILE:LINE: KEY: what is wrong`; tables and
// keys are checked in a fixed order (top level, bench, clock, daq, channels, triggers,
// simulation; within a table, unknown keys first, then each key in the documented order).
// This file holds parse_rig() and the bench, clock, DAQ and simulation tables; the channels
// are rig_channels.cpp, the triggers and recording rig_triggers.cpp, the TOML reading
// internal/rig_toml.h.
#include "acquisition/rig/rig_file.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <span>
#include <system_error>

#include "acquisition/rig/internal/rig_toml.h"

namespace doorbench {

using namespace rig_detail;

namespace {

namespace fs = std::filesystem;

constexpr std::string_view kDaqBackends[] = {"simulated", "comedi", "none"};
// Upper bounds on what a rig can ask for (docs/rig-format.md, "Limits"): beyond them a
// recording would exhaust memory or disk, or run for longer than anyone records a door.
constexpr double kMinSampleRateHz = 1.0;
constexpr double kMaxSampleRateHz = 200000.0;  // scans per second
constexpr std::string_view kDoorModels[] = {"sensory", "physical"};
constexpr int kMinResolutionBits = 8;
constexpr int kMaxResolutionBits = 24;

void read_bench(const Section& root, RigDefinition& rig, const Failer& failer) {
  const std::optional<Section> bench = root.table("bench");
  if (!bench) failer.fail(1, "bench", "missing required table [bench]");
  bench->allow_only({"name", "description"});
  rig.name = bench->required_string("name");
  rig.description = bench->string("description").value_or("");
}

void read_clock(const Section& root, RigDefinition& rig) {
  const std::optional<Section> clock = root.table("clock");
  if (!clock) return;
  clock->allow_only({"sample_rate_hz", "convert_interval_s"});
  rig.sample_rate_hz = clock->number("sample_rate_hz").value_or(rig.sample_rate_hz);
  if (!(rig.sample_rate_hz >= kMinSampleRateHz && rig.sample_rate_hz <= kMaxSampleRateHz)) {
    clock->fail("sample_rate_hz", "must be from " + format_readable(kMinSampleRateHz) + " to " +
                                      format_readable(kMaxSampleRateHz) + " Hz (got " +
                                      format_number(rig.sample_rate_hz) + ")");
  }
  rig.convert_interval_s = clock->number("convert_interval_s").value_or(rig.convert_interval_s);
  if (!(rig.convert_interval_s >= 0 && rig.convert_interval_s <= 1.0 / kMinSampleRateHz)) {
    clock->fail("convert_interval_s",
                "must be from 0 to 1 s (got " + format_number(rig.convert_interval_s) + ")");
  }
}

void read_daq(const Section& root, RigDefinition& rig, const Failer& failer) {
  const std::optional<Section> daq = root.table("daq");
  if (!daq) failer.fail(1, "daq", "missing required table [daq]");
  daq->allow_only({"backend", "device", "range_V", "resolution_bits", "start_trigger"});
  rig.daq_backend = daq->choice("backend", kDaqBackends, "a DAQ backend", rig.daq_backend);
  // A rig whose channels are all Modbus has no DAQ: backend "none", no device.
  if (rig.daq_backend == "none") {
    if (daq->find("device"))
      daq->fail("device", "a rig without a DAQ (backend \"none\") has no device");
  } else {
    rig.daq_device = daq->required_string("device");
  }
  if (const auto range = daq->range("range_V")) {
    rig.daq_range_min_V = range->first;
    rig.daq_range_max_V = range->second;
  }
  if (const auto bits = daq->integer("resolution_bits")) {
    if (*bits < kMinResolutionBits || *bits > kMaxResolutionBits) {
      daq->fail("resolution_bits", "must be an integer from " + std::to_string(kMinResolutionBits) +
                                       " to " + std::to_string(kMaxResolutionBits) + " (got " +
                                       std::to_string(*bits) + ")");
    }
    rig.daq_resolution_bits = static_cast<int>(*bits);
  }
  // Checked against the triggers once they are read (check_start_trigger).
  rig.daq_start_trigger = daq->string("start_trigger").value_or("");
}

// A file named in [simulation] must exist (relative paths resolve against the rig's folder).
void check_file_exists(const Section& simulation, const RigDefinition& rig, std::string_view key,
                       const std::string& path) {
  const fs::path resolved = rig.resolve(path);
  std::error_code error;
  const fs::file_status status = fs::status(resolved, error);
  if (!fs::exists(status)) {
    simulation.fail(
        key, in_quotes(path) + " resolves to " + resolved.string() + ", which does not exist");
  }
  if (!fs::is_regular_file(status)) {
    simulation.fail(
        key, in_quotes(path) + " resolves to " + resolved.string() + ", which is not a file");
  }
}

void read_simulation(const Section& root, RigDefinition& rig, const ParsedChannels& parsed,
                     const Failer& failer) {
  std::optional<std::size_t> simulated;
  for (std::size_t i = 0; i < rig.channels.size() && !simulated; ++i) {
    if (rig.channels[i].backend == "simulated") simulated = i;
  }
  const std::optional<Section> table = root.table("simulation");
  if (!table) {
    if (simulated) {
      failer.fail(parsed.backend_lines[*simulated], "simulation",
                  "missing table [simulation], required because channels[" +
                      std::to_string(*simulated) + "].backend is \"simulated\"");
    }
    return;
  }
  if (!simulated) {
    failer.fail(table->line(), "simulation",
                "only for rigs with simulated channels (no channel's backend is \"simulated\")");
  }

  table->allow_only({"door", "model", "effects", "force", "seed", "realtime", "hand"});
  RigSimulation simulation;
  simulation.line = table->line();
  simulation.door = table->string("door").value_or(simulation.door);
  if (simulation.door != "reference") check_file_exists(*table, rig, "door", simulation.door);
  simulation.model = table->choice("model", kDoorModels, "a door model", simulation.model);
  if (const auto effects = table->string("effects")) {
    check_file_exists(*table, rig, "effects", *effects);
    simulation.effects = *effects;
  }
  if (const auto force = table->string("force")) {
    check_file_exists(*table, rig, "force", *force);
    if (table->table("hand")) {
      table->fail("force", "a scripted force replaces the virtual hand: remove [simulation.hand]");
    }
    simulation.force = *force;
  }
  if (const auto seed = table->integer("seed")) {
    if (*seed < 0) table->fail("seed", "must be >= 0 (got " + std::to_string(*seed) + ")");
    simulation.seed = static_cast<std::uint64_t>(*seed);
  }
  simulation.realtime = table->boolean("realtime").value_or(simulation.realtime);

  if (const std::optional<Section> hand = table->table("hand")) {
    hand->allow_only({"cycles", "target_deg", "cycle_duration_s"});
    if (const auto cycles = hand->integer("cycles")) {
      if (*cycles < 1) hand->fail("cycles", "must be >= 1 (got " + std::to_string(*cycles) + ")");
      if (*cycles > INT_MAX) {
        hand->fail("cycles", "must be <= " + std::to_string(INT_MAX) + " (got " +
                                 std::to_string(*cycles) + ")");
      }
      simulation.hand_cycles = static_cast<int>(*cycles);
    }
    simulation.hand_target_deg = hand->number("target_deg").value_or(simulation.hand_target_deg);
    if (!(simulation.hand_target_deg > 0 && simulation.hand_target_deg < 180)) {
      hand->fail("target_deg",
                 "must be > 0 and < 180 (got " + format_number(simulation.hand_target_deg) + ")");
    }
    simulation.hand_cycle_duration_s =
        hand->number("cycle_duration_s").value_or(simulation.hand_cycle_duration_s);
    if (!(simulation.hand_cycle_duration_s > 0)) {
      hand->fail("cycle_duration_s",
                 "must be > 0 (got " + format_number(simulation.hand_cycle_duration_s) + ")");
    }
    const double total_s = simulation.hand_cycles * simulation.hand_cycle_duration_s;
    if (!(total_s <= kMaxRecordingS)) {
      hand->fail(hand->find("cycle_duration_s") ? "cycle_duration_s" : "cycles",
                 "cycles * cycle_duration_s = " + std::to_string(simulation.hand_cycles) + " * " +
                     format_number(simulation.hand_cycle_duration_s) +
                     " s = " + format_number(total_s) +
                     " s must be <= " + format_readable(kMaxRecordingS) + " s (a day)");
    }
  }
  rig.simulation = std::move(simulation);
}

}  // namespace

const RigModbusDevice* RigDefinition::find_modbus_device(std::string_view device_name) const {
  for (const RigModbusDevice& device : modbus_devices) {
    if (device.name == device_name) return &device;
  }
  return nullptr;
}

const RigChannel* RigDefinition::find_channel(std::string_view channel_name) const {
  for (const RigChannel& channel : channels) {
    if (channel.name == channel_name) return &channel;
  }
  return nullptr;
}

std::filesystem::path RigDefinition::resolve(const std::string& path) const {
  const fs::path written(path);
  if (written.is_absolute() || base_dir.empty()) return written;
  return base_dir / written;
}

namespace {

std::string trimmed(std::string_view text) {
  const auto begin = text.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return "";
  const auto end = text.find_last_not_of(" \t\r");
  return std::string(text.substr(begin, end - begin + 1));
}

// toml++ refuses a key or table given twice naming only the second ("cannot redefine
// existing string 'name'"): the line of the first, found in the text (the table header
// `[name]`, or `name =` under the same header), or 0.
int first_definition_line(std::string_view text, int second_line, std::string_view description) {
  const auto close = description.rfind('\'');
  const auto open = close == std::string_view::npos ? close : description.rfind('\'', close - 1);
  if (open == std::string_view::npos ||
      description.find("cannot redefine existing") == std::string_view::npos) {
    return 0;
  }
  const std::string name(description.substr(open + 1, close - open - 1));
  const bool table = description.find("existing table") != std::string_view::npos;
  std::vector<std::string> lines;
  for (std::size_t start = 0; start <= text.size();) {
    const auto end = std::min(text.find('\n', start), text.size());
    lines.push_back(trimmed(text.substr(start, end - start)));
    start = end + 1;
  }
  const int last = std::min<int>(second_line - 1, static_cast<int>(lines.size()));
  int from = 1;  // a key: under the header that holds the second one
  if (!table) {
    for (int n = last; n >= 1; --n) {
      if (lines[n - 1].starts_with("[")) {
        from = n + 1;
        break;
      }
    }
  }
  const std::string key = name.substr(name.rfind('.') + 1);
  for (int n = from; n <= last; ++n) {
    const std::string& line = lines[n - 1];
    if (table && (line == "[" + name + "]" || line == "[[" + name + "]]")) return n;
    if (!table && (line.starts_with(key) || line.starts_with("\"" + key + "\""))) {
      const std::size_t after = line.starts_with(key) ? key.size() : key.size() + 2;
      const std::string rest = trimmed(std::string_view(line).substr(after));
      if (rest.starts_with("=")) return n;
    }
  }
  return 0;
}

}  // namespace

RigDefinition parse_rig(std::string_view text, std::string_view source,
                        const std::filesystem::path& base_dir) {
  const Failer failer(source);
  toml::table root_table;
  try {
    root_table = toml::parse(text, source);
  } catch (const toml::parse_error& error) {
    std::string what(error.description());
    const int line = line_of(error.source());
    if (const int first = first_definition_line(text, line, what); first > 0) {
      what += " (given twice: lines " + std::to_string(first) + " and " + std::to_string(line) +
              "; a file says each thing once)";
    }
    failer.fail(line, "syntax", what);
  }

  RigDefinition rig;
  rig.source = std::string(source);
  rig.text = std::string(text);
  rig.base_dir = base_dir;

  const Section root(failer, root_table, "", 1);
  root.allow_only(
      {"bench", "clock", "daq", "modbus", "channels", "triggers", "recording", "simulation"});
  read_bench(root, rig, failer);
  read_clock(root, rig);
  read_daq(root, rig, failer);
  read_modbus_devices(root, rig);
  const ParsedChannels parsed = read_channels(root, rig, failer);
  rig.channels = parsed.channels;
  check_scan_fits(root, rig, failer);
  rig.triggers = read_triggers(root, rig);
  check_start_trigger(root, rig);
  read_recording(root, rig);
  read_simulation(root, rig, parsed, failer);
  return rig;
}

std::optional<RigDefinition> parse_stored_rig(std::string_view text, std::string_view source) {
  if (text.empty()) return std::nullopt;
  try {
    return parse_rig(text, source, {});
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

RigDefinition read_rig_file(const std::filesystem::path& path) {
  std::error_code error;
  if (fs::is_directory(path, error)) {
    throw RigError(path.string() + ": cannot read the rig file: it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw RigError(path.string() +
                   ": cannot read the rig file: " + std::generic_category().message(errno));
  }
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) {
    throw RigError(path.string() +
                   ": cannot read the rig file: " + std::generic_category().message(errno));
  }
  return parse_rig(text, path.string(), path.parent_path());
}

}  // namespace doorbench
