// Session files in HDF5 through the C API: the reader. The layout is in
// docs/session-format.md; keep that page, this file and session_writer.cpp in step.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <utility>

#include "acquisition/session/internal/session_hdf5.h"
#include "acquisition/session/printable.h"
#include "acquisition/session/session_file.h"
#include "core/number_format.h"

namespace doorbench {

namespace fs = std::filesystem;
using doorbench::CalibrationRecord;
using namespace session_hdf5;
// ---------------------------------------------------------------------------------------
// Reader

struct SessionReader::Impl {
  struct Channel {
    Handle raw, time;
    hsize_t count = 0;
    double first_time = 0.0, last_time = 0.0;  // of the first and last samples
  };

  fs::path path;
  std::string prefix;
  Handle file;
  SessionMetadata metadata;
  std::vector<ChannelInfo> infos;
  std::vector<Channel> channels;  // parallel to infos
  std::vector<SessionEvent> events;
  std::vector<CalibrationRecord> calibrations;

  template <class Body>
  auto guarded(Body&& body) const {
    const Hdf5Quiet quiet;
    try {
      return body();
    } catch (const Failure& failure) {
      throw SessionError(prefix + failure.what());
    }
  }

  std::size_t index_of(const std::string& name) const {
    for (std::size_t i = 0; i < infos.size(); ++i) {
      if (infos[i].name == name) return i;
    }
    std::string known;
    for (const ChannelInfo& info : infos) known += (known.empty() ? "" : ", ") + info.name;
    throw SessionError(prefix + "no channel " + in_quotes(name) +
                       " (channels: " + (known.empty() ? "none" : known) + ")");
  }

  void open() {
    std::error_code error;
    if (!fs::exists(path, error)) throw Failure("no such file");
    if (fs::is_directory(path, error)) throw Failure("is a directory, not a session file");
    const htri_t is_hdf5 = H5Fis_hdf5(path.c_str());
    if (is_hdf5 < 0) fail("cannot open");
    if (is_hdf5 == 0) throw Failure("not a doorbench session (not an HDF5 file)");
    file = checked(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, "cannot open");
    const hid_t root = file.get();

    if (!has_attribute(root, "format")) {
      throw Failure("not a doorbench session (no format attribute)");
    }
    const std::string format = read_text_attribute(root, "format", "/");
    if (format != kFormatName) {
      throw Failure("not a doorbench session (format is " + in_quotes(format) + ")");
    }
    if (!has_attribute(root, "format_version")) {
      throw Failure("doorbench session without a format_version attribute");
    }
    const double version = read_double_attribute(root, "format_version", "/");
    if (version != std::floor(version) || version < 1) {
      throw Failure("session format version " + format_number(version) + " is not valid");
    }
    if (version > kSessionFormatVersion) {
      throw Failure("session format version " + format_number(version) +
                    " is newer than this doorbench (" + std::to_string(kSessionFormatVersion) +
                    ")");
    }

    for (const char* group : kReservedGroups) {
      if (!has_link(root, group)) throw Failure(std::string("session lacks group /") + group);
    }
    {
      const Handle meta = open_group(root, "metadata");
      const hid_t g = meta.get();
      const std::string where = "/metadata";
      metadata.rig_name = read_text_attribute(g, "rig_name", where);
      metadata.operator_name = read_text_attribute(g, "operator", where);
      metadata.product_id = read_text_attribute(g, "product_id", where);
      metadata.start_time_utc = read_text_attribute(g, "start_time_utc", where);
      metadata.software_version = read_text_attribute(g, "software_version", where);
      metadata.notes = read_text_attribute(g, "notes", where);
      metadata.rig_definition = read_text_dataset(g, "rig_definition", where);
    }
    load_channels();
    load_events();
    load_calibrations();
  }

