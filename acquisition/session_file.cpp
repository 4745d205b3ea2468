// Session files in HDF5 through the C API. The layout is in docs/session-format.md; keep
// that page and this file in step.
//
// Every HDF5 identifier lives in a Handle (RAII). HDF5's automatic error printing is
// switched off while doorbench calls into it (Hdf5Quiet); failures become SessionErrors
// whose text is `PATH: what failed (HDF5: the innermost cause)`.
#include "acquisition/session_file.h"

#include <hdf5.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <utility>

#include "acquisition/printable.h"

namespace doorbench {

namespace fs = std::filesystem;
using calibration::CalibrationRecord;

namespace {

constexpr const char* kFormatName = "doorbench-session";
constexpr hsize_t kEventChunk = 1024;                    // events per chunk and per write
constexpr std::size_t kMaxChunkSamples = 1u << 24;       // 128 MiB of float64 per chunk
constexpr std::size_t kMetadataCacheBytes = 256u << 10;  // the writer's HDF5 metadata cache
const char* const kReservedGroups[] = {"metadata", "channels", "calibrations", "events"};

// ---------------------------------------------------------------------------------------
// HDF5 plumbing

// A failure inside this file; the public functions prefix the session's path.
class Failure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A time as it reads back (shortest round-trip form; "nan", "inf").
std::string format_time(double t) {
  char text[32];
  const auto result = std::to_chars(std::begin(text), std::end(text), t);
  return std::string(text, result.ptr);
}

// Switches HDF5's automatic error printing off for the current thread while it lives.
class Hdf5Quiet {
 public:
  Hdf5Quiet() {
    H5Eget_auto2(H5E_DEFAULT, &function_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~Hdf5Quiet() { H5Eset_auto2(H5E_DEFAULT, function_, data_); }
  Hdf5Quiet(const Hdf5Quiet&) = delete;
  Hdf5Quiet& operator=(const Hdf5Quiet&) = delete;

 private:
  H5E_auto2_t function_ = nullptr;
  void* data_ = nullptr;
};

// The innermost message on HDF5's error stack (the cause), then clears the stack.
std::string hdf5_cause() {
  std::string cause;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned, const H5E_error2_t* error, void* data) -> herr_t {
        if (error->desc && *error->desc) *static_cast<std::string*>(data) = error->desc;
        return 0;
      },
      &cause);
  H5Eclear2(H5E_DEFAULT);
  return cause;
}

[[noreturn]] void fail(const std::string& what) {
  const std::string cause = hdf5_cause();
  throw Failure(cause.empty() ? what : what + " (HDF5: " + cause + ")");
}

void check(herr_t status, const std::string& what) {
  if (status < 0) fail(what);
}

// Owns one HDF5 identifier and closes it with the matching H5?close.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Handle() { reset(); }
  Handle(Handle&& other) noexcept
      : id_(std::exchange(other.id_, H5I_INVALID_HID)), closer_(other.closer_) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
      closer_ = other.closer_;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  explicit operator bool() const { return id_ >= 0; }
  // Closes now; returns the close function's status (negative on failure).
  herr_t reset() {
    herr_t status = 0;
    if (id_ >= 0) status = closer_(std::exchange(id_, H5I_INVALID_HID));
    return status;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

Handle checked(hid_t id, Handle::Closer closer, const std::string& what) {
  if (id < 0) fail(what);
  return Handle(id, closer);
}

Handle make_group(hid_t parent, const std::string& name, bool track_order = false) {
  Handle gcpl = checked(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, "cannot create a property list");
  if (track_order) {
    check(H5Pset_link_creation_order(gcpl.get(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED),
          "cannot track the order of group " + name);
  }
  return checked(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose,
                 "cannot create group " + name);
}

Handle open_group(hid_t parent, const std::string& name) {
  return checked(H5Gopen2(parent, name.c_str(), H5P_DEFAULT), H5Gclose,
                 "cannot open group " + name);
}

Handle open_dataset(hid_t parent, const std::string& name) {
  return checked(H5Dopen2(parent, name.c_str(), H5P_DEFAULT), H5Dclose,
                 "cannot open dataset " + name);
}

bool has_link(hid_t parent, const std::string& name) {
  const htri_t exists = H5Lexists(parent, name.c_str(), H5P_DEFAULT);
  if (exists < 0) fail("cannot look up " + name);
  return exists > 0;
}

bool has_attribute(hid_t object, const std::string& name) {
  const htri_t exists = H5Aexists(object, name.c_str());
  if (exists < 0) fail("cannot look up attribute " + name);
  return exists > 0;
}

// Variable-length UTF-8 strings: the type of every text in a session.
Handle text_type() {
  Handle type = checked(H5Tcopy(H5T_C_S1), H5Tclose, "cannot make the string type");
  check(H5Tset_size(type.get(), H5T_VARIABLE), "cannot make the string type");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "cannot make the string type");
  return type;
}

Handle scalar_space() {
  return checked(H5Screate(H5S_SCALAR), H5Sclose, "cannot make a dataspace");
}

Handle simple_space(hsize_t size, hsize_t max_size) {
  return checked(H5Screate_simple(1, &size, &max_size), H5Sclose, "cannot make a dataspace");
}

void write_attribute(hid_t object, const std::string& name, hid_t file_type, hid_t memory_type,
                     hid_t space, const void* data) {
  Handle attribute =
      checked(H5Acreate2(object, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT),
              H5Aclose, "cannot create attribute " + name);
  check(H5Awrite(attribute.get(), memory_type, data), "cannot write attribute " + name);
}

void write_text_attribute(hid_t object, const std::string& name, const std::string& text) {
  const Handle type = text_type();
  const char* pointer = text.c_str();
  write_attribute(object, name, type.get(), type.get(), scalar_space().get(), &pointer);
}

void write_double_attribute(hid_t object, const std::string& name, double value) {
  write_attribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, scalar_space().get(), &value);
}

void write_int_attribute(hid_t object, const std::string& name, int value) {
  write_attribute(object, name, H5T_STD_I32LE, H5T_NATIVE_INT, scalar_space().get(), &value);
}

void write_doubles_attribute(hid_t object, const std::string& name,
                             const std::vector<double>& values) {
  const hsize_t size = values.size();
  write_attribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, simple_space(size, size).get(),
                  values.data());
}

// Reads a string of either kind (variable- or fixed-length) from an attribute or dataset.
template <class Read>
std::string read_text(hid_t stored_type, hid_t space, const std::string& what, Read&& read) {
  if (H5Tget_class(stored_type) != H5T_STRING) throw Failure(what + " is not text");
  if (H5Sget_simple_extent_npoints(space) != 1) throw Failure(what + " is not a single text");
  const htri_t variable = H5Tis_variable_str(stored_type);
  if (variable < 0) fail("cannot read " + what);
  if (variable > 0) {
    const Handle type = text_type();
    char* pointer = nullptr;
    check(read(type.get(), &pointer), "cannot read " + what);
    std::string text = pointer ? pointer : "";
    H5free_memory(pointer);
    return text;
  }
  const std::size_t size = H5Tget_size(stored_type);
  Handle type = checked(H5Tcopy(H5T_C_S1), H5Tclose, "cannot make the string type");
  check(H5Tset_size(type.get(), size + 1), "cannot make the string type");
  check(H5Tset_strpad(type.get(), H5T_STR_NULLTERM), "cannot make the string type");
  std::string buffer(size + 1, '\0');
  check(read(type.get(), buffer.data()), "cannot read " + what);
  buffer.resize(std::char_traits<char>::length(buffer.c_str()));
  return buffer;
}

Handle open_attribute(hid_t object, const std::string& name, const std::string& where) {
  if (!has_attribute(object, name)) throw Failure(where + " lacks attribute " + name);
  return checked(H5Aopen(object, name.c_str(), H5P_DEFAULT), H5Aclose,
                 "cannot open attribute " + where + " " + name);
}

std::string read_text_attribute(hid_t object, const std::string& name, const std::string& where) {
  const Handle attribute = open_attribute(object, name, where);
  const Handle type = checked(H5Aget_type(attribute.get()), H5Tclose, "cannot read " + name);
  const Handle space = checked(H5Aget_space(attribute.get()), H5Sclose, "cannot read " + name);
  return read_text(
      type.get(), space.get(), where + " attribute " + name,
      [&](hid_t memory_type, void* into) { return H5Aread(attribute.get(), memory_type, into); });
}

// Numeric attributes of any stored numeric type, converted by HDF5.
std::vector<double> read_doubles_attribute(hid_t object, const std::string& name,
                                           const std::string& where) {
  const Handle attribute = open_attribute(object, name, where);
  const Handle type = checked(H5Aget_type(attribute.get()), H5Tclose, "cannot read " + name);
  const H5T_class_t type_class = H5Tget_class(type.get());
  if (type_class != H5T_FLOAT && type_class != H5T_INTEGER) {
    throw Failure(where + " attribute " + name + " is not a number");
  }
  const Handle space = checked(H5Aget_space(attribute.get()), H5Sclose, "cannot read " + name);
  const hssize_t count = H5Sget_simple_extent_npoints(space.get());
  if (count < 0) fail("cannot read " + where + " attribute " + name);
  std::vector<double> values(static_cast<std::size_t>(count));
  if (count > 0) {
    check(H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, values.data()),
          "cannot read " + where + " attribute " + name);
  }
  return values;
}

