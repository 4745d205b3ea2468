#include "acquisition/session/tdms.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <set>

#include "acquisition/session/csv_table.h"
#include "acquisition/session/internal/tdms_scaling.h"
#include "acquisition/session/lfs_pointer.h"
#include "acquisition/session/printable.h"
#include "core/time_text.h"

namespace doorbench {

namespace {

// The lead-in's table of contents (ToC) flags.
constexpr std::uint32_t kTocMetaData = 1u << 1;
constexpr std::uint32_t kTocNewObjList = 1u << 2;
constexpr std::uint32_t kTocRawData = 1u << 3;
constexpr std::uint32_t kTocInterleavedData = 1u << 5;
constexpr std::uint32_t kTocBigEndian = 1u << 6;
constexpr std::uint32_t kTocDAQmxRawData = 1u << 7;
constexpr std::size_t kLeadInBytes = 28;
constexpr std::uint32_t kNoRawData = 0xFFFFFFFFu;
constexpr std::uint32_t kSameRawIndex = 0x00000000u;
// The DAQmx raw data indexes: the bytes 69 12 00 00 (format-changing scalers) and 69 13 00 00
// (digital line scalers), read little-endian; the byte-swapped reading is taken too.
constexpr std::uint32_t kDaqmxFormatScaler = 0x00001269u;
constexpr std::uint32_t kDaqmxDigitalScaler = 0x00001369u;
constexpr std::uint32_t kDaqmxFormatScalerSwapped = 0x69120000u;
constexpr std::uint32_t kDaqmxDigitalScalerSwapped = 0x69130000u;
constexpr std::uint64_t kIncompleteSegment = 0xFFFFFFFFFFFFFFFFull;

// Data types (tdsDataType).
enum : std::uint32_t {
  kVoid = 0,
  kI8 = 1,
  kI16 = 2,
  kI32 = 3,
  kI64 = 4,
  kU8 = 5,
  kU16 = 6,
  kU32 = 7,
  kU64 = 8,
  kSingle = 9,
  kDouble = 10,
  kExtended = 11,
  kSingleWithUnit = 0x19,
  kDoubleWithUnit = 0x1A,
  kExtendedWithUnit = 0x1B,
  kString = 0x20,
  kBoolean = 0x21,
  kTimeStamp = 0x44,
  kFixedPoint = 0x4F,
  kComplexSingle = 0x08000C,
  kComplexDouble = 0x10000D,
  kDaqmxRaw = 0xFFFFFFFFu,
};

std::string hex(std::uint32_t value) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%X", value);
  return buffer;
}

std::string type_name(std::uint32_t type) {
  switch (type) {
    case kVoid:
      return "void";
    case kI8:
      return "I8";
    case kI16:
      return "I16";
    case kI32:
      return "I32";
    case kI64:
      return "I64";
    case kU8:
      return "U8";
    case kU16:
      return "U16";
    case kU32:
      return "U32";
    case kU64:
      return "U64";
    case kSingle:
      return "SGL";
    case kDouble:
      return "DBL";
    case kExtended:
      return "EXT (extended float)";
    case kSingleWithUnit:
      return "SGL with unit";
    case kDoubleWithUnit:
      return "DBL with unit";
    case kExtendedWithUnit:
      return "EXT with unit (extended float)";
    case kString:
      return "string";
    case kBoolean:
      return "boolean";
    case kTimeStamp:
      return "time stamp";
    case kFixedPoint:
      return "fixed point";
    case kComplexSingle:
      return "complex SGL";
    case kComplexDouble:
      return "complex DBL";
    case kDaqmxRaw:
      return "DAQmx raw data";
    default:
      return "unknown type " + hex(type);
  }
}

// Bytes per value of the numeric channel types; 0 for the types a channel may not have here.
std::size_t numeric_size(std::uint32_t type) {
  switch (type) {
    case kI8:
    case kU8:
      return 1;
    case kI16:
    case kU16:
      return 2;
    case kI32:
    case kU32:
    case kSingle:
    case kSingleWithUnit:
      return 4;
    case kI64:
    case kU64:
    case kDouble:
    case kDoubleWithUnit:
      return 8;
    default:
      return 0;
  }
}

// One scaler of a DAQmx raw data index: where its values are in the raw buffers.
struct DaqmxScaler {
  std::uint32_t type = 0;         // DAQmx's own codes: 0 U8, 1 I8, 2 U16, ... 9 DBL
  std::uint32_t buffer = 0;       // the raw buffer (one per device) it reads from
  std::uint32_t byte_offset = 0;  // within the buffer's stride (digital: bit_offset / 8)
  std::uint32_t bit_offset = 0;   // digital line scalers: the line's bit in the stride
  bool digital = false;
  std::uint32_t scale_id = 0;  // the NI_Scale[scale_id] it stands for
};

// Bytes per value of DAQmx's scaler data types (its own codes); 0 for the others.
std::size_t daqmx_value_size(std::uint32_t type) {
  static constexpr std::size_t kSizes[] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8};
  return type < 10 ? kSizes[type] : 0;
}