  void load_channels() {
    const Handle group = open_group(file.get(), "channels");
    for (const std::string& name : link_names(group.get())) {
      // The documented rule (docs/session-format.md), also for files made elsewhere: such a
      // name reaches terminals, CSV headers and HDF5 paths.
      if (!valid_channel_name(name)) {
        throw Failure("/channels/" + printable(name) +
                      ": a channel name is letters, digits and _ only");
      }
      const std::string where = "/channels/" + name;
      const Handle g = open_group(group.get(), name);
      const hid_t id = g.get();
      ChannelInfo info;
      info.name = name;
      info.sensor_kind = read_text_attribute(id, "sensor_kind", where);
      info.sensor_serial = read_text_attribute(id, "sensor_serial", where);
      const std::string raw_type = read_text_attribute(id, "raw_type", where);
      if (raw_type == "counts") {
        info.raw_type = RawType::kCounts;
      } else if (raw_type == "values") {
        info.raw_type = RawType::kValues;
      } else {
        throw Failure(where + ": raw_type must be counts or values, not " + in_quotes(raw_type));
      }
      info.raw_unit = read_text_attribute(id, "raw_unit", where);
      info.raw_offset = read_double_attribute(id, "raw_offset", where);
      info.raw_scale = read_double_attribute(id, "raw_scale", where);
      info.range_min = read_double_attribute(id, "range_min", where);
      info.range_max = read_double_attribute(id, "range_max", where);
      info.unit = read_text_attribute(id, "unit", where);
      info.calibration_id = read_text_attribute(id, "calibration_id", where);
      if (has_attribute(id, "geometry_calibration_id")) {
        info.geometry_calibration_id = read_text_attribute(id, "geometry_calibration_id", where);
      }
      info.sample_rate_hz = read_double_attribute(id, "sample_rate_hz", where);
      info.first_sample_time_s = read_double_attribute(id, "first_sample_time_s", where);
      if (!(info.sample_rate_hz >= 0) || !std::isfinite(info.sample_rate_hz)) {
        throw Failure(where + ": sample_rate_hz must be >= 0");
      }

      Channel channel;
      if (!has_link(id, "raw")) throw Failure(where + " lacks dataset raw");
      channel.raw = open_dataset(id, "raw");
      channel.count = dataset_length(channel.raw.get(), where + "/raw");
      if (info.sample_rate_hz == 0) {
        if (!has_link(id, "time_s")) {
          throw Failure(where + " lacks dataset time_s (sample_rate_hz is 0: explicit times)");
        }
        channel.time = open_dataset(id, "time_s");
        if (dataset_length(channel.time.get(), where + "/time_s") != channel.count) {
          throw Failure(where + ": time_s and raw differ in length");
        }
        if (channel.count > 0) {
          read_range(channel.time.get(), H5T_NATIVE_DOUBLE, 0, 1, &channel.first_time,
                     where + "/time_s");
          read_range(channel.time.get(), H5T_NATIVE_DOUBLE, channel.count - 1, 1,
                     &channel.last_time, where + "/time_s");
        }
      } else {
        channel.first_time = info.first_sample_time_s;
        channel.last_time = uniform_time(info, channel.count == 0 ? 0 : channel.count - 1);
      }
      infos.push_back(std::move(info));
      channels.push_back(std::move(channel));
    }
  }

  static double uniform_time(const ChannelInfo& info, hsize_t index) {
    return info.first_sample_time_s + static_cast<double>(index) / info.sample_rate_hz;
  }

  std::vector<std::string> read_texts(hid_t group, const std::string& name, hsize_t count) {
    const std::string where = "/events/" + name;
    const Handle dataset = open_dataset(group, name);
    if (dataset_length(dataset.get(), where) != count) {
      throw Failure(where + " and /events/time_s differ in length");
    }
    std::vector<std::string> texts;
    texts.reserve(count);
    if (count == 0) return texts;
    const Handle type = text_type();
    std::vector<char*> pointers(count, nullptr);
    read_range(dataset.get(), type.get(), 0, count, pointers.data(), where);
    for (char* pointer : pointers) {
      texts.emplace_back(pointer ? pointer : "");
      H5free_memory(pointer);
    }
    return texts;
  }

  void load_events() {
    const Handle group = open_group(file.get(), "events");
    for (const char* name : {"time_s", "kind", "channel", "detail"}) {
      if (!has_link(group.get(), name)) throw Failure(std::string("/events lacks dataset ") + name);
    }
    const Handle time = open_dataset(group.get(), "time_s");
    const hsize_t count = dataset_length(time.get(), "/events/time_s");
    std::vector<double> times(count);
    read_range(time.get(), H5T_NATIVE_DOUBLE, 0, count, times.data(), "/events/time_s");
    const std::vector<std::string> kinds = read_texts(group.get(), "kind", count);
    const std::vector<std::string> names = read_texts(group.get(), "channel", count);
    const std::vector<std::string> details = read_texts(group.get(), "detail", count);
    events.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      events[i] = SessionEvent{
          .time_s = times[i], .kind = kinds[i], .channel = names[i], .detail = details[i]};
    }
  }