double read_double_attribute(hid_t object, const std::string& name, const std::string& where) {
  const std::vector<double> values = read_doubles_attribute(object, name, where);
  if (values.size() != 1) throw Failure(where + " attribute " + name + " is not a single number");
  return values.front();
}

std::string read_text_dataset(hid_t parent, const std::string& name, const std::string& where) {
  if (!has_link(parent, name)) throw Failure(where + " lacks dataset " + name);
  const Handle dataset = open_dataset(parent, name);
  const Handle type = checked(H5Dget_type(dataset.get()), H5Tclose, "cannot read " + name);
  const Handle space = checked(H5Dget_space(dataset.get()), H5Sclose, "cannot read " + name);
  return read_text(type.get(), space.get(), where + "/" + name, [&](hid_t memory_type, void* into) {
    return H5Dread(dataset.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, into);
  });
}

// Names of the links in a group, in creation order when the group tracks it.
std::vector<std::string> link_names(hid_t group) {
  std::vector<std::string> names;
  const H5L_iterate_t collect = [](hid_t, const char* name, const H5L_info_t*, void* data) {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return herr_t{0};
  };
  hsize_t position = 0;
  if (H5Literate(group, H5_INDEX_CRT_ORDER, H5_ITER_INC, &position, collect, &names) >= 0) {
    return names;
  }
  H5Eclear2(H5E_DEFAULT);  // creation order not tracked: name order
  names.clear();
  position = 0;
  check(H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, &position, collect, &names),
        "cannot list a group");
  return names;
}