static_assert(std::endian::native == std::endian::little,
              "the reader assumes a little-endian host");

// The value of type T stored at `at` in the segment's byte order (kTocBigEndian: all but the
// ToC itself is big-endian).
template <typename T>
T stored(const std::uint8_t* at, bool big_endian) {
  std::array<std::uint8_t, sizeof(T)> bytes;
  std::memcpy(bytes.data(), at, sizeof(T));
  if (big_endian) std::reverse(bytes.begin(), bytes.end());
  T value;
  std::memcpy(&value, bytes.data(), sizeof(T));
  return value;
}

template <typename T>
double read_as(const std::uint8_t* at, bool big_endian) {
  return static_cast<double>(stored<T>(at, big_endian));
}

// A scaler's value at `at`: the number of its type, or a digital line's bit (0 or 1; the
// bit offset counts from the least significant bit of the first byte of the stride).
double daqmx_value(const DaqmxScaler& scaler, const std::uint8_t* at, bool big_endian) {
  if (scaler.digital) return static_cast<double>((at[0] >> (scaler.bit_offset % 8)) & 1u);
  switch (scaler.type) {
    case 0:
      return read_as<std::uint8_t>(at, big_endian);
    case 1:
      return read_as<std::int8_t>(at, big_endian);
    case 2:
      return read_as<std::uint16_t>(at, big_endian);
    case 3:
      return read_as<std::int16_t>(at, big_endian);
    case 4:
      return read_as<std::uint32_t>(at, big_endian);
    case 5:
      return read_as<std::int32_t>(at, big_endian);
    case 6:
      return read_as<std::uint64_t>(at, big_endian);
    case 7:
      return read_as<std::int64_t>(at, big_endian);
    case 8:
      return read_as<float>(at, big_endian);
    default:
      return read_as<double>(at, big_endian);
  }
}

// A reader over the file's bytes in the current segment's byte order, errors naming the
// segment and the byte where the field at fault starts.
class Reader {
 public:
  Reader(const std::vector<std::uint8_t>& bytes, const std::string& source)
      : bytes_(bytes), source_(source) {}

  [[noreturn]] void fail(const std::string& what) const { fail_at(position_, what); }
  [[noreturn]] void fail_at(std::size_t position, const std::string& what) const {
    throw TdmsError(source_ + ": segment " + std::to_string(segment_) + " (byte " +
                    std::to_string(position) + "): " + what);
  }
  void need(std::size_t count) const {
    if (position_ + count > bytes_.size() || position_ + count < position_) {
      fail("the file ends inside the segment (" + std::to_string(count) + " bytes needed, " +
           std::to_string(bytes_.size() - std::min(position_, bytes_.size())) + " left)");
    }
  }
  // A count just read from the file (at count_at), checked against the bytes left before it
  // is believed (4294967295 properties claimed); each item takes at least `min_bytes`.
  void need_items(std::uint64_t count, std::size_t min_bytes, const std::string& what,
                  std::size_t count_at) const {
    const std::size_t left = bytes_.size() - std::min(position_, bytes_.size());
    if (count > left / min_bytes) {
      fail_at(count_at, "claims " + std::to_string(count) + " " + what + ", but only " +
                            std::to_string(left) + " bytes are left (each takes at least " +
                            std::to_string(min_bytes) + ")");
    }
  }
  template <typename T>
  T read() {
    need(sizeof(T));
    const T value = stored<T>(bytes_.data() + position_, big_endian_);
    position_ += sizeof(T);
    return value;
  }
  std::string read_string() {
    const auto length = read<std::uint32_t>();
    need(length);
    std::string text(reinterpret_cast<const char*>(bytes_.data() + position_), length);
    position_ += length;
    return text;
  }
  double read_number(std::uint32_t type) {
    switch (type) {
      case kI8:
        return read<std::int8_t>();
      case kI16:
        return read<std::int16_t>();
      case kI32:
        return read<std::int32_t>();
      case kI64:
        return static_cast<double>(read<std::int64_t>());
      case kU8:
        return read<std::uint8_t>();
      case kU16:
        return read<std::uint16_t>();
      case kU32:
        return read<std::uint32_t>();
      case kU64:
        return static_cast<double>(read<std::uint64_t>());
      case kSingle:
      case kSingleWithUnit:
        return read<float>();
      case kDouble:
      case kDoubleWithUnit:
        return read<double>();
      default:
        fail("no number of type " + type_name(type));
    }
  }

