#include "acquisition/session/session_csv.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <system_error>

#include "acquisition/session/interpolation.h"
#include "acquisition/session/output_file.h"
#include "acquisition/session/resample.h"
#include "core/percentile.h"

namespace doorbench {
namespace {

std::string column_name(const ChannelInfo& channel) {
  // Built with append: GCC 12 warns falsely (-Wrestrict) on "_" + std::string.
  std::string suffix("_");
  suffix.append(unit_column_suffix(channel.unit));
  const std::string& name = channel.name;
  const bool has_suffix = name.size() > suffix.size() &&
                          name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  const std::string column = has_suffix ? name : name + suffix;
  // An extra column must not take a main column's name (the inclinometer called "angle"
  // would become angle_rad): prefix it with its sensor kind.
  for (std::string_view main :
       {kTimeColumn, kForceColumn, kAngleColumn, kRateColumn, kStrokeColumn}) {
    if (column == main) return channel.sensor_kind + "_" + column;
  }
  return column;
}

// A channel whose calibration record states a delay (a low-pass sensor lags) is shifted
// back on read: the value at t is the one recorded at t + delay, linearly interpolated
// (held at the ends). The samples in the file are not changed.
std::vector<double> correct_delay(const SessionReader& session, const ChannelInfo& channel,
                                  const std::vector<double>& time_s, std::vector<double> values) {
  if (channel.calibration_id.empty() || values.size() < 2) return values;
  double delay_s = 0.0;
  for (const CalibrationRecord& record : session.calibrations()) {
    if (record.id == channel.calibration_id) delay_s = record.delay_s;
  }
  if (delay_s == 0.0) return values;
  std::vector<double> shifted(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    shifted[i] = interpolate_held(time_s, values, time_s[i] + delay_s);
  }
  return shifted;
}

// The force channel's geometry record (handle radius, the cell's mounting angle), if the
// session applies one: the cell, turned by α from the handle's tangent, reads F · cos α, and
// the record's polynomial ({0, 1/cos α}) gives back the tangential force F.
std::optional<CalibrationRecord> geometry_record(const SessionReader& session,
                                                 const ChannelInfo& channel) {
  if (channel.geometry_calibration_id.empty()) return std::nullopt;
  for (CalibrationRecord& record : session.calibrations()) {
    if (record.id == channel.geometry_calibration_id) {
      if (record.sensor_kind != "geometry" || record.input_unit != channel.unit ||
          record.unit != channel.unit) {
        throw SessionError(session.path().string() + ": channel " + channel.name +
                           "'s geometry record " + record.id + " is a " + record.sensor_kind +
                           " record from " + record.input_unit + " to " + record.unit +
                           ", not a geometry record in " + channel.unit);
      }
      return std::move(record);
    }
  }
  throw SessionError(session.path().string() + ": channel " + channel.name +
                     " uses geometry record " + channel.geometry_calibration_id +
                     ", which is not in the session's /calibrations");
}

bool is_signed_by_mounting(const ChannelInfo& channel) {
  return channel.sensor_kind == "load_cell";
}

// The channels a recording exports: the first force (N), rate (rad/s) and full-range
// angle (rad, not an inclinometer) channel, then every other one.
struct ExportedChannels {
  const ChannelInfo* force = nullptr;
  const ChannelInfo* rate = nullptr;
  const ChannelInfo* angle = nullptr;
  std::vector<const ChannelInfo*> extras;
  std::vector<const ChannelInfo*> all;  // force, rate, angle (those there), extras
};

ExportedChannels exported_channels(const SessionReader& session) {
  const std::vector<ChannelInfo>& channels = session.channels();
  if (channels.empty()) throw SessionError(session.path().string() + ": no channels to export");
  ExportedChannels exported;
  for (const ChannelInfo& channel : channels) {
    if (!exported.force && channel.unit == "N")
      exported.force = &channel;
    else if (!exported.rate && channel.unit == "rad/s")
      exported.rate = &channel;
    else if (!exported.angle && channel.unit == "rad" && channel.sensor_kind != "inclinometer")
      exported.angle = &channel;
    else
      exported.extras.push_back(&channel);
  }
  const std::string where = session.path().string();
  if (!exported.force) {
    throw SessionError(where + ": no force channel (unit N) to export as force_N");
  }
  if (!exported.rate && !exported.angle) {
    throw SessionError(where +
                       ": neither a rate channel (rad/s) nor a full-range angle channel "
                       "(rad, not an inclinometer) to export");
  }
  exported.all.push_back(exported.force);
  if (exported.rate) exported.all.push_back(exported.rate);
  if (exported.angle) exported.all.push_back(exported.angle);
  exported.all.insert(exported.all.end(), exported.extras.begin(), exported.extras.end());
  return exported;
}

// Each column's channel, "force_N=force,...", so that import names the channels as they
// were (csv-format.md).
std::string channel_names_line(const ExportedChannels& exported) {
  std::string names;
  const auto name = [&](std::string_view column, const ChannelInfo& channel) {
    if (!names.empty()) names.push_back(',');
    names.append(column).append("=").append(channel.name);
  };
  name(kForceColumn, *exported.force);
  if (exported.rate) name(kRateColumn, *exported.rate);
  if (exported.angle) name(kAngleColumn, *exported.angle);
  for (const ChannelInfo* extra : exported.extras) name(column_name(*extra), *extra);
  return names;
}

// A channel's physical values on its own clock.
struct OwnClock {
  std::vector<double> time_s, values;
};

// Every exported channel on its own clock, delay-corrected (docs/synchronization.md).
std::vector<OwnClock> read_on_own_clocks(const SessionReader& session,
                                         const std::vector<const ChannelInfo*>& exported) {
  std::vector<OwnClock> own;
  for (const ChannelInfo* channel : exported) {
    const ChannelSlice slice = session.read(channel->name);
    std::vector<double> values = session.physical(channel->name, slice);
    own.push_back(
        {slice.time_s, correct_delay(session, *channel, slice.time_s, std::move(values))});
  }
  return own;
}

// One clock: the same uniform rate and sample count, or the very same explicit times.
bool on_one_clock(const std::vector<const ChannelInfo*>& exported,
                  const std::vector<OwnClock>& own) {
  for (std::size_t i = 1; i < exported.size(); ++i) {
    const ChannelInfo& a = *exported[0];
    const ChannelInfo& b = *exported[i];
    if (own[0].time_s.size() != own[i].time_s.size()) return false;
    if (a.sample_rate_hz > 0 && b.sample_rate_hz > 0) {
      if (!(std::abs(a.sample_rate_hz - b.sample_rate_hz) <= 1e-9 * a.sample_rate_hz)) {
        return false;
      }
    } else if (!(a.sample_rate_hz == 0 && b.sample_rate_hz == 0 &&
                 own[0].time_s == own[i].time_s)) {
      return false;
    }
  }
  return true;
}

// Channels on one uniform clock of which some end before the others (a channel cut
// short): the rows go on to the longest channel's end, on the first channel's clock
// continued, and a shorter channel's cells past its end are missing (NaN: empty cells in a
// CSV; preprocessing leaves out a stroke with missing samples and says so). Fills `columns`,
// recording.time_s and the `cut_short` metadata ("force from 1.001 s (1000 of 2000 rows)");
// false, touching nothing, unless every channel has the same uniform rate and start (within
// half a sample) and the counts differ.
bool on_one_clock_cut_short(const std::vector<const ChannelInfo*>& exported,
                            std::vector<OwnClock>& own, std::vector<std::vector<double>>& columns,
                            Recording& recording) {
  const double rate_hz = exported[0]->sample_rate_hz;
  std::size_t longest = 0;
  bool counts_differ = false;
  for (std::size_t i = 0; i < exported.size(); ++i) {
    const double rate_i = exported[i]->sample_rate_hz;
    if (!(rate_i > 0) || !(std::abs(rate_i - rate_hz) <= 1e-9 * rate_hz)) return false;
    // The same start (the converters' skews of a few µs aside): a channel that starts late
    // is resampled onto the common span instead.
    if (own[i].time_s.empty() ||
        !(std::abs(own[i].time_s.front() - own[0].time_s.front()) < 0.5 / rate_hz)) {
      return false;
    }
    counts_differ = counts_differ || own[i].time_s.size() != own[0].time_s.size();
    longest = std::max(longest, own[i].time_s.size());
  }
  if (!counts_differ) return false;
  recording.time_s = own[0].time_s;
  const double first_s = own[0].time_s.front();
  for (std::size_t j = recording.time_s.size(); j < longest; ++j) {
    recording.time_s.push_back(first_s + static_cast<double>(j) / rate_hz);
  }
  std::string cut;
  for (std::size_t i = 0; i < exported.size(); ++i) {
    const std::size_t count = own[i].values.size();
    columns[i] = std::move(own[i].values);
    if (count == longest) continue;
    columns[i].resize(longest, std::numeric_limits<double>::quiet_NaN());
    if (!cut.empty()) cut += "; ";
    cut += exported[i]->name + " from " + format_csv_number(recording.time_s[count]) + " s (" +
           std::to_string(count) + " of " + std::to_string(longest) + " rows)";
  }
  recording.metadata.emplace_back(std::string(kCutShortKey), cut);
  return true;
}

// The time span every channel has samples in. Throws SessionError for a channel of fewer
// than two samples or no span in common.
std::pair<double, double> common_span_s(const std::string& where,
                                        const std::vector<const ChannelInfo*>& exported,
                                        const std::vector<OwnClock>& own) {
  double first_s = -std::numeric_limits<double>::infinity();
  double last_s = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < exported.size(); ++i) {
    if (own[i].time_s.size() < 2) {
      throw SessionError(where + ": channel " + exported[i]->name + " has " +
                         std::to_string(own[i].time_s.size()) +
                         " samples, too few to place on a common clock");
    }
    first_s = std::max(first_s, own[i].time_s.front());
    last_s = std::min(last_s, own[i].time_s.back());
  }
  if (!(last_s > first_s)) {
    throw SessionError(where + ": the exported channels have no time span in common");
  }
  return {first_s, last_s};
}

// The common axis, in recording.time_s and sample_rate_hz: the first uniform exported
// channel's clock (the force channel's if uniform), else a common rate of 1 / the force
// channel's median interval; within [first_s, last_s]. Returns how, for the metadata.
std::string place_common_axis(const std::vector<const ChannelInfo*>& exported,
                              const std::vector<OwnClock>& own, double first_s, double last_s,
                              Recording& recording) {
  std::optional<std::size_t> reference;
  for (std::size_t i = 0; i < exported.size() && !reference; ++i) {
    if (exported[i]->sample_rate_hz > 0) reference = i;
  }
  std::string placed;
  if (reference) {
    for (double t : own[*reference].time_s) {
      if (t >= first_s && t <= last_s) recording.time_s.push_back(t);
    }
    recording.sample_rate_hz = exported[*reference]->sample_rate_hz;
    placed = "on the clock of " + exported[*reference]->name;
  } else {
    const double rate_hz = 1.0 / median_interval_s(own[0].time_s);
    recording.time_s = uniform_axis(first_s, last_s, rate_hz);
    recording.sample_rate_hz = rate_hz;
    placed = "on a common clock of " + format_csv_number(rate_hz) +
             " Hz (1 / the median interval of " + exported[0]->name + ")";
  }
  return placed + " from " + format_csv_number(first_s) + " s to " + format_csv_number(last_s) +
         " s";
}

// Marks the times of runs of NaN (the channel's gaps) false in `keep` and appends each
// run to `gaps` as "NAME FIRST-LAST s" (joined by "; ").
void mark_gaps(const std::string& name, const std::vector<double>& column,
               const std::vector<double>& time_s, std::vector<bool>& keep, std::string& gaps) {
  for (std::size_t j = 0; j < column.size(); ++j) {
    if (!std::isnan(column[j])) continue;
    std::size_t end = j;
    while (end + 1 < column.size() && std::isnan(column[end + 1])) ++end;
    for (std::size_t k = j; k <= end; ++k) keep[k] = false;
    if (!gaps.empty()) gaps += "; ";
    gaps += name + " " + format_csv_number(time_s[j]) + "-" + format_csv_number(time_s[end]) + " s";
    j = end;
  }
}

// Leaves out the values whose `keep` is false.
void compact(std::vector<double>& values, const std::vector<bool>& keep) {
  std::size_t n = 0;
  for (std::size_t j = 0; j < values.size(); ++j) {
    if (keep[j]) values[n++] = values[j];
  }
  values.resize(n);
}

// Channels on different clocks, resampled linearly onto a common axis (recording.time_s);
// times inside a gap of any channel are left out: a jump in the time column.
std::vector<std::vector<double>> resample_onto_common_clock(
    const std::string& where, const std::vector<const ChannelInfo*>& exported,
    std::vector<OwnClock>& own, Recording& recording) {
  const auto [first_s, last_s] = common_span_s(where, exported, own);
  const std::string placed = place_common_axis(exported, own, first_s, last_s, recording);
  std::vector<std::vector<double>> columns(exported.size());
  std::vector<bool> keep(recording.time_s.size(), true);
  std::string gaps;
  for (std::size_t i = 0; i < exported.size(); ++i) {
    const ChannelInfo& channel = *exported[i];
    const double interval_s = channel.sample_rate_hz > 0 ? 1.0 / channel.sample_rate_hz
                                                         : median_interval_s(own[i].time_s);
    columns[i] = resample_linear(own[i].time_s, own[i].values, recording.time_s,
                                 kGapIntervals * interval_s, where + ": channel " + channel.name);
    mark_gaps(channel.name, columns[i], recording.time_s, keep, gaps);
  }
  if (!gaps.empty()) {
    compact(recording.time_s, keep);
    for (std::vector<double>& column : columns) compact(column, keep);
    recording.metadata.emplace_back("resample_gaps", gaps);
  }
  recording.metadata.emplace_back("resampled", "linear interpolation " + placed);
  return columns;
}

// "stroke 7" → 7 (imported strokes keep their ids); 0 otherwise.
int stroke_id(const std::string& detail) {
  if (detail.rfind("stroke ", 0) != 0) return 0;
  try {
    return std::stoi(detail.substr(7));
  } catch (const std::exception&) {
    return 0;
  }
}

}  // namespace