hsize_t dataset_length(hid_t dataset, const std::string& where) {
  const Handle space = checked(H5Dget_space(dataset), H5Sclose, "cannot read " + where);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) fail("cannot read " + where);
  if (rank == 0) return 1;
  if (rank != 1) throw Failure(where + " is not one-dimensional");
  hsize_t size = 0;
  check(H5Sget_simple_extent_dims(space.get(), &size, nullptr), "cannot read " + where);
  return size;
}

// Reads elements [first, first + count) of a 1-D dataset, converted to `memory_type`.
void read_range(hid_t dataset, hid_t memory_type, hsize_t first, hsize_t count, void* into,
                const std::string& where) {
  if (count == 0) return;
  const Handle file_space = checked(H5Dget_space(dataset), H5Sclose, "cannot read " + where);
  check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, &first, nullptr, &count, nullptr),
        "cannot select samples of " + where);
  const Handle memory_space = simple_space(count, count);
  check(H5Dread(dataset, memory_type, memory_space.get(), file_space.get(), H5P_DEFAULT, into),
        "cannot read " + where);
}

// Grows a 1-D dataset from `first` to `first + count` elements and writes them.
void write_range(hid_t dataset, hid_t memory_type, hsize_t first, hsize_t count, const void* data,
                 const std::string& where) {
  if (count == 0) return;
  const hsize_t new_size = first + count;
  check(H5Dset_extent(dataset, &new_size), "cannot extend " + where);
  const Handle file_space = checked(H5Dget_space(dataset), H5Sclose, "cannot write " + where);
  check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, &first, nullptr, &count, nullptr),
        "cannot select samples of " + where);
  const Handle memory_space = simple_space(count, count);
  check(H5Dwrite(dataset, memory_type, memory_space.get(), file_space.get(), H5P_DEFAULT, data),
        "cannot write " + where);
}

