// Mapping a TDMS file's channels to a recording (acquisition/session/tdms.h): the --map
// syntax with its escapes, the channel list for messages, and tdms_to_recording.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

#include "acquisition/session/csv_table.h"
#include "acquisition/session/map_syntax.h"
#include "acquisition/session/tdms.h"

namespace doorbench {

namespace {

// One TARGET=GROUP/CHANNEL item (escapes kept).
TdmsMapItem parse_map_item(const MapItemText& given) {
  TdmsMapItem parsed;
  parsed.target = given.target;
  parsed.text = given.text;
  if (!given.target.empty()) {
    for (std::size_t slash : unescaped_positions(parsed.text, '/')) {
      std::string group = unescaped(parsed.text.substr(0, slash));
      std::string channel = unescaped(parsed.text.substr(slash + 1));
      if (!group.empty() && !channel.empty()) parsed.splits.emplace_back(group, channel);
    }
  }
  if (parsed.splits.empty()) {
    throw std::invalid_argument("--map item '" + given.item +
                                "' is not TARGET=GROUP/CHANNEL (e.g. force=Load/Force)");
  }
  parsed.group = parsed.splits.front().first;
  parsed.channel = parsed.splits.front().second;
  return parsed;
}

}  // namespace

std::vector<TdmsMapItem> parse_tdms_map(const std::string& text) {
  std::vector<TdmsMapItem> items;
  std::vector<std::string> targets;
  for (const MapItemText& given : split_map_items(text)) {
    TdmsMapItem item = parse_map_item(given);
    check_map_target(item.target, targets);
    targets.push_back(item.target);
    items.push_back(std::move(item));
  }
  return items;
}

std::string escape_tdms_map_name(const std::string& name) {
  std::string out;
  for (char c : name) {
    if (c == '/' || c == ',' || c == '=' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

std::string tdms_channel_list(const TdmsFile& file) {
  std::string list;
  for (const TdmsChannel& c : file.channels) {
    list += (list.empty() ? "" : ", ") + escape_tdms_map_name(c.group) + "/" +
            escape_tdms_map_name(c.name);
  }
  return list.empty() ? "none" : list;
}

namespace {

const TdmsProperty* property(const TdmsChannel& channel, const std::string& name) {
  const auto it = channel.properties.find(name);
  return it == channel.properties.end() ? nullptr : &it->second;
}

// The item a map gives for `target`, or null.
const TdmsMapItem* map_item(const std::vector<TdmsMapItem>& map, const std::string& target) {
  const TdmsMapItem* found = nullptr;
  for (const TdmsMapItem& item : map) {
    if (item.target == target) found = &item;
  }
  return found;
}

// A mapping error: "SOURCE: WHAT; the file's channels: A/B, ..." (the names to map).
[[noreturn]] void mapping_error(const TdmsFile& file, const std::string& source,
                                const std::string& what) {
  throw TdmsError(source + ": " + what + "; the file's channels: " + tdms_channel_list(file));
}

// A channel's name as --map takes it.
std::string map_name(const TdmsChannel& channel) {
  return escape_tdms_map_name(channel.group) + "/" + escape_tdms_map_name(channel.name);
}

// The map's force item; throws when the map gives no force or no motion channel.
const TdmsMapItem& check_map(const TdmsFile& file, const std::vector<TdmsMapItem>& map,
                             const std::string& source) {
  const TdmsMapItem* force_item = map_item(map, "force");
  const bool has_motion = map_item(map, "angle") != nullptr || map_item(map, "rate") != nullptr;
  if (!force_item)
    mapping_error(file, source, "--map gives no force channel (force=GROUP/CHANNEL)");
  if (!has_motion) {
    mapping_error(file, source,
                  "--map gives neither angle nor rate (angle=GROUP/CHANNEL or "
                  "rate=GROUP/CHANNEL)");
  }
  return *force_item;
}

// The channel an item maps, which must exist, be the only one its text can mean, and hold
// numbers.
const TdmsChannel& mapped_channel(const TdmsFile& file, const TdmsMapItem& item,
                                  const std::string& source) {
  std::vector<const TdmsChannel*> matches;
  for (const auto& [group, name] : item.splits) {
    if (const TdmsChannel* channel = file.find(group, name)) matches.push_back(channel);
  }
  if (matches.empty()) {
    mapping_error(file, source, item.target + ": no channel " + item.text);
  }
  if (matches.size() > 1) {
    std::string meant;
    for (const TdmsChannel* channel : matches) {
      meant += (meant.empty() ? "" : " and ") + map_name(*channel);
    }
    mapping_error(file, source,
                  item.target + ": " + item.text + " can mean " + meant +
                      " (write '\\/' for a '/' inside a name)");
  }
  const TdmsChannel& channel = *matches.front();
  if (channel.data_type.empty()) {
    mapping_error(file, source,
                  item.target + ": channel " + map_name(channel) + " has no numeric values");
  }
  return channel;
}

// Without a time channel, the time from the force channel's waveform properties
// (wf_start_offset + i · wf_increment), or from rate_hz (> 0: --rate-hz) where the channel
// has no wf_increment. Returns the interval between samples.
double waveform_time(const TdmsFile& file, const TdmsChannel& force, const std::string& source,
                     double rate_hz, Recording& recording) {
  const TdmsProperty* increment = property(force, "wf_increment");
  const bool has_increment = increment && increment->number && *increment->number > 0;
  if (!has_increment && !(rate_hz > 0)) {
    mapping_error(file, source,
                  "force: channel " + map_name(force) +
                      " has no wf_increment > 0 to give the time (give its rate, --rate-hz R, "
                      "or map a time channel, time=GROUP/CHANNEL)");
  }
  if (has_increment && rate_hz > 0 && !(std::abs(*increment->number * rate_hz - 1.0) <= 1e-9)) {
    mapping_error(file, source,
                  "force: --rate-hz " + format_csv_number(rate_hz) + " contradicts channel " +
                      map_name(force) + "'s wf_increment " + format_csv_number(*increment->number) +
                      " s (" + format_csv_number(1.0 / *increment->number) + " Hz)");
  }
  const double interval_s = has_increment ? *increment->number : 1.0 / rate_hz;
  const TdmsProperty* offset = property(force, "wf_start_offset");
  const double first_s = offset && offset->number ? *offset->number : 0.0;
  recording.time_s.resize(force.values.size());
  for (std::size_t i = 0; i < force.values.size(); ++i) {
    // i / rate, as a session's uniform clock computes it, for a rate given by --rate-hz.
    recording.time_s[i] = has_increment ? first_s + static_cast<double>(i) * interval_s
                                        : first_s + static_cast<double>(i) / rate_hz;
  }
  if (!has_increment) {
    recording.metadata.emplace_back("tdms_rate_hz",
                                    format_csv_number(rate_hz) + " (--rate-hz: no wf_increment)");
  }
  return interval_s;
}

// The factor from a time channel's unit to seconds: 1e-3 for ms, 1e-6 for us; none for
// another unit or none stated.
std::optional<double> time_unit_factor(const TdmsChannel& channel) {
  const TdmsProperty* unit = property(channel, "unit_string");
  if (!unit) return std::nullopt;
  return stated_unit_factor(unit_symbol(unit->text), "s");
}

// `conversions` and, for each force, angle or rate mapped without one whose channel's
// unit_string states a unit stated_unit_factor converts ("Degrees", "deg/s", "kN"): its
// stated_unit_conversion.
std::vector<ImportConversion> with_channel_unit_conversions(
    const TdmsFile& file, const std::vector<TdmsMapItem>& map,
    const std::vector<ImportConversion>& conversions, const std::string& source) {
  std::vector<ImportConversion> all = conversions;
  for (const TdmsMapItem& item : map) {
    if (item.target != "force" && item.target != "angle" && item.target != "rate") continue;
    if (find_conversion(conversions, item.target) != nullptr) continue;
    const TdmsProperty* unit = property(mapped_channel(file, item, source), "unit_string");
    if (!unit) continue;
    if (auto conversion = stated_unit_conversion(
            item.target, unit_symbol(unit->text),
            item.target + "=" + item.text + ", the unit its channel states")) {
      all.push_back(std::move(*conversion));
    }
  }
  return all;
}

// The unit a target's channel must state (when it states one): the target's, or for a
// converted target its record's input unit ("" for a --scale: any).
std::string expected_unit(const TdmsMapItem& item, const ImportConversion* conversion) {
  if (conversion) return conversion->record ? conversion->record->input_unit : "";
  return item.target == "force"   ? "N"
         : item.target == "angle" ? "rad"
         : item.target == "rate"  ? "rad/s"
         : item.target == "time"  ? "s"
                                  : "";
}

// One mapped channel into its column (force, angle, rate, an extra; time is taken
// before): as many values as the force channel, the same waveform increment as the clock's
// (interval_s > 0, when the time is the waveform's), the target's unit (or its record's
// input unit); its origin as metadata, and its record when it is converted.
void take_mapped_column(const TdmsFile& file, const TdmsMapItem& item, const TdmsChannel& channel,
                        const TdmsChannel& force, double interval_s,
                        const TdmsImportOptions& options, const std::string& source,
                        Recording& recording) {
  const std::string name = map_name(channel);
  if (channel.values.size() != force.values.size()) {
    mapping_error(file, source,
                  item.target + ": channel " + name + " has " +
                      std::to_string(channel.values.size()) + " values, the force channel " +
                      std::to_string(force.values.size()));
  }
  if (interval_s > 0 && item.target != "time") {
    const TdmsProperty* increment = property(channel, "wf_increment");
    if (increment && increment->number && *increment->number != interval_s) {
      mapping_error(file, source,
                    item.target + ": channel " + name + " has wf_increment " +
                        format_csv_number(*increment->number) + ", the force channel " +
                        format_csv_number(interval_s));
    }
  }
  const ImportConversion* conversion = find_conversion(options.conversions, item.target);
  const std::string expected = expected_unit(item, conversion);
  const TdmsProperty* unit = property(channel, "unit_string");
  const bool states_unit = unit && !unit->text.empty();
  const bool time = item.target == "time";
  if (!expected.empty() && states_unit && unit->text != expected &&
      (conversion ||
       (unit_symbol(unit->text) != expected && !(time && time_unit_factor(channel))))) {
    mapping_error(file, source,
                  item.target + ": channel " + name + " is in '" + unit->text + "', not " +
                      expected +
                      (conversion ? " (" + conversion->given + ")"
                       : time     ? " (the time is read in s, ms or us)"
                                  : " (convert it: --calibration " + item.target +
                                    "=RECORD or --scale " + item.target +
                                    "=GAIN[,OFFSET]; or map it as an extra column whose "
                                    "name ends in its unit)"));
  }
  if (conversion) {
    CalibrationRecord record;
    try {
      record = conversion->record_for(states_unit ? unit->text : "");
    } catch (const std::invalid_argument& error) {
      mapping_error(file, source, item.target + ": channel " + name + " " + error.what());
    }
    recording.metadata.emplace_back("tdms_" + item.target + "_calibration", record.id);
    recording.calibrations.emplace(import_target_column(item.target), std::move(record));
  }
  if (item.target == "force") {
    recording.force_N = channel.values;
  } else if (item.target == "angle") {
    recording.angle_rad = channel.values;
  } else if (item.target == "rate") {
    recording.rate_rad_s = channel.values;
  } else if (item.target != "time") {
    recording.extra_names.push_back(item.target);
    recording.extra_columns.push_back(channel.values);
  }
  const std::string key = "tdms_" + item.target;
  recording.metadata.emplace_back(key + "_channel", name);
  if (unit) recording.metadata.emplace_back(key + "_unit", unit->text);
  if (!channel.scaling.empty()) recording.metadata.emplace_back(key + "_scaling", channel.scaling);
}

// The handle radius: a file property, else the force channel's group's; must be > 0.
std::optional<double> handle_radius_m(const TdmsFile& file, const TdmsChannel& force,
                                      const std::string& source) {
  std::optional<double> radius;
  if (const auto it = file.file_properties.find("handle_radius_m");
      it != file.file_properties.end() && it->second.number) {
    radius = it->second.number;
  } else if (const auto group = file.group_properties.find(force.group);
             group != file.group_properties.end()) {
    if (const auto r = group->second.find("handle_radius_m");
        r != group->second.end() && r->second.number) {
      radius = r->second.number;
    }
  }
  if (radius && !(*radius > 0)) throw TdmsError(source + ": handle_radius_m must be > 0");
  return radius;
}

// The file's other properties as metadata "tdms_file_NAME" (non-alphanumerics as '_', line
// breaks as spaces).
void file_properties_as_metadata(const TdmsFile& file, Recording& recording) {
  for (const auto& [name, value] : file.file_properties) {
    if (name == "handle_radius_m") continue;
    std::string key = "tdms_file_";
    for (char c : name) key += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    std::string text = value.text;
    std::replace(text.begin(), text.end(), '\n', ' ');
    std::replace(text.begin(), text.end(), '\r', ' ');
    recording.metadata.emplace_back(key, text);
  }
}

// --keep-raw: each mapped channel's DAQmx scalers as stored (TdmsChannel::daqmx_raw), as
// extra columns named after the target ("force_raw"; "incl_raw" for incl_V; the scaler id
// appended when the channel has several: "force_raw0"), each with a metadata line saying
// what it holds. Channels without DAQmx raw data add nothing.
void add_raw_columns(const TdmsFile& file, const std::vector<TdmsMapItem>& map,
                     const std::string& source, Recording& recording) {
  for (const TdmsMapItem& item : map) {
    if (item.target == "time") continue;
    const TdmsChannel& channel = mapped_channel(file, item, source);
    if (channel.daqmx_raw.empty()) continue;
    const bool physical = item.target == "force" || item.target == "angle" || item.target == "rate";
    const std::string stem = physical ? item.target : item.target.substr(0, item.target.rfind('_'));
    for (const auto& [id, values] : channel.daqmx_raw) {
      const std::string name =
          stem + "_raw" + (channel.daqmx_raw.size() > 1 ? std::to_string(id) : std::string());
      if (values.size() != recording.time_s.size()) {
        throw TdmsError(std::string(source)
                            .append(": --keep-raw: DAQmx scaler ")
                            .append(std::to_string(id))
                            .append(" of ")
                            .append(map_name(channel))
                            .append(" holds ")
                            .append(std::to_string(values.size()))
                            .append(" values for ")
                            .append(std::to_string(recording.time_s.size()))
                            .append(" samples"));
      }
      recording.extra_names.push_back(name);
      recording.extra_columns.push_back(values);
      recording.metadata.emplace_back("tdms_raw_" + name, std::string("DAQmx scaler ")
                                                              .append(std::to_string(id))
                                                              .append(" of ")
                                                              .append(map_name(channel))
                                                              .append(" as stored (")
                                                              .append(item.target)
                                                              .append(" is it through ")
                                                              .append(channel.scaling)
                                                              .append(")"));
    }
  }
}

}  // namespace

std::string TdmsImportOptions::validate() const {
  if (!std::isfinite(rate_hz) || rate_hz < 0) return "--rate-hz must be a finite rate >= 0";
  for (const ImportConversion& conversion : conversions) {
    if (conversion.target == "time") return conversion.given + ": time cannot be converted";
  }
  return "";
}

Recording tdms_to_recording(const TdmsFile& file, const std::vector<TdmsMapItem>& map,
                            const std::string& source, const TdmsImportOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  Recording recording;
  recording.source = source;
  const TdmsChannel& force = mapped_channel(file, check_map(file, map, source), source);
  // One channel, one target: a channel mapped as both force and angle is a typing error.
  std::vector<std::pair<const TdmsChannel*, std::string>> taken;
  for (const TdmsMapItem& item : map) {
    const TdmsChannel* channel = &mapped_channel(file, item, source);
    for (const auto& [earlier, target] : taken) {
      if (earlier == channel) {
        mapping_error(file, source,
                      item.target + ": channel " + map_name(*channel) + " is mapped as " + target +
                          " already (one channel per target)");
      }
    }
    taken.emplace_back(channel, item.target);
  }
  const TdmsMapItem* time_item = map_item(map, "time");
  double interval_s = 0.0;  // the waveform clock's interval (0: a time channel)
  if (time_item && options.rate_hz > 0) {
    mapping_error(file, source,
                  "--rate-hz and time=" + time_item->text + " both give the time (give one)");
  }
  if (time_item) {
    const TdmsChannel& clock = mapped_channel(file, *time_item, source);
    recording.time_s = clock.values;
    if (const std::optional<double> factor = time_unit_factor(clock)) {
      for (double& t : recording.time_s) t *= *factor;
    }
  } else {
    interval_s = waveform_time(file, force, source, options.rate_hz, recording);
  }
  if (const TdmsProperty* start = property(force, "wf_start_time")) {
    recording.metadata.emplace_back("tdms_wf_start_time", start->text);
  }
  TdmsImportOptions with_units = options;
  with_units.conversions = with_channel_unit_conversions(file, map, options.conversions, source);
  for (const TdmsMapItem& item : map) {
    take_mapped_column(file, item, mapped_channel(file, item, source), force, interval_s,
                       with_units, source, recording);
  }
  for (std::size_t i = 1; i < recording.time_s.size(); ++i) {
    if (!(recording.time_s[i] > recording.time_s[i - 1])) {
      throw TdmsError(source + ": time is not strictly increasing at sample " + std::to_string(i));
    }
  }
  if (const std::optional<double> radius = handle_radius_m(file, force, source)) {
    recording.handle_radius_m = radius;
  }
  file_properties_as_metadata(file, recording);
  for (const ImportConversion& conversion : options.conversions) {
    if (!map_item(map, conversion.target)) {
      mapping_error(file, source,
                    conversion.given + ": --map has no " + conversion.target + " channel");
    }
  }
  if (options.keep_raw) add_raw_columns(file, map, source, recording);
  return recording;
}

}  // namespace doorbench