StrokeColumns stroke_columns_from_events(std::vector<SessionEvent> events,
                                         const std::vector<double>& time_s) {
  std::stable_sort(events.begin(), events.end(), [](const SessionEvent& a, const SessionEvent& b) {
    return a.time_s < b.time_s;
  });
  StrokeColumns strokes{std::vector<int>(time_s.size(), 0), std::vector<int>(time_s.size(), 1)};
  std::size_t next_event = 0;
  int current = 0, number = 0, mounting = 1;
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    // An event at a sample's time applies to that sample (a part in 1e9 of slack for
    // times that went through arithmetic).
    const double slack = 1e-9 * std::max(1.0, std::abs(time_s[i]));
    while (next_event < events.size() && events[next_event].time_s <= time_s[i] + slack) {
      const SessionEvent& event = events[next_event++];
      if (event.kind == "stroke_start") {
        // Imported strokes keep their ids; others are numbered in order.
        const int id = stroke_id(event.detail);
        number = id > 0 ? id : number + 1;
        current = number;
        strokes.any_stroke = true;
        if (event.detail == "opening") mounting = 1;
        if (event.detail == "closing") mounting = -1;
      } else if (event.kind == "stroke_end") {
        current = 0;
      }
    }
    strokes.stroke[i] = current;
    strokes.sign[i] = mounting;
  }
  return strokes;
}