  std::size_t position() const { return position_; }
  void seek(std::size_t position) { position_ = position; }
  void set_segment(int segment) { segment_ = segment; }
  void set_big_endian(bool big_endian) { big_endian_ = big_endian; }
  bool big_endian() const { return big_endian_; }
  std::size_t size() const { return bytes_.size(); }
  const std::uint8_t* at(std::size_t position) const { return bytes_.data() + position; }

 private:
  const std::vector<std::uint8_t>& bytes_;
  const std::string& source_;
  std::size_t position_ = 0;
  int segment_ = 0;
  bool big_endian_ = false;
};

// A time stamp (seconds since 1904-01-01 UTC and 2^-64 fractions) as ISO 8601 UTC.
std::string time_stamp_text(std::int64_t seconds, std::uint64_t fractions) {
  constexpr std::int64_t kEpoch1904To1970_s = 2082844800;
  // 2^-64 s fractions to the nearest microsecond; a fraction that rounds to 1 s carries.
  std::int64_t unix_s = seconds - kEpoch1904To1970_s;
  std::int64_t microseconds = std::llround(std::ldexp(static_cast<double>(fractions), -64) * 1e6);
  if (microseconds == 1000000) {
    microseconds = 0;
    ++unix_s;
  }
  return iso8601_utc_text(unix_s, microseconds, 6);
}

TdmsProperty read_property_value(Reader& in, std::uint32_t type) {
  TdmsProperty property;
  if (type == kString) {
    property.text = in.read_string();
  } else if (type == kBoolean) {
    property.number = in.read<std::uint8_t>() != 0 ? 1.0 : 0.0;
    property.text = *property.number != 0 ? "true" : "false";
  } else if (type == kTimeStamp) {
    // Little-endian: the fractions, then the seconds; big-endian: the 128-bit number whole,
    // the seconds first.
    std::uint64_t fractions = 0;
    std::int64_t seconds = 0;
    if (in.big_endian()) {
      seconds = in.read<std::int64_t>();
      fractions = in.read<std::uint64_t>();
    } else {
      fractions = in.read<std::uint64_t>();
      seconds = in.read<std::int64_t>();
    }
    property.text = time_stamp_text(seconds, fractions);
  } else if (type == kComplexSingle) {
    const float re = in.read<float>(), im = in.read<float>();
    property.text = format_csv_number(re) + (im < 0 ? "" : "+") + format_csv_number(im) + "i";
  } else if (type == kComplexDouble) {
    const double re = in.read<double>(), im = in.read<double>();
    property.text = format_csv_number(re) + (im < 0 ? "" : "+") + format_csv_number(im) + "i";
  } else if (numeric_size(type) > 0) {
    property.number = in.read_number(type);
    property.text = format_csv_number(*property.number);
  } else {
    in.fail_at(in.position() - 4, "properties of type " + type_name(type) + " are not supported");
  }
  return property;
}

// An object path "/'group'/'channel'" split and unescaped ('' is a quote).
std::vector<std::string> split_path(const std::string& path, const Reader& in,
                                    std::size_t path_at) {
  std::vector<std::string> parts;
  std::size_t i = 0;
  if (path == "/") return parts;
  while (i < path.size()) {
    if (path[i] != '/' || i + 1 >= path.size() || path[i + 1] != '\'') {
      in.fail_at(path_at, "object path '" + path + "' is not of the form /'group'/'channel'");
    }
    i += 2;
    std::string name;
    while (true) {
      if (i >= path.size()) {
        in.fail_at(path_at, "object path '" + path + "' has an unterminated name");
      }
      if (path[i] == '\'') {
        if (i + 1 < path.size() && path[i + 1] == '\'') {
          name += '\'';
          i += 2;
          continue;
        }
        ++i;
        break;
      }
      name += path[i++];
    }
    parts.push_back(name);
  }
  if (parts.size() > 2) {
    in.fail_at(path_at, "object path '" + path + "' is deeper than group and channel");
  }
  return parts;
}

