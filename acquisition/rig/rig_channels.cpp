// The rig file's channels (docs/rig-format.md, "Channels" and "Modbus"): the Modbus
// devices, each channel with its backend and its sensor's parameters, and the check that
// the DAQ's channels fit one scan.
#include <algorithm>
#include <climits>
#include <cmath>
#include <set>

#include "acquisition/rig/internal/rig_toml.h"
#include "acquisition/rig/sensor_parameters.h"

namespace doorbench::rig_detail {

namespace {

constexpr std::string_view kSensorKinds[] = {"load_cell", "inclinometer", "gyroscope"};
constexpr std::string_view kChannelBackends[] = {"simulated", "comedi", "modbus"};
constexpr std::string_view kModbusTransports[] = {"tcp", "rtu"};
constexpr std::string_view kModbusParities[] = {"none", "even", "odd"};
constexpr std::string_view kModbusRegisterKinds[] = {"holding", "input"};
constexpr std::string_view kModbusTypes[] = {"int16", "uint16", "int32", "uint32", "float32"};
constexpr std::string_view kModbusOrders[] = {"big", "little"};
constexpr std::string_view kArefs[] = {"ground", "common", "diff", "other"};

// The unit a sensor kind's readings have after calibration.
std::string_view unit_of(std::string_view sensor) {
  if (sensor == "load_cell") return "N";
  if (sensor == "inclinometer") return "rad";
  return "rad/s";
}

// The field of `fields` that `message` names first, as a whole word ("" if none).
std::string_view field_named_in(std::string_view message, std::span<const ParameterField> fields) {
  auto word_char = [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  };
  std::string_view best;
  std::size_t best_position = std::string_view::npos;
  for (const ParameterField& field : fields) {
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
  for (const ParameterField& field : Parameters::fields()) valid.push_back(field.name);

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
  if (!(value > 0)) table.fail(key, "must be > 0 (got " + format_number(value) + ")");
  return value;
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
    table->fail("range", "min " + format_number(modbus.range_min) + " must be below max " +
                             format_number(modbus.range_max));
  }
  if (!table->find("poll_rate_hz")) table->fail("poll_rate_hz", "missing required key");
  modbus.poll_rate_hz = positive_number(*table, "poll_rate_hz", 0);
  if (modbus.poll_rate_hz > 10000) {
    table->fail("poll_rate_hz",
                "must be <= 10000 (got " + format_number(modbus.poll_rate_hz) + ")");
  }
  return modbus;
}

}  // namespace

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
                                        format_number(device.reconnect_min_s) + " (got " +
                                        format_number(device.reconnect_max_s) + ")");
    }
    rig.modbus_devices.push_back(std::move(device));
  }
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
        table.fail("range_V", "[" + format_number(range->first) + ", " +
                                  format_number(range->second) +
                                  "] V must lie inside the DAQ's range [" +
                                  format_number(rig.daq_range_min_V) + ", " +
                                  format_number(rig.daq_range_max_V) + "] V (daq.range_V)");
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
      read_parameters<LoadCellParameters>(table, channel.sensor, channel);
    } else if (channel.sensor == "inclinometer") {
      read_parameters<InclinometerParameters>(table, channel.sensor, channel);
    } else {
      read_parameters<GyroscopeParameters>(table, channel.sensor, channel);
    }

    parsed.backend_lines.push_back(table.line_of_key("backend"));
    parsed.channels.push_back(std::move(channel));
  }
  return parsed;
}

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
    failer.fail(line, "clock.convert_interval_s",
                "(channels - 1) * convert_interval_s = (" + std::to_string(daq_channels) +
                    " - 1) * " + format_number(rig.convert_interval_s) +
                    " s = " + format_number(scan_s) +
                    " s must be less than the sample period 1 / sample_rate_hz = " +
                    format_number(period_s) + " s");
  }

  DaqParameters daq;
  daq.range_min_V = rig.daq_range_min_V;
  daq.range_max_V = rig.daq_range_max_V;
  daq.resolution_bits = rig.daq_resolution_bits;
  daq.sample_rate_hz = rig.sample_rate_hz;
  daq.convert_interval_s = rig.convert_interval_s;
  const std::string message = daq.validate();
  if (message.empty()) return;
  const std::string_view field = field_named_in(message, DaqParameters::fields());
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

}  // namespace doorbench::rig_detail
