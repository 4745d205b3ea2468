#pragma once
// Internal to the session file's writer and reader (session_writer.cpp, session_reader.cpp):
// the HDF5 plumbing they share. Not for other code: the session's interface is
// acquisition/session_file.h.
//
// Every HDF5 identifier lives in a Handle (RAII). HDF5's automatic error printing is
// switched off while doorbench calls into it (Hdf5Quiet); failures are Failures, which the
// public functions turn into SessionErrors `PATH: what failed (HDF5: the innermost cause)`.
// Thread safety: as HDF5's (doorbench's HDF5 calls happen on one thread at a time).
#include <hdf5.h>

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/session_file.h"

namespace doorbench::session_hdf5 {

using doorbench::CalibrationRecord;

inline constexpr const char* kFormatName = "doorbench-session";
inline constexpr hsize_t kEventChunk = 1024;                    // events per chunk and per write
inline constexpr std::size_t kMaxChunkSamples = 1u << 24;       // 128 MiB of float64 per chunk
inline constexpr std::size_t kMetadataCacheBytes = 256u << 10;  // the writer's HDF5 metadata cache
inline const char* const kReservedGroups[] = {"metadata", "channels", "calibrations", "events"};

// ---------------------------------------------------------------------------------------
// HDF5 plumbing

// A failure inside this file; the public functions prefix the session's path.
class Failure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A time as it reads back (shortest round-trip form; "nan", "inf").
std::string format_time(double t);

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
std::string hdf5_cause();

[[noreturn]] void fail(const std::string& what);

void check(herr_t status, const std::string& what);

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

Handle checked(hid_t id, Handle::Closer closer, const std::string& what);

Handle make_group(hid_t parent, const std::string& name, bool track_order = false);

Handle open_group(hid_t parent, const std::string& name);

Handle open_dataset(hid_t parent, const std::string& name);

bool has_link(hid_t parent, const std::string& name);

bool has_attribute(hid_t object, const std::string& name);

// Variable-length UTF-8 strings: the type of every text in a session.
Handle text_type();

Handle scalar_space();

Handle simple_space(hsize_t size, hsize_t max_size);

void write_attribute(hid_t object, const std::string& name, hid_t file_type, hid_t memory_type,
                     hid_t space, const void* data);

void write_text_attribute(hid_t object, const std::string& name, const std::string& text);

void write_double_attribute(hid_t object, const std::string& name, double value);

void write_int_attribute(hid_t object, const std::string& name, int value);

void write_doubles_attribute(hid_t object, const std::string& name,
                             const std::vector<double>& values);

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

Handle open_attribute(hid_t object, const std::string& name, const std::string& where);

std::string read_text_attribute(hid_t object, const std::string& name, const std::string& where);

// Numeric attributes of any stored numeric type, converted by HDF5.
std::vector<double> read_doubles_attribute(hid_t object, const std::string& name,
                                           const std::string& where);

double read_double_attribute(hid_t object, const std::string& name, const std::string& where);

std::string read_text_dataset(hid_t parent, const std::string& name, const std::string& where);

// Names of the links in a group, in creation order when the group tracks it.
std::vector<std::string> link_names(hid_t group);

hsize_t dataset_length(hid_t dataset, const std::string& where);

// Reads elements [first, first + count) of a 1-D dataset, converted to `memory_type`.
void read_range(hid_t dataset, hid_t memory_type, hsize_t first, hsize_t count, void* into,
                const std::string& where);

// Grows a 1-D dataset from `first` to `first + count` elements and writes them.
void write_range(hid_t dataset, hid_t memory_type, hsize_t first, hsize_t count, const void* data,
                 const std::string& where);

// An empty, chunked 1-D dataset of unlimited size. Whole chunks are written at once, so
// the chunk cache is off: chunks go straight to the file and memory stays bounded.
Handle make_stream_dataset(hid_t parent, const std::string& name, hid_t type, hsize_t chunk,
                           int deflate_level);

// ---------------------------------------------------------------------------------------
// Names and text

std::string in_quotes(const std::string& text);

bool valid_channel_name(const std::string& name);

bool valid_link_name(const std::string& name);

// "results/fit-1" → {"results", "fit-1"}; empty when the path is unusable.
std::vector<std::string> split_group_path(const std::string& group);

const char* to_string(RawType type);

// /calibrations/<id>: the record's JSON (authoritative) and its fields as attributes.
void write_record_group(hid_t calibrations, const CalibrationRecord& record,
                        const std::string& json);

}  // namespace doorbench::session_hdf5