  void load_calibrations() {
    const Handle group = open_group(file.get(), "calibrations");
    for (const std::string& id : link_names(group.get())) {
      const std::string where = "/calibrations/" + id;
      const Handle g = open_group(group.get(), id);
      const std::string json = read_text_attribute(g.get(), "record", where);
      CalibrationRecord record;
      try {
        record = calibration_record_from_json(json, where);
      } catch (const std::runtime_error& error) {
        throw Failure(error.what());
      }
      if (record.id != id) throw Failure(where + ": the record's id is " + in_quotes(record.id));
      calibrations.push_back(std::move(record));
    }
  }

  ChannelSlice read(const std::string& name, double start_s, double end_s) const {
    const std::size_t index = index_of(name);
    if (std::isnan(start_s) || std::isnan(end_s)) {
      throw std::invalid_argument(prefix + "read " + name + ": start_s and end_s must not be NaN");
    }
    const ChannelInfo& info = infos[index];
    const Channel& channel = channels[index];
    const hsize_t count = channel.count;
    ChannelSlice slice;
    hsize_t first = 0, last = 0;  // [first, last)
    std::vector<double> all_times;
    auto check_size = [&](hsize_t samples, const char* dataset) {
      if (samples > kMaxReadSamples) {
        throw Failure("/channels/" + name + "/" + dataset + ": " + std::to_string(samples) +
                      " samples to read at once; at most " + std::to_string(kMaxReadSamples) +
                      " are (read a shorter time range)");
      }
    };
    if (channel.time) {
      check_size(count, "time_s");
      all_times.resize(count);
      read_range(channel.time.get(), H5T_NATIVE_DOUBLE, 0, count, all_times.data(),
                 "/channels/" + name + "/time_s");
      // The writer keeps them finite and increasing; a file made elsewhere may not.
      for (hsize_t i = 0; i < count; ++i) {
        if (!std::isfinite(all_times[i]) || (i > 0 && !(all_times[i] > all_times[i - 1]))) {
          throw Failure("/channels/" + name + "/time_s: sample " + std::to_string(i) + " (" +
                        format_time(all_times[i]) + " s) is " +
                        (std::isfinite(all_times[i])
                             ? "not after the one before (" + format_time(all_times[i - 1]) + " s)"
                             : "not finite") +
                        "; times must be finite and increasing");
        }
      }
      first = static_cast<hsize_t>(std::lower_bound(all_times.begin(), all_times.end(), start_s) -
                                   all_times.begin());
      last = static_cast<hsize_t>(std::upper_bound(all_times.begin(), all_times.end(), end_s) -
                                  all_times.begin());
    } else {
      // An estimate from the clock, then corrected against the very times returned.
      auto estimate = [&](double t) -> hsize_t {
        const double position = (t - info.first_sample_time_s) * info.sample_rate_hz;
        if (!(position > 0)) return 0;
        if (position >= static_cast<double>(count)) return count;
        return static_cast<hsize_t>(position);
      };
      auto time = [&](hsize_t i) { return uniform_time(info, i); };
      first = estimate(start_s);
      while (first > 0 && time(first - 1) >= start_s) --first;
      while (first < count && time(first) < start_s) ++first;
      last = estimate(end_s);
      while (last > 0 && time(last - 1) > end_s) --last;
      while (last < count && time(last) <= end_s) ++last;
    }
    slice.first_index = first;
    if (last <= first) return slice;
    const hsize_t size = last - first;
    check_size(size, "raw");
    slice.raw.resize(size);
    read_range(channel.raw.get(), H5T_NATIVE_DOUBLE, first, size, slice.raw.data(),
               "/channels/" + name + "/raw");
    if (channel.time) {
      slice.time_s.assign(all_times.begin() + static_cast<std::ptrdiff_t>(first),
                          all_times.begin() + static_cast<std::ptrdiff_t>(last));
    } else {
      slice.time_s.resize(size);
      for (hsize_t i = 0; i < size; ++i) slice.time_s[i] = uniform_time(info, first + i);
    }
    return slice;
  }

  std::vector<double> physical(const std::string& name, const ChannelSlice& slice) const {
    const ChannelInfo& info = infos[index_of(name)];
    std::vector<double> values(slice.raw.size());
    const CalibrationRecord* record = nullptr;
    if (!info.calibration_id.empty()) {
      for (const CalibrationRecord& candidate : calibrations) {
        if (candidate.id == info.calibration_id) record = &candidate;
      }
      if (!record) {
        throw SessionError(prefix + "channel " + name + " uses calibration record " +
                           info.calibration_id + ", which is not in the session");
      }
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (is_lost_sample(info, slice.raw[i])) {
        values[i] = std::numeric_limits<double>::quiet_NaN();
        continue;
      }
      const double signal = info.raw_offset + info.raw_scale * slice.raw[i];
      values[i] = record ? record->apply(signal) : signal;
    }
    return values;
  }