struct ObjectState {
  std::vector<std::string> parts;
  bool has_raw = false;
  bool daqmx = false;  // DAQmx raw data: scalers and raw buffer widths
  std::vector<DaqmxScaler> scalers;
  std::vector<std::uint32_t> widths;  // bytes per sample of each raw buffer
  std::uint32_t type = kVoid;
  std::uint64_t count = 0;         // values per chunk
  std::uint64_t string_bytes = 0;  // string channels: bytes per chunk
  std::size_t channel = 0;         // index into TdmsFile::channels (channels only)
  bool is_channel = false;
};

std::size_t chunk_bytes(const ObjectState& object) {
  if (object.type == kString) return static_cast<std::size_t>(object.string_bytes);
  if (object.daqmx) {
    std::size_t stride = 0;
    for (std::uint32_t width : object.widths) stride += width;
    return static_cast<std::size_t>(object.count) * stride;
  }
  return static_cast<std::size_t>(object.count) * numeric_size(object.type);
}

}  // namespace

const TdmsChannel* TdmsFile::find(const std::string& group, const std::string& name) const {
  for (const TdmsChannel& channel : channels) {
    if (channel.group == group && channel.name == name) return &channel;
  }
  return nullptr;
}

namespace {

// One segment's lead-in: its table of contents and where its parts are.
struct SegmentLayout {
  std::uint32_t toc = 0;
  std::size_t meta_start = 0;
  std::size_t raw_start = 0;
  std::size_t end = 0;  // the next segment's start
};

// The lead-in at `start`: "TDSm" (bytes 0-3), the ToC flags (4-7, always little-endian),
// then in the segment's byte order the version (8-11), the next segment's offset (12-19)
// and the raw data's (20-27), both counted from the lead-in's end. Errors name the byte
// where the field at fault starts.
SegmentLayout read_lead_in(Reader& in, std::size_t start, std::size_t file_bytes) {
  in.seek(start);
  const std::size_t tag_bytes = std::min<std::size_t>(4, file_bytes - start);
  if (tag_bytes < 4 || std::memcmp(in.at(start), "TDSm", 4) != 0) {
    if (tag_bytes == 4 && std::memcmp(in.at(start), "TDSh", 4) == 0) {
      in.fail("this is a TDMS index file (.tdms_index); import the .tdms file itself");
    }
    const std::string found(reinterpret_cast<const char*>(in.at(start)), tag_bytes);
    in.fail("no TDMS segment here (a segment starts with 'TDSm'; these bytes are '" +
            printable(found) + "')");
  }
  in.need(kLeadInBytes);
  in.set_big_endian(false);
  in.seek(start + 4);
  SegmentLayout layout;
  layout.toc = in.read<std::uint32_t>();
  in.set_big_endian((layout.toc & kTocBigEndian) != 0);
  const auto version = in.read<std::uint32_t>();
  const auto next_offset = in.read<std::uint64_t>();
  const auto raw_offset = in.read<std::uint64_t>();
  if (version != 4712 && version != 4713) {
    in.fail_at(start + 8, "TDMS version " + std::to_string(version) +
                              " is not supported (4712 and 4713 are)" +
                              (in.big_endian() ? " (read big-endian: the ToC says so)" : ""));
  }
  layout.meta_start = start + kLeadInBytes;
  layout.end = next_offset == kIncompleteSegment
                   ? file_bytes
                   : layout.meta_start + static_cast<std::size_t>(next_offset);
  if (next_offset > file_bytes || layout.end > file_bytes || layout.end < layout.meta_start) {
    in.fail_at(start + 12, "the next segment offset (" + std::to_string(next_offset) +
                               ") points past the end of the file (" + std::to_string(file_bytes) +
                               " bytes)");
  }
  layout.raw_start = layout.meta_start + static_cast<std::size_t>(raw_offset);
  if (raw_offset > file_bytes || layout.raw_start > layout.end) {
    in.fail_at(start + 20, "the raw data offset (" + std::to_string(raw_offset) +
                               ") points past the segment's end");
  }
  return layout;
}

// Reads TDMS files: the objects met so far and the current segment's object list.
class TdmsParser {
 public:
  TdmsParser(const std::vector<std::uint8_t>& bytes, const std::string& source)
      : bytes_(bytes), in_(bytes, source) {}

