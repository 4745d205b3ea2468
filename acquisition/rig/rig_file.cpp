// Rig definition files (TOML): parsing and every rule of docs/rig-format.md. The first
// broken rule ends the parse with a RigError `FILE:LINE: KEY: what is wrong`; tables and
// keys are checked in a fixed order (top level, bench, clock, daq, channels, triggers,
// simulation; within a table, unknown keys first, then each key in the documented order).
#include "acquisition/rig/rig_file.h"

#include <toml++/toml.h>

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

#include "acquisition/rig/sensor_parameters.h"

namespace doorbench {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kSensorKinds[] = {"load_cell", "inclinometer", "gyroscope"};
constexpr std::string_view kChannelBackends[] = {"simulated", "comedi", "modbus"};
constexpr std::string_view kDaqBackends[] = {"simulated", "comedi", "none"};
constexpr std::string_view kModbusTransports[] = {"tcp", "rtu"};
constexpr std::string_view kModbusParities[] = {"none", "even", "odd"};
constexpr std::string_view kModbusRegisterKinds[] = {"holding", "input"};
constexpr std::string_view kModbusTypes[] = {"int16", "uint16", "int32", "uint32", "float32"};
constexpr std::string_view kModbusOrders[] = {"big", "little"};
constexpr std::string_view kTriggerKinds[] = {"software", "external", "level", "manual"};
constexpr std::string_view kDirections[] = {"rising", "falling"};
constexpr double kMaxPreTriggerS = 60.0;  // TriggerOptions::kMaxPreTriggerS
// Upper bounds on what a rig can ask for (docs/rig-format.md, "Limits"): beyond them a
// recording would exhaust memory or disk, or run for longer than anyone records a door.
constexpr double kMinSampleRateHz = 1.0;
constexpr double kMaxSampleRateHz = 200000.0;  // scans per second
constexpr double kMaxRecordingS = 86400.0;     // a day, as `record --duration-s`
constexpr double kMaxHoldS = 3600.0;
// A bound as written in the docs: 200000, not 2e+05.
std::string whole_number_text(double value) { return std::to_string(static_cast<long long>(value)); }
constexpr std::string_view kArefs[] = {"ground", "common", "diff", "other"};
constexpr std::string_view kDoorModels[] = {"sensory", "physical"};
constexpr int kMinResolutionBits = 8;
constexpr int kMaxResolutionBits = 24;

// Shortest text that reads back as the same double.
std::string number_text(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string in_quotes(std::string_view text) {
  return "\"" + std::string(text) + "\"";
}

std::string joined(std::span<const std::string_view> items) {
  std::string text;
  for (std::string_view item : items) {
    if (!text.empty()) text += ", ";
    text += item;
  }
  return text;
}

bool one_of(std::string_view value, std::span<const std::string_view> allowed) {
  return std::find(allowed.begin(), allowed.end(), value) != allowed.end();
}

int line_of(const toml::source_region& region) {
  return region.begin.line > 0 ? static_cast<int>(region.begin.line) : 1;
}
int line_of(const toml::node& node) {
  return line_of(node.source());
}

bool before(const toml::source_position& a, const toml::source_position& b) {
  return a.line != b.line ? a.line < b.line : a.column < b.column;
}

std::string type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    default:
      return "nothing";
  }
}