  Handle group_at(const std::string& group) const {
    const std::vector<std::string> parts = split_group_path(group);
    if (parts.empty()) throw Failure("no group " + in_quotes(group));
    Handle current = open_group(file.get(), "/");
    for (const std::string& part : parts) {
      if (!has_link(current.get(), part)) throw Failure("no group " + group);
      H5O_info_t info;
      check(H5Oget_info_by_name(current.get(), part.c_str(), &info, H5P_DEFAULT),
            "cannot look up " + group);
      if (info.type != H5O_TYPE_GROUP) throw Failure(group + " is not a group");
      current = open_group(current.get(), part);
    }
    return current;
  }
};

SessionReader::SessionReader(const fs::path& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->prefix = path.string() + ": ";
  impl_->guarded([&] { impl_->open(); });
}

SessionReader::~SessionReader() = default;
SessionReader::SessionReader(SessionReader&&) noexcept = default;
SessionReader& SessionReader::operator=(SessionReader&&) noexcept = default;

const fs::path& SessionReader::path() const {
  return impl_->path;
}
const SessionMetadata& SessionReader::metadata() const {
  return impl_->metadata;
}
const std::vector<ChannelInfo>& SessionReader::channels() const {
  return impl_->infos;
}

const ChannelInfo& SessionReader::channel(const std::string& name) const {
  return impl_->infos[impl_->index_of(name)];
}

std::size_t SessionReader::sample_count(const std::string& channel) const {
  return impl_->channels[impl_->index_of(channel)].count;
}

double SessionReader::start_time_s() const {
  bool any = false;
  double start = 0.0;
  for (const Impl::Channel& channel : impl_->channels) {
    if (channel.count == 0) continue;
    start = any ? std::min(start, channel.first_time) : channel.first_time;
    any = true;
  }
  return start;
}

double SessionReader::end_time_s() const {
  bool any = false;
  double end = 0.0;
  for (const Impl::Channel& channel : impl_->channels) {
    if (channel.count == 0) continue;
    end = any ? std::max(end, channel.last_time) : channel.last_time;
    any = true;
  }
  return end;
}

std::vector<SessionEvent> SessionReader::events() const {
  return impl_->events;
}

std::vector<CalibrationRecord> SessionReader::calibrations() const {
  return impl_->calibrations;
}

ChannelSlice SessionReader::read(const std::string& channel, double start_s, double end_s) const {
  return impl_->guarded([&] { return impl_->read(channel, start_s, end_s); });
}

std::vector<LostRun> lost_runs(const ChannelInfo& channel, const ChannelSlice& slice) {
  std::vector<LostRun> runs;
  for (std::size_t i = 0; i < slice.raw.size(); ++i) {
    if (!is_lost_sample(channel, slice.raw[i])) continue;
    if (!runs.empty() && runs.back().first_index + runs.back().count == slice.first_index + i) {
      ++runs.back().count;
      runs.back().last_time_s = slice.time_s[i];
    } else {
      runs.push_back({slice.first_index + i, 1, slice.time_s[i], slice.time_s[i]});
    }
  }
  return runs;
}

std::vector<double> SessionReader::physical(const std::string& channel,
                                            const ChannelSlice& slice) const {
  return impl_->physical(channel, slice);
}

std::vector<std::string> SessionReader::group_datasets(const std::string& group) const {
  return impl_->guarded([&] {
    const Handle g = impl_->group_at(group);
    std::vector<std::string> names;
    for (const std::string& name : link_names(g.get())) {
      H5O_info_t info;
      check(H5Oget_info_by_name(g.get(), name.c_str(), &info, H5P_DEFAULT),
            "cannot look up " + group + "/" + name);
      if (info.type == H5O_TYPE_DATASET) names.push_back(name);
    }
    return names;
  });
}