  TdmsFile parse() {
    std::size_t start = 0;
    while (start < bytes_.size()) {
      ++file_.segments;
      in_.set_segment(file_.segments);
      const SegmentLayout layout = read_lead_in(in_, start, bytes_.size());
      if (layout.toc & kTocMetaData) read_meta_data(layout);
      if ((layout.toc & kTocRawData) && layout.raw_start < layout.end) read_raw_data(layout);
      start = layout.end;
    }
    return std::move(file_);
  }

 private:
  void read_meta_data(const SegmentLayout& layout) {
    if (layout.toc & kTocNewObjList) active_.clear();
    in_.seek(layout.meta_start);
    const auto count = in_.read<std::uint32_t>();
    in_.need_items(count, 12, "objects", layout.meta_start);  // path length, raw index, properties
    for (std::uint32_t o = 0; o < count; ++o) {
      const std::size_t path_at = in_.position();
      const std::string path = in_.read_string();
      ObjectState& object = object_at(path, path_at);
      read_raw_index(path, object);
      read_properties(object);
      if (std::find(active_.begin(), active_.end(), path) == active_.end()) {
        active_.push_back(path);
      }
    }
  }

  // The object at `path`, a channel (group/channel) added to the file when first met.
  ObjectState& object_at(const std::string& path, std::size_t path_at) {
    const bool known = objects_.count(path) > 0;
    ObjectState& object = objects_[path];
    if (!known) {
      object.parts = split_path(path, in_, path_at);
      if (object.parts.size() == 2) {
        object.is_channel = true;
        object.channel = file_.channels.size();
        file_.channels.push_back({object.parts[0], object.parts[1], "", {}, {}, "", {}});
      }
    }
    return object;
  }

  void read_raw_index(const std::string& path, ObjectState& object) {
    const std::size_t index_at = in_.position();
    const auto index = in_.read<std::uint32_t>();
    if (index == kNoRawData) {
      object.has_raw = false;
      return;
    }
    if (index == kSameRawIndex) {
      if (!object.has_raw && object.type == kVoid) {
        in_.fail_at(index_at, "object " + path + " repeats a raw data index it never had");
      }
      object.has_raw = true;
      return;
    }
    if (index == kDaqmxFormatScaler || index == kDaqmxDigitalScaler ||
        index == kDaqmxFormatScalerSwapped || index == kDaqmxDigitalScalerSwapped) {
      read_daqmx_index(path, object, index_at,
                       index == kDaqmxDigitalScaler || index == kDaqmxDigitalScalerSwapped);
      return;
    }
    const auto type = in_.read<std::uint32_t>();
    const auto dimension = in_.read<std::uint32_t>();
    const auto values = in_.read<std::uint64_t>();
    std::uint64_t string_bytes = 0;
    if (type == kString) string_bytes = in_.read<std::uint64_t>();
    if (dimension != 1) {
      in_.fail_at(index_at, "object " + path + ": arrays of dimension " +
                                std::to_string(dimension) + " are not supported (1 is)");
    }
    if (type != kString && numeric_size(type) == 0) {
      in_.fail_at(index_at, "object " + path + ": channels of type " + type_name(type) +
                                " are not supported (I8-I64, U8-U64, SGL, DBL are; strings "
                                "are skipped)");
    }
    object.has_raw = true;
    object.daqmx = false;
    object.type = type;
    object.count = values;
    object.string_bytes = string_bytes;
    if (object.is_channel && type != kString) {
      file_.channels[object.channel].data_type = type_name(type);
    }
  }

