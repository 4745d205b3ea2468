// Session files in HDF5 through the C API: the writer. The layout is in
// docs/session-format.md; keep that page, this file and session_reader.cpp in step.
#include <algorithm>
#include <cmath>
#include <cstdio>
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
// Options

std::string SessionWriterOptions::validate() const {
  if (chunk_samples < 1 || chunk_samples > kMaxChunkSamples) {
    return "session chunk_samples must be 1 to " + std::to_string(kMaxChunkSamples) + ", not " +
           std::to_string(chunk_samples);
  }
  if (deflate_level < 0 || deflate_level > 9) {
    return "session deflate_level must be 0 (no compression) to 9, not " +
           std::to_string(deflate_level);
  }
  return "";
}

// ---------------------------------------------------------------------------------------
// Writer

struct SessionWriter::Impl {
  struct Channel {
    ChannelInfo info;
    bool timed = false;  // explicit times (sample_rate_hz == 0)
    Handle group, raw, time;
    std::vector<std::int32_t> counts;  // the write buffer: one chunk, allocated on first use
    std::vector<double> values, times;
    std::size_t buffered = 0;  // samples in the buffer
    hsize_t written = 0;       // samples in the file
    double last_time = 0.0;    // of the latest appended sample (timed channels)
    bool calibration_known = false;
  };

  fs::path path;
  std::string prefix;  // "PATH: "
  SessionWriterOptions options;
  Handle file, channels_group, calibrations_group;
  Handle event_time, event_kind, event_channel, event_detail;
  std::vector<Channel> channels;
  std::vector<std::pair<std::string, std::string>> calibrations;  // id, JSON
  std::vector<SessionEvent> events;                               // buffered, up to kEventChunk
  hsize_t events_written = 0;
  bool closed = false;

  [[noreturn]] void misuse(const std::string& what) const {
    throw std::invalid_argument(prefix + what);
  }

  // Runs `body` with HDF5 quiet; internal failures become SessionErrors naming the file.
  template <class Body>
  auto guarded(Body&& body) {
    const Hdf5Quiet quiet;
    if (closed) throw std::logic_error(prefix + "the session writer is already closed");
    try {
      return body();
    } catch (const Failure& failure) {
      throw SessionError(prefix + failure.what());
    }
  }