std::vector<double> SessionReader::read_group_dataset(const std::string& group,
                                                      const std::string& name) const {
  return impl_->guarded([&] {
    const Handle g = impl_->group_at(group);
    if (!valid_link_name(name) || !has_link(g.get(), name)) {
      throw Failure("group " + group + " has no dataset " + in_quotes(name));
    }
    const std::string where = group + "/" + name;
    const Handle dataset = open_dataset(g.get(), name);
    const Handle type = checked(H5Dget_type(dataset.get()), H5Tclose, "cannot read " + where);
    const H5T_class_t type_class = H5Tget_class(type.get());
    if (type_class != H5T_FLOAT && type_class != H5T_INTEGER) {
      throw Failure(where + " does not hold numbers");
    }
    const hsize_t count = dataset_length(dataset.get(), where);
    std::vector<double> values(count);
    if (count > 0) {
      check(H5Dread(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
            "cannot read " + where);
    }
    return values;
  });
}

std::string SessionReader::read_group_attribute(const std::string& group,
                                                const std::string& name) const {
  return impl_->guarded([&] {
    const Handle g = impl_->group_at(group);
    if (!has_attribute(g.get(), name)) {
      throw Failure("group " + group + " has no attribute " + in_quotes(name));
    }
    return read_text_attribute(g.get(), name, group);
  });
}

// ---------------------------------------------------------------------------------------
// Applying a record to an existing session

std::string apply_calibration(const fs::path& path, const std::string& channel,
                              const CalibrationRecord& record, const std::string& note) {
  const std::string prefix = path.string() + ": ";
  // A geometry record corrects the load cell's calibrated force; it does not replace the
  // cell's own record, so it has an attribute of its own.
  const bool geometry = record.sensor_kind == "geometry";
  const char* attribute = geometry ? "geometry_calibration_id" : "calibration_id";
  std::string previous;
  {
    // The reader checks the whole file and the channel first.
    const SessionReader reader(path);
    const ChannelInfo& info = reader.channel(channel);
    if (geometry && info.sensor_kind != "load_cell") {
      throw SessionError(prefix + "channel " + channel + " is a " + info.sensor_kind +
                         "; geometry record " + record.id + " applies to a load cell");
    }
    previous = geometry ? info.geometry_calibration_id : info.calibration_id;
    if (std::string problem = record.validate(); !problem.empty()) {
      throw SessionError(prefix + problem);
    }
    if (!valid_link_name(record.id)) {
      throw SessionError(prefix + "calibration record id " + in_quotes(record.id) +
                         " cannot name an HDF5 group (no /)");
    }
    if (!info.unit.empty() && !record.unit.empty() && info.unit != record.unit) {
      throw SessionError(prefix + "channel " + channel + " has unit " + in_quotes(info.unit) +
                         " but calibration record " + record.id + " gives " +
                         in_quotes(record.unit));
    }
    for (const CalibrationRecord& known : reader.calibrations()) {
      if (known.id == record.id && to_json(known) != to_json(record)) {
        throw SessionError(prefix + "the session already holds a different calibration record " +
                           record.id + " (records are never changed: make a new version)");
      }
    }
  }
  const Hdf5Quiet quiet;
  try {
    const Handle file = checked(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose,
                                "cannot open for writing");
    const Handle calibrations = open_group(file.get(), "calibrations");
    if (!has_link(calibrations.get(), record.id)) {
      write_record_group(calibrations.get(), record, to_json(record));
    }
    const Handle group = open_group(file.get(), "/channels/" + channel);
    if (has_attribute(group.get(), attribute)) {
      check(H5Adelete(group.get(), attribute), "cannot change /channels/" + channel);
    }
    write_text_attribute(group.get(), attribute, record.id);

    // One more event, at the end of the four parallel datasets.
    const Handle events = open_group(file.get(), "events");
    const Handle time = open_dataset(events.get(), "time_s");
    const Handle kind = open_dataset(events.get(), "kind");
    const Handle event_channel = open_dataset(events.get(), "channel");
    const Handle detail = open_dataset(events.get(), "detail");
    const hsize_t at = dataset_length(time.get(), "/events/time_s");
    const double zero = 0.0;
    const std::string detail_text = "applied " + record.id + " (was " +
                                    (previous.empty() ? "none" : previous) + ")" +
                                    (note.empty() ? "" : "; " + note);
    const char* kind_text = "calibration";
    const char* channel_text = channel.c_str();
    const char* detail_pointer = detail_text.c_str();
    const Handle text = text_type();
    write_range(time.get(), H5T_NATIVE_DOUBLE, at, 1, &zero, "/events/time_s");
    write_range(kind.get(), text.get(), at, 1, &kind_text, "/events/kind");
    write_range(event_channel.get(), text.get(), at, 1, &channel_text, "/events/channel");
    write_range(detail.get(), text.get(), at, 1, &detail_pointer, "/events/detail");
  } catch (const Failure& failure) {
    throw SessionError(prefix + failure.what());
  }
  return previous;
}

}  // namespace doorbench