  // A DAQmx raw data index (after its 4-byte header): data type 0xFFFFFFFF, dimension,
  // values per chunk, the scalers (type, raw buffer, byte or bit offset, sample format, scale
  // id), the raw buffers' widths.
  void read_daqmx_index(const std::string& path, ObjectState& object, std::size_t index_at,
                        bool digital) {
    const auto type = in_.read<std::uint32_t>();
    const auto dimension = in_.read<std::uint32_t>();
    const auto values = in_.read<std::uint64_t>();
    if (type != kDaqmxRaw) {
      in_.fail_at(index_at, "object " + path + ": a DAQmx raw data index of data type " +
                                hex(type) + " (0xFFFFFFFF expected)");
    }
    if (dimension != 1) {
      in_.fail_at(index_at, "object " + path + ": arrays of dimension " +
                                std::to_string(dimension) + " are not supported (1 is)");
    }
    object.scalers.clear();
    const auto scalers = in_.read<std::uint32_t>();
    for (std::uint32_t k = 0; k < scalers; ++k) {
      DaqmxScaler scaler;
      scaler.digital = digital;
      scaler.type = in_.read<std::uint32_t>();
      scaler.buffer = in_.read<std::uint32_t>();
      if (digital) {
        scaler.bit_offset = in_.read<std::uint32_t>();
        scaler.byte_offset = scaler.bit_offset / 8;
        in_.read<std::uint8_t>();  // sample format bitmap
      } else {
        scaler.byte_offset = in_.read<std::uint32_t>();
        in_.read<std::uint32_t>();  // sample format bitmap
      }
      scaler.scale_id = in_.read<std::uint32_t>();
      if (daqmx_value_size(scaler.type) == 0) {
        in_.fail_at(index_at, "object " + path + ": DAQmx scalers of data type " +
                                  std::to_string(scaler.type) +
                                  " are not supported (0-9: U8, I8, U16, I16, U32, I32, U64, I64, "
                                  "SGL, DBL are)");
      }
      object.scalers.push_back(scaler);
    }
    object.widths.clear();
    const auto widths = in_.read<std::uint32_t>();
    for (std::uint32_t k = 0; k < widths; ++k) object.widths.push_back(in_.read<std::uint32_t>());
    for (const DaqmxScaler& scaler : object.scalers) {
      if (scaler.buffer >= object.widths.size() ||
          scaler.byte_offset + daqmx_value_size(scaler.type) > object.widths[scaler.buffer]) {
        in_.fail_at(index_at, "object " + path + ": DAQmx scaler " +
                                  std::to_string(scaler.scale_id) +
                                  " reads past its raw buffer's width");
      }
    }
    object.has_raw = true;
    object.daqmx = true;
    object.type = kDaqmxRaw;
    object.count = values;
    if (object.is_channel) file_.channels[object.channel].data_type = type_name(kDaqmxRaw);
  }

  // The object's properties: the file's, a group's or a channel's.
  void read_properties(const ObjectState& object) {
    const std::size_t count_at = in_.position();
    const auto properties = in_.read<std::uint32_t>();
    in_.need_items(properties, 9, "properties", count_at);  // name length, type, a value's byte
    for (std::uint32_t p = 0; p < properties; ++p) {
      const std::string name = in_.read_string();
      const auto type = in_.read<std::uint32_t>();
      TdmsProperty value = read_property_value(in_, type);
      if (object.parts.empty()) {
        file_.file_properties[name] = std::move(value);
      } else if (object.parts.size() == 1) {
        file_.group_properties[object.parts[0]][name] = std::move(value);
      } else {
        file_.channels[object.channel].properties[name] = std::move(value);
      }
    }
  }

  // The segment's chunks of raw data, each holding every active object's values.
  void read_raw_data(const SegmentLayout& layout) {
    std::vector<ObjectState*> with_data;
    std::size_t chunk = 0;
    for (const std::string& path : active_) {
      ObjectState& object = objects_[path];
      if (!object.has_raw || object.count == 0) continue;
      with_data.push_back(&object);
      // DAQmx channels share their raw buffers: the segment's chunk is one channel's.
      if (!object.daqmx || with_data.size() == 1) chunk += chunk_bytes(object);
    }
    const std::size_t raw_bytes = layout.end - layout.raw_start;
    if (chunk == 0)
      in_.fail_at(layout.raw_start, "raw data but no object with raw data in the segment");
    if (raw_bytes % chunk != 0) {
      in_.fail_at(layout.raw_start, "raw data of " + std::to_string(raw_bytes) +
                                        " bytes is not a whole number of " + std::to_string(chunk) +
                                        "-byte chunks (partial chunks are not supported)");
    }
    const std::size_t chunks = raw_bytes / chunk;
    in_.seek(layout.raw_start);
    if (with_data.front()->daqmx) {
      check_daqmx(with_data);
      for (std::size_t c = 0; c < chunks; ++c) read_daqmx_chunk(with_data);
      return;
    }
    const bool interleaved = (layout.toc & kTocInterleavedData) != 0;
    if (interleaved) check_interleaved(with_data);
    for (std::size_t c = 0; c < chunks; ++c) {
      if (interleaved) {
        read_interleaved_chunk(with_data);
      } else {
        read_contiguous_chunk(with_data);
      }
    }
  }