bool is_name(std::string_view name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// The unit a sensor kind's readings have after calibration.
std::string_view unit_of(std::string_view sensor) {
  if (sensor == "load_cell") return "N";
  if (sensor == "inclinometer") return "rad";
  return "rad/s";
}

class Failer {
 public:
  explicit Failer(std::string_view source) : source_(source) {}
  [[noreturn]] void fail(int line, std::string_view key, std::string_view what) const {
    throw RigError(source_ + ":" + std::to_string(line) + ": " + std::string(key) + ": " +
                   std::string(what));
  }

 private:
  std::string source_;
};

// One TOML table of the rig with its dotted path (for messages) and its line.
class Section {
 public:
  Section(const Failer& failer, const toml::table& table, std::string path, int line)
      : failer_(&failer), table_(&table), path_(std::move(path)), line_(line) {}

  const std::string& path() const { return path_; }
  int line() const { return line_; }
  std::string key_path(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  }
  const toml::node* find(std::string_view key) const { return table_->get(key); }
  // The line of `key`'s value, or the table's line when the key is absent.
  int line_of_key(std::string_view key) const {
    const toml::node* node = find(key);
    return node ? line_of(*node) : line_;
  }
  [[noreturn]] void fail(std::string_view key, std::string_view what) const {
    failer_->fail(line_of_key(key), key_path(key), what);
  }
  // At the table itself: its path and line.
  [[noreturn]] void fail_here(std::string_view what) const { failer_->fail(line_, path_, what); }
  [[noreturn]] void fail_at(const toml::node& node, std::string_view key,
                            std::string_view what) const {
    failer_->fail(line_of(node), key_path(key), what);
  }

  // The table's keys in file order.
  std::vector<std::pair<const toml::key*, const toml::node*>> entries() const {
    std::vector<std::pair<const toml::key*, const toml::node*>> result;
    for (auto&& [key, node] : *table_) result.emplace_back(&key, &node);
    std::stable_sort(result.begin(), result.end(), [](const auto& a, const auto& b) {
      return before(a.first->source().begin, b.first->source().begin);
    });
    return result;
  }

  // Rejects the first key (in file order) that is not in `allowed`.
  void allow_only(std::span<const std::string_view> allowed) const {
    for (const auto& [key, node] : entries()) {
      if (!one_of(key->str(), allowed)) {
        failer_->fail(line_of(key->source()), key_path(key->str()),
                      "unknown key; valid keys: " + joined(allowed));
      }
    }
  }
  void allow_only(std::initializer_list<std::string_view> allowed) const {
    allow_only(std::span<const std::string_view>(allowed.begin(), allowed.size()));
  }

  std::optional<std::string> string(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    if (!node->is_string()) fail(key, "must be a string, not " + type_name(*node));
    std::string value = node->as_string()->get();
    if (value.empty()) fail(key, "must not be empty");
    return value;
  }
  std::string required_string(std::string_view key) const {
    std::optional<std::string> value = string(key);
    if (!value) fail(key, "missing required key");
    return *value;
  }
  // A string that must be one of `allowed`; `what` names the kind of value.
  std::string choice(std::string_view key, std::span<const std::string_view> allowed,
                     std::string_view what, std::optional<std::string_view> fallback) const {
    std::optional<std::string> value = string(key);
    if (!value) {
      if (!fallback) fail(key, "missing required key");
      return std::string(*fallback);
    }
    if (!one_of(*value, allowed)) {
      fail(key, in_quotes(*value) + " is not " + std::string(what) + "; valid: " + joined(allowed));
    }
    return *value;
  }

  std::optional<double> number(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    return number_value(*node, key);
  }
  double number_value(const toml::node& node, std::string_view key) const {
    double value = 0;
    if (node.is_integer()) {
      value = static_cast<double>(node.as_integer()->get());
    } else if (node.is_floating_point()) {
      value = node.as_floating_point()->get();
    } else {
      fail_at(node, key, "must be a number, not " + type_name(node));
    }
    if (!std::isfinite(value)) {
      fail_at(node, key, "must be a finite number (got " + number_text(value) + ")");
    }
    return value;
  }

  std::optional<std::int64_t> integer(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    if (!node->is_integer()) fail(key, "must be an integer, not " + type_name(*node));
    return node->as_integer()->get();
  }

  std::optional<bool> boolean(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    if (!node->is_boolean()) fail(key, "must be true or false, not " + type_name(*node));
    return node->as_boolean()->get();
  }

  // `key = [min, max]` in volts, min < max.
  std::optional<std::pair<double, double>> range(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    const toml::array* array = node->as_array();
    if (!array || array->size() != 2 || !(*array)[0].is_number() || !(*array)[1].is_number()) {
      fail(key, "must be [min, max], two numbers in volts");
    }
    const double min = number_value((*array)[0], key);
    const double max = number_value((*array)[1], key);
    if (!(min < max)) {
      fail(key, "min " + number_text(min) + " V must be below max " + number_text(max) + " V");
    }
    return std::pair{min, max};
  }

  std::optional<Section> table(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    if (!node->is_table()) fail(key, "must be a table, not " + type_name(*node));
    return Section(*failer_, *node->as_table(), key_path(key), line_of(*node));
  }

  // `[[key]]`: the array's tables (empty when the key is absent).
  std::vector<Section> array_of_tables(std::string_view key) const {
    std::vector<Section> result;
    const toml::node* node = find(key);
    if (!node) return result;
    const toml::array* array = node->as_array();
    if (!array) {
      fail(key,
           "must be an array of tables ([[" + std::string(key) + "]]), not " + type_name(*node));
    }
    for (std::size_t i = 0; i < array->size(); ++i) {
      const std::string element_path = key_path(key) + "[" + std::to_string(i) + "]";
      const toml::node& element = (*array)[i];
      if (!element.is_table()) {
        failer_->fail(line_of(element), element_path, "must be a table, not " + type_name(element));
      }
      result.emplace_back(*failer_, *element.as_table(), element_path, line_of(element));
    }
    return result;
  }

 private:
  const Failer* failer_;
  const toml::table* table_;
  std::string path_;
  int line_;
};

// The field of `fields` that `message` names first, as a whole word ("" if none).
std::string_view field_named_in(std::string_view message,
                                std::span<const sensors::ParameterField> fields) {
  auto word_char = [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  };
  std::string_view best;
  std::size_t best_position = std::string_view::npos;
  for (const sensors::ParameterField& field : fields) {
    for (std::size_t at = message.find(field.name); at != std::string_view::npos;
         at = message.find(field.name, at + 1)) {
      const std::size_t end = at + field.name.size();
      const bool whole = (at == 0 || !word_char(message[at - 1])) &&
                         (end == message.size() || !word_char(message[end]));
      if (whole) {
        if (at < best_position) {
          best_position = at;
          best = field.name;
        }
        break;
      }
    }
  }
  return best;
}

// Fills a sensor's *Parameters from `[channels.parameters]` and validates it.
template <class Parameters>
void read_parameters(const Section& channel, std::string_view sensor, RigChannel& out) {
  Parameters parameters;
  std::vector<std::string_view> valid;
  for (const sensors::ParameterField& field : Parameters::fields()) valid.push_back(field.name);

  const std::optional<Section> table = channel.table("parameters");
  if (table) {
    for (const auto& [key, node] : table->entries()) {
      const std::string name(key->str());
      if (!one_of(name, valid)) {
        table->fail_at(*node, name,
                       "not a parameter of " + std::string(sensor) + "; valid: " + joined(valid));
      }
      const double value = table->number_value(*node, name);
      parameters.set(name, value);
      out.parameters.emplace_back(name, value);
    }
  }
  const std::string message = parameters.validate();
  if (message.empty()) return;
  const std::string_view field = field_named_in(message, Parameters::fields());
  if (table && !field.empty() && table->find(field)) table->fail(field, message);
  if (table) table->fail_here(message);
  channel.fail("parameters", message);
}

struct ParsedChannels {
  std::vector<RigChannel> channels;
  std::vector<int> backend_lines;  // per channel: the line of its backend key
};

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
    clock->fail("sample_rate_hz", "must be from " + whole_number_text(kMinSampleRateHz) + " to " +
                                      whole_number_text(kMaxSampleRateHz) + " Hz (got " +
                                      number_text(rig.sample_rate_hz) + ")");
  }
  rig.convert_interval_s = clock->number("convert_interval_s").value_or(rig.convert_interval_s);
  if (!(rig.convert_interval_s >= 0 && rig.convert_interval_s <= 1.0 / kMinSampleRateHz)) {
    clock->fail("convert_interval_s",
                "must be from 0 to 1 s (got " + number_text(rig.convert_interval_s) + ")");
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

// An integer key within [min, max], or `fallback` when absent.
int bounded_integer(const Section& table, std::string_view key, std::int64_t min, std::int64_t max,
                    int fallback) {
  const std::optional<std::int64_t> value = table.integer(key);
  if (!value) return fallback;
  if (*value < min || *value > max) {
    table.fail(key, "must be an integer from " + std::to_string(min) + " to " +
                        std::to_string(max) + " (got " + std::to_string(*value) + ")");
  }
  return static_cast<int>(*value);
}

double positive_number(const Section& table, std::string_view key, double fallback) {
  const double value = table.number(key).value_or(fallback);
  if (!(value > 0)) table.fail(key, "must be > 0 (got " + number_text(value) + ")");
  return value;
}

void read_modbus_devices(const Section& root, RigDefinition& rig) {
  const std::optional<Section> modbus = root.table("modbus");
  if (!modbus) return;
  modbus->allow_only({"devices"});
  for (const Section& table : modbus->array_of_tables("devices")) {
    table.allow_only({"name", "transport", "host", "port", "device", "baud", "parity", "data_bits",
                      "stop_bits", "response_timeout_s", "reconnect_min_s", "reconnect_max_s"});
    RigModbusDevice device;
    device.line = table.line();
    device.name = table.required_string("name");
    if (!is_name(device.name)) {
      table.fail("name", in_quotes(device.name) + " must consist of letters, digits and _ only");
    }
    for (const RigModbusDevice& other : rig.modbus_devices) {
      if (other.name == device.name) {
        table.fail("name", in_quotes(device.name) + " is already the name of the device at line " +
                               std::to_string(other.line));
      }
    }
    device.transport = table.choice("transport", kModbusTransports, "a transport", std::nullopt);
    const bool tcp = device.transport == "tcp";
    for (std::string_view key : {"host", "port"}) {
      if (!tcp && table.find(key)) table.fail(key, "only tcp devices have a " + std::string(key));
    }
    for (std::string_view key : {"device", "baud", "parity", "data_bits", "stop_bits"}) {
      if (tcp && table.find(key)) table.fail(key, "only rtu devices have a " + std::string(key));
    }
    if (tcp) {
      device.host = table.required_string("host");
      device.port = bounded_integer(table, "port", 1, 65535, device.port);
    } else {
      device.device = table.required_string("device");
      device.baud = bounded_integer(table, "baud", 50, 4000000, device.baud);
      device.parity = table.choice("parity", kModbusParities, "a parity", device.parity);
      device.data_bits = bounded_integer(table, "data_bits", 5, 8, device.data_bits);
      device.stop_bits = bounded_integer(table, "stop_bits", 1, 2, device.stop_bits);
    }
    device.response_timeout_s =
        positive_number(table, "response_timeout_s", device.response_timeout_s);
    device.reconnect_min_s = positive_number(table, "reconnect_min_s", device.reconnect_min_s);
    device.reconnect_max_s = positive_number(table, "reconnect_max_s", device.reconnect_max_s);
    if (device.reconnect_max_s < device.reconnect_min_s) {
      table.fail("reconnect_max_s", "must be >= reconnect_min_s " +
                                        number_text(device.reconnect_min_s) + " (got " +
                                        number_text(device.reconnect_max_s) + ")");
    }
    rig.modbus_devices.push_back(std::move(device));
  }
}

// `[channels.modbus]` of a modbus channel.
RigModbusChannel read_modbus_channel(const Section& channel, const RigDefinition& rig) {
  const std::optional<Section> table = channel.table("modbus");
  if (!table) channel.fail("modbus", "missing required table [channels.modbus] (modbus channels)");
  table->allow_only({"device", "unit_id", "register", "address", "type", "byte_order", "word_order",
                     "scale", "offset", "range", "poll_rate_hz"});
  RigModbusChannel modbus;
  modbus.line = table->line();
  modbus.device = table->required_string("device");
  if (!rig.find_modbus_device(modbus.device)) {
    std::string names;
    for (const RigModbusDevice& device : rig.modbus_devices) {
      names.append(names.empty() ? "" : ", ").append(device.name);
    }
    table->fail("device", in_quotes(modbus.device) + " is not the name of a [[modbus.devices]] " +
                              "table (" + (names.empty() ? "there are none" : "they are " + names) +
                              ")");
  }
  modbus.unit_id = bounded_integer(*table, "unit_id", 0, 247, modbus.unit_id);
  modbus.kind = table->choice("register", kModbusRegisterKinds, "a register kind", std::nullopt);
  if (!table->find("address")) table->fail("address", "missing required key");
  modbus.address = bounded_integer(*table, "address", 0, 65535, 0);
  modbus.type = table->choice("type", kModbusTypes, "a register type", std::nullopt);
  const bool wide = modbus.type != "int16" && modbus.type != "uint16";
  if (wide && modbus.address > 65534) {
    table->fail("address", "a 32-bit value needs two registers; 65535 is the last one");
  }
  modbus.byte_order = table->choice("byte_order", kModbusOrders, "a byte order", std::nullopt);
  if (wide) {
    modbus.word_order = table->choice("word_order", kModbusOrders, "a word order", std::nullopt);
  } else if (table->find("word_order")) {
    table->fail("word_order", "only 32-bit types (int32, uint32, float32) have a word order");
  }
  modbus.scale = table->number("scale").value_or(modbus.scale);
  if (modbus.scale == 0) table->fail("scale", "must not be 0");
  modbus.offset = table->number("offset").value_or(modbus.offset);
  const toml::node* range = table->find("range");
  if (!range) table->fail("range", "missing required key ([min, max] in the channel's unit)");
  const toml::array* array = range->as_array();
  if (!array || array->size() != 2 || !(*array)[0].is_number() || !(*array)[1].is_number()) {
    table->fail("range", "must be [min, max], two numbers in the channel's unit");
  }
  modbus.range_min = table->number_value((*array)[0], "range");
  modbus.range_max = table->number_value((*array)[1], "range");
  if (!(modbus.range_min < modbus.range_max)) {
    table->fail("range", "min " + number_text(modbus.range_min) + " must be below max " +
                             number_text(modbus.range_max));
  }
  if (!table->find("poll_rate_hz")) table->fail("poll_rate_hz", "missing required key");
  modbus.poll_rate_hz = positive_number(*table, "poll_rate_hz", 0);
  if (modbus.poll_rate_hz > 10000) {
    table->fail("poll_rate_hz", "must be <= 10000 (got " + number_text(modbus.poll_rate_hz) + ")");
  }
  return modbus;
}

ParsedChannels read_channels(const Section& root, const RigDefinition& rig, const Failer& failer) {
  const std::vector<Section> tables = root.array_of_tables("channels");
  if (tables.empty()) {
    failer.fail(root.line_of_key("channels"), "channels",
                "at least one [[channels]] table is required");
  }
  ParsedChannels parsed;
  for (const Section& table : tables) {
    table.allow_only({"name", "sensor", "serial", "backend", "address", "range_V", "aref",
                      "calibration", "unit", "parameters", "modbus"});
    RigChannel channel;
    channel.line = table.line();

    channel.name = table.required_string("name");
    if (!is_name(channel.name)) {
      table.fail("name", in_quotes(channel.name) + " must consist of letters, digits and _ only");
    }
    for (std::size_t j = 0; j < parsed.channels.size(); ++j) {
      if (parsed.channels[j].name == channel.name) {
        table.fail("name", in_quotes(channel.name) + " is already the name of channels[" +
                               std::to_string(j) + "] (line " +
                               std::to_string(parsed.channels[j].line) + ")");
      }
    }

    channel.sensor = table.choice("sensor", kSensorKinds, "a sensor kind", std::nullopt);
    channel.serial = table.required_string("serial");

    channel.backend = table.choice("backend", kChannelBackends, "a backend", std::nullopt);
    if (channel.backend != "modbus" && channel.backend != rig.daq_backend) {
      table.fail("backend", in_quotes(channel.backend) + " does not match daq.backend " +
                                in_quotes(rig.daq_backend) +
                                " (simulated and comedi channels are sampled by the rig's DAQ)");
    }

    const bool modbus = channel.backend == "modbus";
    if (modbus) {
      // Where a Modbus value is takes several keys: [channels.modbus] holds them.
      for (std::string_view key : {"address", "range_V"}) {
        if (table.find(key)) {
          table.fail(key,
                     "modbus channels give it in [channels.modbus] (device, unit_id, "
                     "register, address; range)");
        }
      }
      channel.modbus = read_modbus_channel(table, rig);
      channel.address = channel.modbus->device + "/" + std::to_string(channel.modbus->unit_id) +
                        "/" + channel.modbus->kind + "/" + std::to_string(channel.modbus->address);
    } else {
      if (table.find("modbus"))
        table.fail("modbus", "only modbus channels have a [channels.modbus]");
      channel.address = table.required_string("address");
    }
    for (std::size_t j = 0; j < parsed.channels.size(); ++j) {
      const RigChannel& other = parsed.channels[j];
      if (other.backend == channel.backend && other.address == channel.address) {
        table.fail("address", in_quotes(channel.address) + " is already the address of channels[" +
                                  std::to_string(j) + "] (line " + std::to_string(other.line) +
                                  ")");
      }
    }

    channel.range_min_V = rig.daq_range_min_V;
    channel.range_max_V = rig.daq_range_max_V;
    if (const auto range = modbus ? std::nullopt : table.range("range_V")) {
      if (range->first < rig.daq_range_min_V || range->second > rig.daq_range_max_V) {
        table.fail("range_V", "[" + number_text(range->first) + ", " + number_text(range->second) +
                                  "] V must lie inside the DAQ's range [" +
                                  number_text(rig.daq_range_min_V) + ", " +
                                  number_text(rig.daq_range_max_V) + "] V (daq.range_V)");
      }
      channel.range_min_V = range->first;
      channel.range_max_V = range->second;
    }

    if (channel.backend == "comedi") {
      channel.aref = table.choice("aref", kArefs, "an aref", "ground");
    } else if (table.find("aref")) {
      table.fail("aref", "only comedi channels have an aref");
    }

    if (modbus) {
      // A transmitter reports a physical value already; scale and offset make the
      // channel's unit of it, so no calibration record applies.
      const std::optional<std::string> calibration = table.string("calibration");
      if (calibration && *calibration != "none") {
        table.fail("calibration", in_quotes(*calibration) +
                                      ": modbus channels take no calibration record (scale and "
                                      "offset in [channels.modbus] give the physical value); "
                                      "write \"none\" or leave the key out");
      }
    } else {
      channel.calibration = table.required_string("calibration");
    }

    channel.unit = table.required_string("unit");
    if (channel.unit != unit_of(channel.sensor)) {
      table.fail("unit", in_quotes(channel.unit) + " does not fit sensor " + channel.sensor +
                             ", whose unit is " + in_quotes(unit_of(channel.sensor)));
    }

    if (channel.sensor == "load_cell") {
      read_parameters<sensors::LoadCellParameters>(table, channel.sensor, channel);
    } else if (channel.sensor == "inclinometer") {
      read_parameters<sensors::InclinometerParameters>(table, channel.sensor, channel);
    } else {
      read_parameters<sensors::GyroscopeParameters>(table, channel.sensor, channel);
    }

    parsed.backend_lines.push_back(table.line_of_key("backend"));
    parsed.channels.push_back(std::move(channel));
  }
  return parsed;
}

// The multiplexed converter must finish a scan within one sample period; then the DAQ
// model's own validation, as a last guard.
void check_scan_fits(const Section& root, const RigDefinition& rig, const Failer& failer) {
  const std::optional<Section> clock = root.table("clock");
  // Only the DAQ's channels are in its scan; Modbus channels are polled on their own.
  const auto daq_channels = static_cast<std::size_t>(
      std::count_if(rig.channels.begin(), rig.channels.end(),
                    [](const RigChannel& channel) { return channel.backend != "modbus"; }));
  if (daq_channels == 0) return;
  const double channels = static_cast<double>(daq_channels);
  const double scan_s = (channels - 1) * rig.convert_interval_s;
  const double period_s = 1.0 / rig.sample_rate_hz;
  if (!(scan_s < period_s)) {
    const int line = clock ? clock->line_of_key("convert_interval_s") : rig.channels.back().line;
    failer.fail(
        line, "clock.convert_interval_s",
        "(channels - 1) * convert_interval_s = (" + std::to_string(daq_channels) + " - 1) * " +
            number_text(rig.convert_interval_s) + " s = " + number_text(scan_s) +
            " s must be less than the sample period 1 / sample_rate_hz = " + number_text(period_s) +
            " s");
  }

  sensors::DaqParameters daq;
  daq.range_min_V = rig.daq_range_min_V;
  daq.range_max_V = rig.daq_range_max_V;
  daq.resolution_bits = rig.daq_resolution_bits;
  daq.sample_rate_hz = rig.sample_rate_hz;
  daq.convert_interval_s = rig.convert_interval_s;
  const std::string message = daq.validate();
  if (message.empty()) return;
  const std::string_view field = field_named_in(message, sensors::DaqParameters::fields());
  const std::optional<Section> daq_table = root.table("daq");
  if ((field == "sample_rate_hz" || field == "convert_interval_s") && clock) {
    clock->fail(field, message);
  }
  if ((field == "range_min_V" || field == "range_max_V") && daq_table) {
    daq_table->fail("range_V", message);
  }
  if (field == "resolution_bits" && daq_table) daq_table->fail("resolution_bits", message);
  failer.fail(daq_table ? daq_table->line() : 1, "daq", message);
}

// The level keys of a trigger, in the order they are checked.
constexpr std::string_view kLevelKeys[] = {"channel", "direction", "level", "hysteresis",
                                           "hold_s",  "absolute",  "unit"};

void read_level(const Section& table, const RigDefinition& rig, RigTrigger& trigger) {
  trigger.channel = table.required_string("channel");
  const RigChannel* channel = rig.find_channel(trigger.channel);
  if (channel == nullptr) {
    std::string names;
    for (const RigChannel& c : rig.channels) names.append(names.empty() ? "" : ", ").append(c.name);
    table.fail("channel", in_quotes(trigger.channel) + " is not a channel of the rig (they are " +
                              names + ")");
  }
  trigger.direction = table.choice("direction", kDirections, "a direction", "rising");
  const std::optional<double> level = table.number("level");
  if (!level)
    table.fail("level", "missing required key (in the channel's unit, " + channel->unit + ")");
  trigger.level = *level;
  trigger.hysteresis = table.number("hysteresis").value_or(0.0);
  if (trigger.hysteresis < 0) {
    table.fail("hysteresis", "must be >= 0 (got " + number_text(trigger.hysteresis) + ")");
  }
  trigger.hold_s = table.number("hold_s").value_or(0.0);
  if (!(trigger.hold_s >= 0 && trigger.hold_s <= kMaxHoldS)) {
    table.fail("hold_s", "must be from 0 to " + whole_number_text(kMaxHoldS) + " s (got " +
                             number_text(trigger.hold_s) + ")");
  }
  trigger.absolute = table.boolean("absolute").value_or(false);
  if (trigger.absolute && !(trigger.level > 0)) {
    table.fail("level",
               "must be > 0 for an absolute level (got " + number_text(trigger.level) + ")");
  }
  if (trigger.absolute && trigger.direction == "rising" && !(trigger.hysteresis < trigger.level)) {
    table.fail("hysteresis", "must be below level " + number_text(trigger.level) +
                                 " for an absolute rising level (got " +
                                 number_text(trigger.hysteresis) + ")");
  }
  if (const auto unit = table.string("unit"); unit && *unit != channel->unit) {
    table.fail("unit", in_quotes(*unit) + " is not the unit of channel " + channel->name +
                           ", which is " + in_quotes(channel->unit));
  }
}

std::vector<RigTrigger> read_triggers(const Section& root, const RigDefinition& rig) {
  std::vector<RigTrigger> triggers;
  for (const Section& table : root.array_of_tables("triggers")) {
    table.allow_only({"name", "kind", "source", "channel", "direction", "level", "hysteresis",
                      "hold_s", "absolute", "unit"});
    RigTrigger trigger;
    trigger.line = table.line();
    trigger.name = table.required_string("name");
    if (!is_name(trigger.name)) {
      table.fail("name", in_quotes(trigger.name) + " must consist of letters, digits and _ only");
    }
    if (trigger.name == "immediate") {
      table.fail("name", "\"immediate\" is reserved (recording.start = \"immediate\")");
    }
    for (std::size_t j = 0; j < triggers.size(); ++j) {
      if (triggers[j].name == trigger.name) {
        table.fail("name", in_quotes(trigger.name) + " is already the name of triggers[" +
                               std::to_string(j) + "] (line " + std::to_string(triggers[j].line) +
                               ")");
      }
    }
    trigger.kind = table.choice("kind", kTriggerKinds, "a trigger kind", std::nullopt);
    const std::optional<std::string> source = table.string("source");
    if (trigger.kind == "external" && !source) {
      table.fail("source",
                 "missing required key (an external trigger needs its input line, e.g. \"PFI0\")");
    }
    if (trigger.kind != "external" && source) {
      table.fail("source", "only external triggers have a source");
    }
    trigger.source = source.value_or("");
    if (trigger.kind == "level") {
      read_level(table, rig, trigger);
    } else {
      for (std::string_view key : kLevelKeys) {
        if (table.find(key)) table.fail(key, "only level triggers have a " + std::string(key));
      }
    }
    triggers.push_back(std::move(trigger));
  }
  return triggers;
}

// `name` must be a trigger's; its index.
std::size_t find_trigger(const Section& table, std::string_view key, const RigDefinition& rig,
                         const std::string& name) {
  for (std::size_t i = 0; i < rig.triggers.size(); ++i) {
    if (rig.triggers[i].name == name) return i;
  }
  std::string names;
  for (const RigTrigger& trigger : rig.triggers) {
    names.append(names.empty() ? "" : ", ").append(trigger.name);
  }
  table.fail(key, in_quotes(name) + " is not the name of a [[triggers]] table (" +
                      (names.empty() ? "there are none" : "they are " + names) + ")");
}

void read_recording(const Section& root, RigDefinition& rig) {
  const std::optional<Section> table = root.table("recording");
  if (!table) return;
  table->allow_only({"start", "stop", "duration_s", "pre_trigger_s", "strokes", "min_stroke_s"});
  RigRecording& recording = rig.recording;
  recording.line = table->line();
  auto no_hold = [&](std::string_view key, const RigTrigger& trigger) {
    if (trigger.hold_s > 0) {
      table->fail(key, in_quotes(trigger.name) + " has hold_s (line " +
                           std::to_string(trigger.line) + "), which only a stop trigger uses");
    }
  };
  recording.start = table->string("start").value_or("immediate");
  const RigTrigger* start = nullptr;
  if (recording.start != "immediate") {
    start = &rig.triggers[find_trigger(*table, "start", rig, recording.start)];
    if (start->kind == "external" && rig.daq_start_trigger != start->name) {
      table->fail("start", in_quotes(start->name) +
                               " is an external trigger: it must also be daq.start_trigger, "
                               "so that the DAQ starts on its line");
    }
    if (start->kind == "level") no_hold("start", *start);
  }
  if (const auto stop = table->string("stop")) {
    const RigTrigger& trigger = rig.triggers[find_trigger(*table, "stop", rig, *stop)];
    if (trigger.kind != "level" && trigger.kind != "manual") {
      table->fail("stop", in_quotes(trigger.name) +
                              (trigger.kind == "external" ? " is an " : " is a ") + trigger.kind +
                              " trigger; a stop must be a level or manual trigger");
    }
    if (trigger.kind == "level" && start != nullptr && start->name == trigger.name) {
      table->fail("stop", in_quotes(trigger.name) +
                              " is also recording.start; a level stop needs a trigger of its own "
                              "(e.g. the falling edge)");
    }
    recording.stop = *stop;
  }
  if (const auto duration = table->number("duration_s")) {
    if (!(*duration > 0 && *duration <= kMaxRecordingS)) {
      table->fail("duration_s", "must be > 0 and <= " + whole_number_text(kMaxRecordingS) + " s (got " +
                                    number_text(*duration) + ")");
    }
    recording.duration_s = *duration;
  }
  recording.pre_trigger_s = table->number("pre_trigger_s").value_or(recording.pre_trigger_s);
  if (!(recording.pre_trigger_s >= 0 && recording.pre_trigger_s <= kMaxPreTriggerS)) {
    table->fail("pre_trigger_s", "must be from 0 to " + number_text(kMaxPreTriggerS) + " s (got " +
                                     number_text(recording.pre_trigger_s) + ")");
  }
  if (const auto strokes = table->string("strokes")) {
    const RigTrigger& trigger = rig.triggers[find_trigger(*table, "strokes", rig, *strokes)];
    if (trigger.kind != "level") {
      table->fail("strokes", in_quotes(trigger.name) +
                                 (trigger.kind == "external" ? " is an " : " is a ") +
                                 trigger.kind + " trigger; stroke markers need a level trigger");
    }
    no_hold("strokes", trigger);
    recording.strokes = *strokes;
  }
  recording.min_stroke_s = table->number("min_stroke_s").value_or(recording.min_stroke_s);
  if (!(recording.min_stroke_s >= 0 && recording.min_stroke_s <= kMaxRecordingS)) {
    table->fail("min_stroke_s", "must be from 0 to " + whole_number_text(kMaxRecordingS) + " s (got " +
                                    number_text(recording.min_stroke_s) + ")");
  }
}

void check_start_trigger(const Section& root, const RigDefinition& rig) {
  if (rig.daq_start_trigger.empty()) return;
  for (const RigTrigger& trigger : rig.triggers) {
    if (trigger.name == rig.daq_start_trigger) return;
  }
  std::string names;
  for (const RigTrigger& trigger : rig.triggers) {
    names.append(names.empty() ? "" : ", ").append(trigger.name);
  }
  root.table("daq")->fail("start_trigger",
                          in_quotes(rig.daq_start_trigger) + " is not the name of a [[triggers]] " +
                              "table (" + (names.empty() ? "there are none" : "they are " + names) +
                              ")");
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
                 "must be > 0 and < 180 (got " + number_text(simulation.hand_target_deg) + ")");
    }
    simulation.hand_cycle_duration_s =
        hand->number("cycle_duration_s").value_or(simulation.hand_cycle_duration_s);
    if (!(simulation.hand_cycle_duration_s > 0)) {
      hand->fail("cycle_duration_s",
                 "must be > 0 (got " + number_text(simulation.hand_cycle_duration_s) + ")");
    }
    const double total_s = simulation.hand_cycles * simulation.hand_cycle_duration_s;
    if (!(total_s <= kMaxRecordingS)) {
      hand->fail(hand->find("cycle_duration_s") ? "cycle_duration_s" : "cycles",
                 "cycles * cycle_duration_s = " + std::to_string(simulation.hand_cycles) + " * " +
                     number_text(simulation.hand_cycle_duration_s) + " s = " +
                     number_text(total_s) + " s must be <= " + whole_number_text(kMaxRecordingS) +
                     " s (a day)");
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
  if (open == std::string_view::npos || description.find("cannot redefine existing") == std::string_view::npos) {
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
