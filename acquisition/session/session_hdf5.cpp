// The HDF5 plumbing of session files (acquisition/session/internal/session_hdf5.h).
#include "acquisition/session/internal/session_hdf5.h"

#include <algorithm>
#include <charconv>
#include <iterator>

#include "acquisition/session/printable.h"

namespace doorbench::session_hdf5 {

std::string format_time(double t) {
  char text[32];
  const auto result = std::to_chars(std::begin(text), std::end(text), t);
  return std::string(text, result.ptr);
}

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

Handle checked(hid_t id, Handle::Closer closer, const std::string& what) {
  if (id < 0) fail(what);
  return Handle(id, closer);
}

Handle make_group(hid_t parent, const std::string& name, bool track_order) {
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

}  // namespace doorbench::session_hdf5