// An empty, chunked 1-D dataset of unlimited size. Whole chunks are written at once, so
// the chunk cache is off: chunks go straight to the file and memory stays bounded.
Handle make_stream_dataset(hid_t parent, const std::string& name, hid_t type, hsize_t chunk,
                           int deflate_level) {
  const bool is_text = H5Tget_class(type) == H5T_STRING;
  const Handle space = simple_space(0, H5S_UNLIMITED);
  const Handle dcpl = checked(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "cannot create " + name);
  check(H5Pset_chunk(dcpl.get(), 1, &chunk), "cannot chunk " + name);
  if (!is_text) {  // numbers: no fill value is written (every element is written once)
    check(H5Pset_fill_time(dcpl.get(), H5D_FILL_TIME_NEVER), "cannot create " + name);
  }
  if (deflate_level > 0) {  // byte shuffling first: counts compress far better
    check(H5Pset_shuffle(dcpl.get()), "cannot compress " + name);
    check(H5Pset_deflate(dcpl.get(), static_cast<unsigned>(deflate_level)),
          "cannot compress " + name);
  }
  const Handle dapl = checked(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose, "cannot create " + name);
  check(
      H5Pset_chunk_cache(dapl.get(), H5D_CHUNK_CACHE_NSLOTS_DEFAULT, 0, H5D_CHUNK_CACHE_W0_DEFAULT),
      "cannot create " + name);
  return checked(
      H5Dcreate2(parent, name.c_str(), type, space.get(), H5P_DEFAULT, dcpl.get(), dapl.get()),
      H5Dclose, "cannot create dataset " + name);
}

// ---------------------------------------------------------------------------------------
// Names and text

std::string in_quotes(const std::string& text) {
  return "\"" + text + "\"";
}

bool valid_channel_name(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

bool valid_link_name(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos;
}

// "results/fit-1" → {"results", "fit-1"}; empty when the path is unusable.
std::vector<std::string> split_group_path(const std::string& group) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t end = group.find('/', begin);
    std::string part = group.substr(begin, end == std::string::npos ? end : end - begin);
    if (!valid_link_name(part)) return {};
    parts.push_back(std::move(part));
    if (end == std::string::npos) return parts;
    begin = end + 1;
  }
}

const char* to_string(RawType type) {
  return type == RawType::kCounts ? "counts" : "values";
}

// The shortest text that reads back as the same double.
std::string number(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return std::string(text, result.ptr);
}

// /calibrations/<id>: the record's JSON (authoritative) and its fields as attributes.
void write_record_group(hid_t calibrations, const CalibrationRecord& record,
                        const std::string& json) {
  const Handle group = make_group(calibrations, record.id);
  const hid_t g = group.get();
  write_text_attribute(g, "record", json);
  write_int_attribute(g, "version", record.version);
  write_text_attribute(g, "sensor_kind", record.sensor_kind);
  write_text_attribute(g, "sensor_serial", record.sensor_serial);
  write_text_attribute(g, "input_unit", record.input_unit);
  write_text_attribute(g, "unit", record.unit);
  write_doubles_attribute(g, "coefficients", record.coefficients);
  write_double_attribute(g, "standard_uncertainty", record.standard_uncertainty);
  write_text_attribute(g, "method", record.method);
  write_text_attribute(g, "date_utc", record.date_utc);
  write_text_attribute(g, "operator", record.operator_name);
  write_text_attribute(g, "valid_until_utc", record.valid_until_utc);
  write_text_attribute(g, "notes", record.notes);
}

}  // namespace

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
        check_units(info, calibration::calibration_record_from_json(*json, "session"));
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
    std::string json = calibration::to_json(record);
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
             number(channel.info.sample_rate_hz) + " Hz); use append_" +
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
               " at " + number(times[i]) + " s follows " + number(previous) + " s");
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
    if (event.kind.empty()) misuse("event at " + number(event.time_s) + " s: kind is empty");
    if (!event.channel.empty() &&
        std::none_of(channels.begin(), channels.end(),
                     [&](const Channel& c) { return c.info.name == event.channel; })) {
      misuse("event " + in_quotes(event.kind) + " at " + number(event.time_s) +
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
      throw Failure("session format version " + number(version) + " is not valid");
    }
    if (version > kSessionFormatVersion) {
      throw Failure("session format version " + number(version) +
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
      events[i] = SessionEvent{times[i], kinds[i], names[i], details[i]};
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
        record = calibration::calibration_record_from_json(json, where);
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
                        (std::isfinite(all_times[i]) ? "not after the one before (" +
                                                           format_time(all_times[i - 1]) + " s)"
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
      if (known.id == record.id && calibration::to_json(known) != calibration::to_json(record)) {
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
      write_record_group(calibrations.get(), record, calibration::to_json(record));
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