  void create(const SessionMetadata& metadata) {
    const Handle fapl = checked(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "cannot create the file");
    // HDF5's metadata cache keeps every chunk-index (B-tree) node of a recording until it
    // reaches its size, 2 MB by default, counted on disk: in memory a node is about 7x
    // larger, so a long recording would grow to ~20 MB. Appending touches only the newest
    // nodes, so a small fixed cache bounds memory without slowing writes.
    H5AC_cache_config_t cache;
    cache.version = H5AC__CURR_CACHE_CONFIG_VERSION;
    check(H5Pget_mdc_config(fapl.get(), &cache), "cannot create the file");
    cache.set_initial_size = true;
    cache.initial_size = kMetadataCacheBytes;
    cache.min_size = kMetadataCacheBytes;
    cache.max_size = kMetadataCacheBytes;
    cache.incr_mode = H5C_incr__off;
    cache.flash_incr_mode = H5C_flash_incr__off;
    cache.decr_mode = H5C_decr__off;
    check(H5Pset_mdc_config(fapl.get(), &cache), "cannot create the file");
    // EXCL: even if the file appeared since the check in the constructor, keep it.
    file = checked(H5Fcreate(path.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, fapl.get()), H5Fclose,
                   "cannot create the file");
    const hid_t root = file.get();
    write_text_attribute(root, "format", kFormatName);
    write_int_attribute(root, "format_version", kSessionFormatVersion);

    const Handle meta = make_group(root, "metadata");
    write_text_attribute(meta.get(), "rig_name", metadata.rig_name);
    write_text_attribute(meta.get(), "operator", metadata.operator_name);
    write_text_attribute(meta.get(), "product_id", metadata.product_id);
    write_text_attribute(meta.get(), "start_time_utc", metadata.start_time_utc);
    write_text_attribute(meta.get(), "software_version", metadata.software_version);
    write_text_attribute(meta.get(), "notes", metadata.notes);
    {
      const Handle type = text_type();
      const Handle dataset =
          checked(H5Dcreate2(meta.get(), "rig_definition", type.get(), scalar_space().get(),
                             H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                  H5Dclose, "cannot create /metadata/rig_definition");
      const char* pointer = metadata.rig_definition.c_str();
      check(H5Dwrite(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &pointer),
            "cannot write /metadata/rig_definition");
    }

    channels_group = make_group(root, "channels", true);
    calibrations_group = make_group(root, "calibrations", true);
    const Handle events_group = make_group(root, "events");
    const Handle text = text_type();
    event_time = make_stream_dataset(events_group.get(), "time_s", H5T_IEEE_F64LE, kEventChunk, 0);
    event_kind = make_stream_dataset(events_group.get(), "kind", text.get(), kEventChunk, 0);
    event_channel = make_stream_dataset(events_group.get(), "channel", text.get(), kEventChunk, 0);
    event_detail = make_stream_dataset(events_group.get(), "detail", text.get(), kEventChunk, 0);
  }

  Channel& channel_at(int index, const char* operation) {
    if (index < 0 || static_cast<std::size_t>(index) >= channels.size()) {
      misuse(std::string(operation) + ": no channel with index " + std::to_string(index) + " (" +
             std::to_string(channels.size()) + " channels)");
    }
    return channels[static_cast<std::size_t>(index)];
  }

  const std::string* calibration_json(const std::string& id) const {
    for (const auto& [known_id, json] : calibrations) {
      if (known_id == id) return &json;
    }
    return nullptr;
  }

  // A channel's calibration record must be in the session before its first sample.
  void require_calibration(Channel& channel) {
    if (channel.calibration_known || channel.info.calibration_id.empty()) return;
    if (!calibration_json(channel.info.calibration_id)) {
      misuse("channel " + channel.info.name + " uses calibration record " +
             channel.info.calibration_id +
             ", which is not in the session (add_calibration before its samples)");
    }
    channel.calibration_known = true;
  }

  void check_units(const ChannelInfo& info, const CalibrationRecord& record) const {
    if (!info.unit.empty() && info.unit != record.unit) {
      misuse("channel " + info.name + " has unit " + in_quotes(info.unit) +
             " but its calibration record " + record.id + " gives " + in_quotes(record.unit));
    }
  }

  int add_channel(const ChannelInfo& info) {
    const std::string& name = info.name;
    if (!valid_channel_name(name)) {
      misuse("channel name " + in_quotes(name) + " must be letters, digits and _ only");
    }
    for (const Channel& existing : channels) {
      if (existing.info.name == name) misuse("channel " + name + " is added twice");
    }
    const std::string where = "channel " + name + ": ";
    if (!std::isfinite(info.sample_rate_hz) || info.sample_rate_hz < 0) {
      misuse(where + "sample_rate_hz must be > 0, or 0 for explicit times");
    }
    if (!std::isfinite(info.first_sample_time_s))
      misuse(where + "first_sample_time_s is not finite");
    if (!std::isfinite(info.raw_offset) || !std::isfinite(info.raw_scale)) {
      misuse(where + "raw_offset and raw_scale must be finite");
    }
    if (std::isnan(info.range_min) || std::isnan(info.range_max) ||
        !(info.range_min < info.range_max)) {
      misuse(where + "range_min must be below range_max");
    }
    const bool timed = info.sample_rate_hz == 0;
    if (timed && info.raw_type == RawType::kCounts) {
      misuse(where + "explicit times (sample_rate_hz 0) need raw_type values, not counts");
    }
    if (!info.calibration_id.empty()) {
      if (const std::string* json = calibration_json(info.calibration_id)) {
        check_units(info, calibration_record_from_json(*json, "session"));
      }
    }

    Channel channel;
    channel.info = info;
    channel.timed = timed;
    channel.group = make_group(channels_group.get(), name);
    const hid_t g = channel.group.get();
    write_text_attribute(g, "sensor_kind", info.sensor_kind);
    write_text_attribute(g, "sensor_serial", info.sensor_serial);
    write_text_attribute(g, "raw_type", to_string(info.raw_type));
    write_text_attribute(g, "raw_unit", info.raw_unit);
    write_double_attribute(g, "raw_offset", info.raw_offset);
    write_double_attribute(g, "raw_scale", info.raw_scale);
    write_double_attribute(g, "range_min", info.range_min);
    write_double_attribute(g, "range_max", info.range_max);
    write_text_attribute(g, "unit", info.unit);
    write_text_attribute(g, "calibration_id", info.calibration_id);
    // Written only when set, so that sessions without a geometry record keep their layout.
    if (!info.geometry_calibration_id.empty()) {
      write_text_attribute(g, "geometry_calibration_id", info.geometry_calibration_id);
    }
    write_double_attribute(g, "sample_rate_hz", info.sample_rate_hz);
    write_double_attribute(g, "first_sample_time_s", info.first_sample_time_s);
    const hsize_t chunk = options.chunk_samples;
    channel.raw = make_stream_dataset(
        g, "raw", info.raw_type == RawType::kCounts ? H5T_STD_I32LE : H5T_IEEE_F64LE, chunk,
        options.deflate_level);
    if (timed) {
      channel.time = make_stream_dataset(g, "time_s", H5T_IEEE_F64LE, chunk, options.deflate_level);
    }
    channels.push_back(std::move(channel));
    return static_cast<int>(channels.size() - 1);
  }

  void add_calibration(const CalibrationRecord& record) {
    if (std::string problem = record.validate(); !problem.empty()) misuse(problem);
    if (!valid_link_name(record.id)) {
      misuse("calibration record id " + in_quotes(record.id) + " cannot name an HDF5 group (no /)");
    }
    std::string json = to_json(record);
    if (const std::string* known = calibration_json(record.id)) {
      if (*known == json) return;  // the same record again
      misuse("calibration record " + record.id + " is added twice with different contents");
    }
    for (const Channel& channel : channels) {
      if (channel.info.calibration_id == record.id) check_units(channel.info, record);
    }
    write_record_group(calibrations_group.get(), record, json);
    calibrations.emplace_back(record.id, std::move(json));
  }

  // Writes `count` samples (raw, and times for timed channels) at the end of the datasets.
  void write_block(Channel& channel, const void* raw, const double* times, std::size_t count) {
    const hid_t memory_type =
        channel.info.raw_type == RawType::kCounts ? H5T_NATIVE_INT32 : H5T_NATIVE_DOUBLE;
    const std::string where = "/channels/" + channel.info.name;
    write_range(channel.raw.get(), memory_type, channel.written, count, raw, where + "/raw");
    if (channel.timed) {
      write_range(channel.time.get(), H5T_NATIVE_DOUBLE, channel.written, count, times,
                  where + "/time_s");
    }
    channel.written += count;
  }

  void flush_buffer(Channel& channel) {
    if (channel.buffered == 0) return;
    const void* raw = channel.info.raw_type == RawType::kCounts
                          ? static_cast<const void*>(channel.counts.data())
                          : static_cast<const void*>(channel.values.data());
    write_block(channel, raw, channel.times.data(), channel.buffered);
    channel.buffered = 0;
  }

  // Streams samples through the channel's one-chunk buffer. Whole chunks that arrive
  // while the buffer is empty go to the file without a copy. Every write starts at a
  // chunk boundary, so each chunk is written once.
  template <class T>
  void stream(Channel& channel, std::vector<T>& buffer, const T* data, const double* times,
              std::size_t count) {
    const std::size_t chunk = options.chunk_samples;
    if (buffer.size() != chunk) {
      buffer.resize(chunk);
      if (channel.timed) channel.times.resize(chunk);
    }
    while (count > 0) {
      if (channel.buffered == 0 && count >= chunk) {
        const std::size_t whole = count - count % chunk;
        write_block(channel, data, times, whole);
        data += whole;
        if (times) times += whole;
        count -= whole;
        continue;
      }
      const std::size_t take = std::min(count, chunk - channel.buffered);
      std::copy_n(data, take, buffer.begin() + static_cast<std::ptrdiff_t>(channel.buffered));
      if (times) {
        std::copy_n(times, take,
                    channel.times.begin() + static_cast<std::ptrdiff_t>(channel.buffered));
        times += take;
      }
      channel.buffered += take;
      data += take;
      count -= take;
      if (channel.buffered == chunk) flush_buffer(channel);
    }
  }

  void check_kind(const Channel& channel, RawType type, bool timed, const char* operation) const {
    const std::string& name = channel.info.name;
    if (channel.timed != timed) {
      if (channel.timed) {
        misuse(std::string(operation) + ": channel " + name +
               " has explicit times (sample_rate_hz 0); use append_timed_values");
      }
      misuse(std::string(operation) + ": channel " + name + " has a uniform clock (" +
             format_number(channel.info.sample_rate_hz) + " Hz); use append_" +
             to_string(channel.info.raw_type));
    }
    if (channel.info.raw_type != type) {
      misuse(std::string(operation) + ": channel " + name + " holds " +
             to_string(channel.info.raw_type) + " (" +
             (channel.info.raw_type == RawType::kCounts ? "int32" : "float64") + "), not " +
             to_string(type));
    }
  }

  void append_counts(int index, std::span<const std::int32_t> counts) {
    Channel& channel = channel_at(index, "append_counts");
    check_kind(channel, RawType::kCounts, false, "append_counts");
    require_calibration(channel);
    stream(channel, channel.counts, counts.data(), nullptr, counts.size());
  }

  void append_values(int index, std::span<const double> values) {
    Channel& channel = channel_at(index, "append_values");
    check_kind(channel, RawType::kValues, false, "append_values");
    require_calibration(channel);
    stream(channel, channel.values, values.data(), nullptr, values.size());
  }

  void append_timed_values(int index, std::span<const double> times,
                           std::span<const double> values) {
    Channel& channel = channel_at(index, "append_timed_values");
    check_kind(channel, RawType::kValues, true, "append_timed_values");
    const std::string& name = channel.info.name;
    if (times.size() != values.size()) {
      misuse("append_timed_values: channel " + name + ": " + std::to_string(times.size()) +
             " times for " + std::to_string(values.size()) + " values");
    }
    bool has_previous = channel.written + channel.buffered > 0;
    double previous = channel.last_time;
    for (std::size_t i = 0; i < times.size(); ++i) {
      const std::size_t sample = channel.written + channel.buffered + i;
      if (!std::isfinite(times[i])) {
        misuse("append_timed_values: channel " + name + ": time of sample " +
               std::to_string(sample) + " is not finite");
      }
      if (has_previous && !(times[i] > previous)) {
        misuse("append_timed_values: channel " + name +
               ": times must be strictly increasing, but sample " + std::to_string(sample) +
               " at " + format_number(times[i]) + " s follows " + format_number(previous) + " s");
      }
      previous = times[i];
      has_previous = true;
    }
    require_calibration(channel);
    stream(channel, channel.values, values.data(), times.data(), values.size());
    if (!times.empty()) channel.last_time = times.back();
  }

  void flush_events() {
    if (events.empty()) return;
    const std::size_t count = events.size();
    std::vector<double> times(count);
    std::vector<const char*> kinds(count), names(count), details(count);
    for (std::size_t i = 0; i < count; ++i) {
      times[i] = events[i].time_s;
      kinds[i] = events[i].kind.c_str();
      names[i] = events[i].channel.c_str();
      details[i] = events[i].detail.c_str();
    }
    const Handle text = text_type();
    write_range(event_time.get(), H5T_NATIVE_DOUBLE, events_written, count, times.data(),
                "/events/time_s");
    write_range(event_kind.get(), text.get(), events_written, count, kinds.data(), "/events/kind");
    write_range(event_channel.get(), text.get(), events_written, count, names.data(),
                "/events/channel");
    write_range(event_detail.get(), text.get(), events_written, count, details.data(),
                "/events/detail");
    events_written += count;
    events.clear();
  }

  void add_event(const SessionEvent& event) {
    if (!std::isfinite(event.time_s))
      misuse("event " + in_quotes(event.kind) + ": time is not finite");
    if (event.kind.empty()) misuse("event at " + format_number(event.time_s) + " s: kind is empty");
    if (!event.channel.empty() &&
        std::none_of(channels.begin(), channels.end(),
                     [&](const Channel& c) { return c.info.name == event.channel; })) {
      misuse("event " + in_quotes(event.kind) + " at " + format_number(event.time_s) +
             " s names channel " + event.channel + ", which is not in the session");
    }
    if (events.capacity() == 0) events.reserve(kEventChunk);
    events.push_back(event);
    if (events.size() == kEventChunk) flush_events();
  }

  // Opens `group`, creating it and every missing parent.
  Handle open_or_create_group(const std::string& group) {
    const std::vector<std::string> parts = split_group_path(group);
    if (parts.empty()) {
      misuse("group " + in_quotes(group) +
             " must be names separated by / (no leading, trailing or double /, no . or ..)");
    }
    if (std::find(std::begin(kReservedGroups), std::end(kReservedGroups), parts.front()) !=
        std::end(kReservedGroups)) {
      misuse("group " + group + " is inside /" + parts.front() +
             ", which the session writes itself");
    }
    Handle current = open_group(file.get(), "/");
    std::string so_far;
    for (const std::string& part : parts) {
      so_far += (so_far.empty() ? "" : "/") + part;
      if (has_link(current.get(), part)) {
        H5O_info_t info;
        check(H5Oget_info_by_name(current.get(), part.c_str(), &info, H5P_DEFAULT),
              "cannot look up " + so_far);
        if (info.type != H5O_TYPE_GROUP) misuse(so_far + " exists and is not a group");
        current = open_group(current.get(), part);
      } else {
        current = make_group(current.get(), part);
      }
    }
    return current;
  }

  void write_group_dataset(const std::string& group, const std::string& name,
                           std::span<const double> values) {
    if (!valid_link_name(name))
      misuse("group " + group + ": dataset name " + in_quotes(name) + " is unusable");
    const Handle g = open_or_create_group(group);
    if (has_link(g.get(), name)) misuse("group " + group + " already has " + name);
    const hsize_t size = values.size();
    const Handle dataset =
        checked(H5Dcreate2(g.get(), name.c_str(), H5T_IEEE_F64LE, simple_space(size, size).get(),
                           H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                H5Dclose, "cannot create dataset " + group + "/" + name);
    if (size > 0) {
      check(
          H5Dwrite(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
          "cannot write dataset " + group + "/" + name);
    }
  }

  void write_group_attribute(const std::string& group, const std::string& name,
                             const std::string& text) {
    if (!valid_link_name(name))
      misuse("group " + group + ": attribute name " + in_quotes(name) + " is unusable");
    const Handle g = open_or_create_group(group);
    if (has_attribute(g.get(), name)) misuse("group " + group + " already has attribute " + name);
    write_text_attribute(g.get(), name, text);
  }

  // Flushes and closes everything; the handles close even when a step fails.
  void finish() {
    closed = true;
    std::string first_failure;
    auto attempt = [&](auto&& step) {
      try {
        step();
      } catch (const std::exception& failure) {
        if (first_failure.empty()) first_failure = failure.what();
      }
    };
    for (Channel& channel : channels) {
      attempt([&] {
        require_calibration(channel);  // for channels that never got samples
      });
      attempt([&] { flush_buffer(channel); });
    }
    attempt([&] { flush_events(); });
    auto close_handle = [&](Handle& handle, const char* what) {
      if (handle.reset() < 0) {
        const std::string cause = hdf5_cause();
        if (first_failure.empty())
          first_failure = std::string("cannot close ") + what + " (HDF5: " + cause + ")";
      }
    };
    for (Channel& channel : channels) {
      close_handle(channel.raw, "a channel");
      close_handle(channel.time, "a channel");
      close_handle(channel.group, "a channel");
      std::vector<std::int32_t>().swap(channel.counts);
      std::vector<double>().swap(channel.values);
      std::vector<double>().swap(channel.times);
    }
    close_handle(event_time, "/events");
    close_handle(event_kind, "/events");
    close_handle(event_channel, "/events");
    close_handle(event_detail, "/events");
    close_handle(channels_group, "/channels");
    close_handle(calibrations_group, "/calibrations");
    close_handle(file, "the file");
    if (!first_failure.empty()) {
      // Misuse messages already carry the path.
      if (first_failure.rfind(prefix, 0) == 0) throw SessionError(first_failure);
      throw SessionError(prefix + first_failure);
    }
  }
};

SessionWriter::SessionWriter(const fs::path& path, const SessionMetadata& metadata,
                             const SessionWriterOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->prefix = path.string() + ": ";
  impl_->options = options;
  if (std::string problem = options.validate(); !problem.empty()) impl_->misuse(problem);
  std::error_code error;
  if (fs::exists(path, error) || fs::is_symlink(path, error)) {
    throw SessionError(impl_->prefix + "already exists (sessions are never overwritten)");
  }
  if (options.deflate_level > 0 && H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0) {
    throw SessionError(impl_->prefix + "this HDF5 library has no gzip (deflate) filter");
  }
  try {
    impl_->guarded([&] { impl_->create(metadata); });
  } catch (...) {
    // Whatever was created is incomplete: close it and remove it.
    const bool created = static_cast<bool>(impl_->file);
    impl_->closed = true;
    impl_->event_time.reset();
    impl_->event_kind.reset();
    impl_->event_channel.reset();
    impl_->event_detail.reset();
    impl_->channels_group.reset();
    impl_->calibrations_group.reset();
    impl_->file.reset();
    if (created) fs::remove(path, error);
    throw;
  }
}

SessionWriter::~SessionWriter() {
  if (!impl_ || impl_->closed) return;
  try {
    close();
  } catch (const std::exception& failure) {
    std::fprintf(stderr, "doorbench: closing the session failed: %s\n", failure.what());
  } catch (...) {
    std::fprintf(stderr, "doorbench: closing the session %s failed\n", impl_->path.c_str());
  }
}

int SessionWriter::add_channel(const ChannelInfo& channel) {
  return impl_->guarded([&] { return impl_->add_channel(channel); });
}

void SessionWriter::add_calibration(const CalibrationRecord& record) {
  impl_->guarded([&] { impl_->add_calibration(record); });
}

void SessionWriter::append_counts(int channel, std::span<const std::int32_t> counts) {
  impl_->guarded([&] { impl_->append_counts(channel, counts); });
}

void SessionWriter::append_values(int channel, std::span<const double> values) {
  impl_->guarded([&] { impl_->append_values(channel, values); });
}

void SessionWriter::append_timed_values(int channel, std::span<const double> time_s,
                                        std::span<const double> values) {
  impl_->guarded([&] { impl_->append_timed_values(channel, time_s, values); });
}

void SessionWriter::add_event(const SessionEvent& event) {
  impl_->guarded([&] { impl_->add_event(event); });
}

void SessionWriter::write_group_dataset(const std::string& group, const std::string& name,
                                        std::span<const double> values) {
  impl_->guarded([&] { impl_->write_group_dataset(group, name, values); });
}

void SessionWriter::write_group_attribute(const std::string& group, const std::string& name,
                                          const std::string& text) {
  impl_->guarded([&] { impl_->write_group_attribute(group, name, text); });
}

void SessionWriter::close() {
  impl_->guarded([&] { impl_->finish(); });
}

}  // namespace doorbench