namespace {

// The handle's radius: the geometry record's (the bench's as calibrated) before the
// truth's, the import's or the haptic group's attribute.
void take_handle_radius(const SessionReader& session,
                        const std::optional<CalibrationRecord>& geometry, Recording& recording) {
  for (const std::string group : {"truth", "import", "haptic"}) {
    try {
      const std::string radius = session.read_group_attribute(group, "handle_radius_m");
      recording.handle_radius_m = std::stod(radius);
      break;
    } catch (const std::exception&) {
      // not in this group
    }
  }
  if (geometry) {
    recording.metadata.emplace_back(std::string(kGeometryCalibrationKey), geometry->id);
    if (const CalibrationQuantity* radius = geometry->quantity("handle_radius_m")) {
      recording.handle_radius_m = radius->value;
    }
  }
}

}  // namespace

Recording session_to_recording(const SessionReader& session) {
  const ExportedChannels exported = exported_channels(session);
  const std::string where = session.path().string();
  Recording recording;
  recording.source = where;
  recording.metadata.emplace_back("source", "doorbench export " + where);
  recording.metadata.emplace_back(std::string(kChannelNamesKey), channel_names_line(exported));

  std::vector<OwnClock> own = read_on_own_clocks(session, exported.all);
  std::vector<std::vector<double>> columns(exported.all.size());
  if (on_one_clock(exported.all, own)) {
    // All on the force channel's clock: its times (converter skews of a few µs are not
    // resampled; explicit times shared by every channel, as imports have them, are kept).
    recording.time_s = own[0].time_s;
    for (std::size_t i = 0; i < exported.all.size(); ++i) columns[i] = std::move(own[i].values);
  } else if (on_one_clock_cut_short(exported.all, own, columns, recording)) {
    // A channel cut short: its cells are missing from its end (the rows go on).
  } else {
    columns = resample_onto_common_clock(where, exported.all, own, recording);
  }
  const auto column = [&](const ChannelInfo& channel) {
    for (std::size_t i = 0; i < exported.all.size(); ++i) {
      if (exported.all[i] == &channel) return columns[i];
    }
    throw std::logic_error("not exported: " + channel.name);
  };

  // Strokes from events; the load cell's mounting from each stroke's detail.
  const StrokeColumns strokes = stroke_columns_from_events(session.events(), recording.time_s);
  recording.force_N = column(*exported.force);
  const std::optional<CalibrationRecord> geometry = geometry_record(session, *exported.force);
  if (geometry) {
    for (double& value : recording.force_N) value = geometry->apply(value);
  }
  if (is_signed_by_mounting(*exported.force)) {
    for (std::size_t i = 0; i < recording.force_N.size(); ++i) {
      recording.force_N[i] *= strokes.sign[i];
    }
  }
  if (exported.rate) recording.rate_rad_s = column(*exported.rate);
  if (exported.angle) recording.angle_rad = column(*exported.angle);
  if (strokes.any_stroke) recording.stroke = strokes.stroke;
  for (const ChannelInfo* extra : exported.extras) {
    recording.extra_names.push_back(column_name(*extra));
    recording.extra_columns.push_back(column(*extra));
  }
  if (!recording.sample_rate_hz && exported.force->sample_rate_hz > 0) {
    recording.sample_rate_hz = exported.force->sample_rate_hz;
  }
  take_handle_radius(session, geometry, recording);
  return recording;
}