  // Every channel of a DAQmx segment reads the same raw buffers.
  void check_daqmx(const std::vector<ObjectState*>& with_data) {
    for (const ObjectState* object : with_data) {
      if (!object->daqmx) {
        in_.fail("a segment mixing DAQmx raw data with other raw data is not supported");
      }
      if (object->count != with_data.front()->count ||
          object->widths != with_data.front()->widths) {
        in_.fail("DAQmx channels with different raw buffers in one segment are not supported");
      }
    }
  }

  // One chunk of DAQmx raw data: each raw buffer in turn, sample by sample, each sample a
  // stride of the buffer's width holding every scaler's value at its offset.
  void read_daqmx_chunk(const std::vector<ObjectState*>& with_data) {
    const ObjectState& first = *with_data.front();
    const std::size_t count = static_cast<std::size_t>(first.count);
    for (std::size_t b = 0; b < first.widths.size(); ++b) {
      const std::size_t width = first.widths[b];
      in_.need(count * width);
      const std::size_t start = in_.position();
      for (ObjectState* object : with_data) {
        if (!object->is_channel) continue;
        auto& raw = file_.channels[object->channel].daqmx_raw;
        for (const DaqmxScaler& scaler : object->scalers) {
          if (scaler.buffer != b) continue;
          std::vector<double>& values = raw[scaler.scale_id];
          for (std::size_t i = 0; i < count; ++i) {
            values.push_back(daqmx_value(scaler, in_.at(start + i * width + scaler.byte_offset),
                                         in_.big_endian()));
          }
        }
      }
      in_.seek(start + count * width);
    }
  }

  void check_interleaved(const std::vector<ObjectState*>& with_data) {
    for (const ObjectState* object : with_data) {
      if (object->type == kString) in_.fail("interleaved string channels are not supported");
      if (object->count != with_data.front()->count) {
        in_.fail("interleaved channels with different numbers of values are not supported");
      }
    }
  }

  void read_interleaved_chunk(const std::vector<ObjectState*>& with_data) {
    for (std::uint64_t i = 0; i < with_data.front()->count; ++i) {
      for (ObjectState* object : with_data) {
        const double value = in_.read_number(object->type);
        if (object->is_channel) file_.channels[object->channel].values.push_back(value);
      }
    }
  }

  // Each object's values in turn; string channels are skipped.
  void read_contiguous_chunk(const std::vector<ObjectState*>& with_data) {
    for (ObjectState* object : with_data) {
      if (object->type == kString) {
        in_.need(chunk_bytes(*object));
        in_.seek(in_.position() + chunk_bytes(*object));
        continue;
      }
      std::vector<double>& values = file_.channels[object->channel].values;
      for (std::uint64_t i = 0; i < object->count; ++i) {
        values.push_back(in_.read_number(object->type));
      }
    }
  }

  const std::vector<std::uint8_t>& bytes_;
  Reader in_;
  TdmsFile file_;
  std::map<std::string, ObjectState> objects_;
  std::vector<std::string> active_;  // the object list of the current segment, in order
};

}  // namespace

TdmsFile parse_tdms(const std::vector<std::uint8_t>& bytes, const std::string& source) {
  const std::string pointer = lfs_pointer_description(
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  if (!pointer.empty()) throw TdmsError(source + ": " + pointer);
  TdmsFile file = TdmsParser(bytes, source).parse();
  for (TdmsChannel& channel : file.channels) tdms_detail::apply_scaling(channel, source);
  return file;
}

TdmsFile read_tdms(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw TdmsError(path.string() + ": cannot open for reading");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  if (bytes.empty()) throw TdmsError(path.string() + ": the file is empty (0 bytes)");
  return parse_tdms(bytes, path.string());
}

}  // namespace doorbench