namespace {

// The channel_names metadata (column=channel,...): which channel each column was; without
// it (a CSV from elsewhere) the main columns give force, angle and rate.
std::map<std::string, std::string> channel_names(const Recording& recording) {
  std::map<std::string, std::string> names = {{std::string(kForceColumn), "force"},
                                              {std::string(kAngleColumn), "angle"},
                                              {std::string(kRateColumn), "rate"}};
  for (const auto& [key, value] : recording.metadata) {
    if (key != kChannelNamesKey) continue;
    std::size_t begin = 0;
    while (begin <= value.size()) {
      const std::size_t end = std::min(value.find(',', begin), value.size());
      const std::string item = value.substr(begin, end - begin);
      const std::size_t equals = item.find('=');
      if (equals != std::string::npos && equals > 0 && equals + 1 < item.size()) {
        names[item.substr(0, equals)] = item.substr(equals + 1);
      }
      begin = end + 1;
    }
  }
  return names;
}

void write_recording_session(const Recording& recording, const std::filesystem::path& path,
                             const SessionMetadata& metadata) {
  const std::size_t count = recording.size();
  if (count == 0) throw std::invalid_argument(recording.source + ": no samples to import");
  // A uniform clock only when it gives back every time exactly (as the reader computes
  // them: first + i / rate), trying the rate rounded to whole hertz first; otherwise the
  // times are stored as they are.
  double rate_hz = 0.0;
  if (count >= 2) {
    const double first = recording.time_s.front();
    const double mean_rate = static_cast<double>(count - 1) / (recording.time_s.back() - first);
    for (double candidate : {std::round(mean_rate), mean_rate}) {
      if (!(candidate > 0) || std::abs(candidate - mean_rate) > 1e-6 * mean_rate) continue;
      bool exact = true;
      for (std::size_t i = 0; i < count && exact; ++i) {
        exact = first + static_cast<double>(i) / candidate == recording.time_s[i];
      }
      if (exact) {
        rate_hz = candidate;
        break;
      }
    }
  }

  SessionWriter writer(path, metadata);
  const std::map<std::string, std::string> names = channel_names(recording);
  auto add = [&](const std::string& column, const std::string& unit,
                 const std::vector<double>& values) {
    ChannelInfo channel;
    const auto named = names.find(column);
    channel.name = named != names.end() ? named->second : column;
    // A narrow-range inclinometer column (as export writes it) stays an inclinometer, so
    // that it is not taken for the full-range angle on the way back.
    channel.sensor_kind = column.rfind("inclinometer", 0) == 0 ? "inclinometer" : "imported";
    channel.raw_type = RawType::kValues;
    channel.raw_unit = unit;
    channel.unit = unit;
    channel.range_min = -std::numeric_limits<double>::max();
    channel.range_max = std::numeric_limits<double>::max();
    channel.sample_rate_hz = rate_hz;
    channel.first_sample_time_s = recording.time_s.front();
    // A raw column (import --scale, --calibration): the raw values, and the record that makes
    // them physical, as a recorded channel keeps its counts and its record.
    const auto calibrated = recording.calibrations.find(column);
    if (calibrated != recording.calibrations.end()) {
      const CalibrationRecord& record = calibrated->second;
      channel.raw_unit = record.input_unit;
      channel.unit = record.unit;
      channel.calibration_id = record.id;
      channel.sensor_serial = record.sensor_serial;
      writer.add_calibration(record);
    }
    const int index = writer.add_channel(channel);
    if (rate_hz > 0)
      writer.append_values(index, values);
    else
      writer.append_timed_values(index, recording.time_s, values);
  };
  add(std::string(kForceColumn), "N", recording.force_N);
  if (recording.angle_rad) add(std::string(kAngleColumn), "rad", *recording.angle_rad);
  if (recording.rate_rad_s) add(std::string(kRateColumn), "rad/s", *recording.rate_rad_s);
  for (std::size_t e = 0; e < recording.extra_names.size(); ++e) {
    const std::string& column = recording.extra_names[e];
    add(column, unit_of_column(column), recording.extra_columns[e]);
  }
  if (recording.stroke) {
    int current = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const int stroke = (*recording.stroke)[i];
      if (stroke == current) continue;
      if (current != 0) writer.add_event({recording.time_s[i], "stroke_end", "", ""});
      if (stroke != 0) {
        writer.add_event(
            {recording.time_s[i], "stroke_start", "", "stroke " + std::to_string(stroke)});
      }
      current = stroke;
    }
    // A stroke still open at the last sample has no end event: it runs to the end.
  }
  writer.write_group_attribute("import", "source_file", recording.source);
  if (recording.handle_radius_m) {
    writer.write_group_attribute("import", "handle_radius_m",
                                 format_csv_number(*recording.handle_radius_m));
  }
  for (const auto& [key, value] : recording.metadata) {
    if (!key.empty()) writer.write_group_attribute("import", "csv_" + key, value);
  }
  writer.close();
}

// Each metadata key becomes one attribute of the import group, so a key may come once. The
// file's own keys are unique (parse_csv_table checks), so a repeat is a key the file has and
// import adds itself (--map, --resample-hz, a TDMS file's timing): refused before anything is
// written, naming the file and the key.
void check_metadata_keys_once(const Recording& recording) {
  std::set<std::string> keys;
  for (const auto& [key, value] : recording.metadata) {
    if (key.empty() || keys.insert(key).second) continue;
    throw SessionError(recording.source + ": metadata key '" + key +
                       "' is one import writes itself; rename the file's key");
  }
}

}  // namespace

void recording_to_session(const Recording& recording, const std::filesystem::path& path,
                          const SessionMetadata& metadata) {
  if (std::filesystem::exists(path)) {
    throw SessionError(path.string() + ": already exists (sessions are never overwritten)");
  }
  check_metadata_keys_once(recording);
  // Whole or not at all (acquisition/session/output_file.h): the session is written beside its
  // name and renamed into place once closed.
  const std::filesystem::path partial = partial_path_for(path);
  try {
    write_recording_session(recording, partial, metadata);
  } catch (const SessionError& error) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw SessionError(path.string() + ": cannot write: " + error.what());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw;
  }
  commit_partial_file(partial, path);
}

}  // namespace doorbench
