#include "acquisition/session/tdms.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <set>

#include "acquisition/session/csv_table.h"

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
constexpr std::uint32_t kDaqmxFormatScaler = 0x69120000u;
constexpr std::uint32_t kDaqmxDigitalScaler = 0x69130000u;
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

// A little-endian reader over the file's bytes, errors naming the segment and byte.
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
  // A count read from the file, checked against the bytes left before it is believed
  // (issue 33: 4294967295 properties claimed); each item takes at least `min_bytes`.
  void need_items(std::uint64_t count, std::size_t min_bytes, const std::string& what) const {
    const std::size_t left = bytes_.size() - std::min(position_, bytes_.size());
    if (count > left / min_bytes) {
      fail("claims " + std::to_string(count) + " " + what + ", but only " + std::to_string(left) +
           " bytes are left (each takes at least " + std::to_string(min_bytes) + ")");
    }
  }
  template <typename T>
  T read() {
    need(sizeof(T));
    T value;
    std::memcpy(&value, bytes_.data() + position_, sizeof(T));  // the host is little-endian
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
  std::size_t size() const { return bytes_.size(); }
  const std::uint8_t* at(std::size_t position) const { return bytes_.data() + position; }

 private:
  const std::vector<std::uint8_t>& bytes_;
  const std::string& source_;
  std::size_t position_ = 0;
  int segment_ = 0;
};

// A time stamp (seconds since 1904-01-01 UTC and 2^-64 fractions) as ISO 8601 UTC.
std::string time_stamp_text(std::int64_t seconds, std::uint64_t fractions) {
  constexpr std::int64_t kEpoch1904To1970_s = 2082844800;
  const std::time_t unix_s = static_cast<std::time_t>(seconds - kEpoch1904To1970_s);
  std::tm utc{};
  gmtime_r(&unix_s, &utc);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%S", &utc);
  char fraction[16];
  std::snprintf(fraction, sizeof fraction, "%.6f", std::ldexp(static_cast<double>(fractions), -64));
  return std::string(date) + (fraction + 1) + "Z";
}

TdmsProperty read_property_value(Reader& in, std::uint32_t type) {
  TdmsProperty property;
  if (type == kString) {
    property.text = in.read_string();
  } else if (type == kBoolean) {
    property.number = in.read<std::uint8_t>() != 0 ? 1.0 : 0.0;
    property.text = *property.number != 0 ? "true" : "false";
  } else if (type == kTimeStamp) {
    const auto fractions = in.read<std::uint64_t>();
    const auto seconds = in.read<std::int64_t>();
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
    in.fail("properties of type " + type_name(type) + " are not supported");
  }
  return property;
}

// An object path "/'group'/'channel'" split and unescaped ('' is a quote).
std::vector<std::string> split_path(const std::string& path, const Reader& in) {
  std::vector<std::string> parts;
  std::size_t i = 0;
  if (path == "/") return parts;
  while (i < path.size()) {
    if (path[i] != '/' || i + 1 >= path.size() || path[i + 1] != '\'') {
      in.fail("object path '" + path + "' is not of the form /'group'/'channel'");
    }
    i += 2;
    std::string name;
    while (true) {
      if (i >= path.size()) in.fail("object path '" + path + "' has an unterminated name");
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
  if (parts.size() > 2) in.fail("object path '" + path + "' is deeper than group and channel");
  return parts;
}

struct ObjectState {
  std::vector<std::string> parts;
  bool has_raw = false;
  std::uint32_t type = kVoid;
  std::uint64_t count = 0;         // values per chunk
  std::uint64_t string_bytes = 0;  // string channels: bytes per chunk
  std::size_t channel = 0;         // index into TdmsFile::channels (channels only)
  bool is_channel = false;
};

std::size_t chunk_bytes(const ObjectState& object) {
  if (object.type == kString) return static_cast<std::size_t>(object.string_bytes);
  return static_cast<std::size_t>(object.count) * numeric_size(object.type);
}

// The channel's scaling (NI_Scaling_Status "unscaled"): scale NI_Number_Of_Scales − 1,
// whose input source is another scale's index or the raw data (−1, absent).
double scale_value(const std::map<std::string, TdmsProperty>& p, int scale, double raw, int depth,
                   const std::string& where) {
  if (scale < 0) return raw;
  if (depth > 16) throw TdmsError(where + ": the scales' input sources form a loop");
  const std::string prefix = "NI_Scale[" + std::to_string(scale) + "]_";
  const auto type = p.find(prefix + "Scale_Type");
  if (type == p.end()) {
    throw TdmsError(where + ": " + prefix + "Scale_Type is missing");
  }
  auto number = [&](const std::string& name) {
    const auto it = p.find(prefix + name);
    if (it == p.end() || !it->second.number) {
      throw TdmsError(where + ": " + prefix + name + " is missing or not a number");
    }
    return *it->second.number;
  };
  auto input = [&](const std::string& kind) {
    const auto it = p.find(prefix + kind + "_Input_Source");
    if (it == p.end() || !it->second.number) return -1;
    const double source = *it->second.number;
    return source >= 4294967295.0 || source < 0 ? -1 : static_cast<int>(source);
  };
  if (type->second.text == "Linear") {
    const double x = scale_value(p, input("Linear"), raw, depth + 1, where);
    return number("Linear_Slope") * x + number("Linear_Y_Intercept");
  }
  if (type->second.text == "Polynomial") {
    const double x = scale_value(p, input("Polynomial"), raw, depth + 1, where);
    const int size = static_cast<int>(number("Polynomial_Coefficients_Size"));
    double sum = 0.0;
    for (int k = size - 1; k >= 0; --k) {
      sum = sum * x + number("Polynomial_Coefficients[" + std::to_string(k) + "]");
    }
    return sum;
  }
  throw TdmsError(where + ": " + prefix + "Scale_Type '" + type->second.text +
                  "' is not supported (Linear and Polynomial are)");
}

void apply_scaling(TdmsChannel& channel, const std::string& source) {
  const auto status = channel.properties.find("NI_Scaling_Status");
  if (status == channel.properties.end() || status->second.text != "unscaled") return;
  const auto count = channel.properties.find("NI_Number_Of_Scales");
  if (count == channel.properties.end() || !count->second.number || *count->second.number < 1) {
    return;
  }
  const int last = static_cast<int>(*count->second.number) - 1;
  const std::string where = source + ": channel " + channel.group + "/" + channel.name;
  for (double& value : channel.values) {
    value = scale_value(channel.properties, last, value, 0, where);
  }
  channel.scaling =
      "NI_Scale[" + std::to_string(last) + "] (" +
      channel.properties.at("NI_Scale[" + std::to_string(last) + "]_Scale_Type").text + ")";
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

SegmentLayout read_lead_in(Reader& in, std::size_t start, std::size_t file_bytes) {
  in.seek(start);
  in.need(kLeadInBytes);
  if (std::memcmp(in.at(start), "TDSm", 4) != 0) {
    if (std::memcmp(in.at(start), "TDSh", 4) == 0) {
      in.fail("this is a TDMS index file (.tdms_index); import the .tdms file itself");
    }
    in.fail("no TDMS segment here (the lead-in starts with 'TDSm')");
  }
  in.seek(start + 4);
  SegmentLayout layout;
  layout.toc = in.read<std::uint32_t>();
  const auto version = in.read<std::uint32_t>();
  const auto next_offset = in.read<std::uint64_t>();
  const auto raw_offset = in.read<std::uint64_t>();
  if (version != 4712 && version != 4713) {
    in.fail("TDMS version " + std::to_string(version) + " is not supported (4712 and 4713 are)");
  }
  if (layout.toc & kTocBigEndian) {
    in.fail("big-endian segments (ToC flag kTocBigEndian) are not supported");
  }
  if (layout.toc & kTocDAQmxRawData) {
    in.fail(
        "DAQmx raw data (ToC flag kTocDAQmxRawData) is not supported: log the channels "
        "scaled (LabVIEW: TDMS, not TDMS raw / 'Log and Read' with scaled data)");
  }
  layout.meta_start = start + kLeadInBytes;
  layout.end = next_offset == kIncompleteSegment
                   ? file_bytes
                   : layout.meta_start + static_cast<std::size_t>(next_offset);
  if (layout.end > file_bytes || layout.end < layout.meta_start) {
    in.fail("the next segment offset (" + std::to_string(next_offset) +
            ") points past the end of the file (" + std::to_string(file_bytes) + " bytes)");
  }
  layout.raw_start = layout.meta_start + static_cast<std::size_t>(raw_offset);
  if (layout.raw_start > layout.end) in.fail("the raw data offset points past the segment's end");
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
    in_.need_items(count, 12, "objects");  // path length, raw index, property count
    for (std::uint32_t o = 0; o < count; ++o) {
      const std::string path = in_.read_string();
      ObjectState& object = object_at(path);
      read_raw_index(path, object);
      read_properties(object);
      if (std::find(active_.begin(), active_.end(), path) == active_.end()) {
        active_.push_back(path);
      }
    }
  }

  // The object at `path`, a channel (group/channel) added to the file when first met.
  ObjectState& object_at(const std::string& path) {
    const bool known = objects_.count(path) > 0;
    ObjectState& object = objects_[path];
    if (!known) {
      object.parts = split_path(path, in_);
      if (object.parts.size() == 2) {
        object.is_channel = true;
        object.channel = file_.channels.size();
        file_.channels.push_back({object.parts[0], object.parts[1], "", {}, {}, ""});
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
        in_.fail("object " + path + " repeats a raw data index it never had");
      }
      object.has_raw = true;
      return;
    }
    if (index == kDaqmxFormatScaler || index == kDaqmxDigitalScaler) {
      in_.fail_at(index_at, "object " + path + ": DAQmx raw data (raw data index " + hex(index) +
                                ") is not supported");
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
    object.type = type;
    object.count = values;
    object.string_bytes = string_bytes;
    if (object.is_channel && type != kString) {
      file_.channels[object.channel].data_type = type_name(type);
    }
  }

  // The object's properties: the file's, a group's or a channel's.
  void read_properties(const ObjectState& object) {
    const auto properties = in_.read<std::uint32_t>();
    in_.need_items(properties, 9, "properties");  // name length, type, a value's byte
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
      chunk += chunk_bytes(object);
    }
    const std::size_t raw_bytes = layout.end - layout.raw_start;
    if (chunk == 0) in_.fail("raw data but no object with raw data in the segment");
    if (raw_bytes % chunk != 0) {
      in_.fail("raw data of " + std::to_string(raw_bytes) + " bytes is not a whole number of " +
               std::to_string(chunk) + "-byte chunks (partial chunks are not supported)");
    }
    const std::size_t chunks = raw_bytes / chunk;
    in_.seek(layout.raw_start);
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
  TdmsFile file = TdmsParser(bytes, source).parse();
  for (TdmsChannel& channel : file.channels) apply_scaling(channel, source);
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

std::vector<TdmsMapItem> parse_tdms_map(const std::string& text) {
  std::vector<TdmsMapItem> items;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    const std::size_t equals = item.find('=');
    const std::size_t slash =
        equals == std::string::npos ? std::string::npos : item.find('/', equals);
    if (equals == std::string::npos || equals == 0 || slash == std::string::npos ||
        slash == equals + 1 || slash + 1 == item.size()) {
      throw std::invalid_argument("--map item '" + item +
                                  "' is not TARGET=GROUP/CHANNEL (e.g. force=Load/Force)");
    }
    const std::string target = item.substr(0, equals);
    if (target != "force" && target != "angle" && target != "rate" && target != "time" &&
        !has_unit_suffix(target)) {
      throw std::invalid_argument("--map target '" + target +
                                  "' is not force, angle, rate, time or a column name with a "
                                  "unit suffix (e.g. inclinometer_angle_rad)");
    }
    for (const TdmsMapItem& earlier : items) {
      if (earlier.target == target) {
        throw std::invalid_argument("--map names target '" + target + "' twice");
      }
    }
    items.push_back({target, item.substr(equals + 1, slash - equals - 1), item.substr(slash + 1)});
    start = comma + 1;
  }
  return items;
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

// The map's force item; throws when the map gives no force or no motion channel.
const TdmsMapItem& check_map(const std::vector<TdmsMapItem>& map, const std::string& source) {
  const TdmsMapItem* force_item = map_item(map, "force");
  const bool has_motion = map_item(map, "angle") != nullptr || map_item(map, "rate") != nullptr;
  if (!force_item) throw TdmsError(source + ": --map gives no force channel (force=GROUP/CHANNEL)");
  if (!has_motion) {
    throw TdmsError(source +
                    ": --map gives neither angle nor rate (angle=GROUP/CHANNEL or "
                    "rate=GROUP/CHANNEL)");
  }
  return *force_item;
}

// The channel an item maps, which must exist and hold numbers.
const TdmsChannel& mapped_channel(const TdmsFile& file, const TdmsMapItem& item,
                                  const std::string& source) {
  const TdmsChannel* channel = file.find(item.group, item.channel);
  if (!channel) {
    std::string known;
    for (const TdmsChannel& c : file.channels) {
      known += (known.empty() ? "" : ", ") + c.group + "/" + c.name;
    }
    throw TdmsError(source + ": " + item.target + ": no channel " + item.group + "/" +
                    item.channel + " (the file has " + (known.empty() ? "none" : known) + ")");
  }
  if (channel->data_type.empty()) {
    throw TdmsError(source + ": " + item.target + ": channel " + item.group + "/" + item.channel +
                    " has no numeric values");
  }
  return *channel;
}

// Without a time channel, the time from the force channel's waveform properties
// (wf_start_offset + i · wf_increment), and its start time as metadata.
void waveform_time(const TdmsChannel& force, const std::string& source, Recording& recording) {
  const TdmsProperty* increment = property(force, "wf_increment");
  if (!increment || !increment->number || !(*increment->number > 0)) {
    throw TdmsError(source + ": force: channel " + force.group + "/" + force.name +
                    " has no wf_increment > 0 to give the time (map a time channel: "
                    "time=GROUP/CHANNEL)");
  }
  const TdmsProperty* offset = property(force, "wf_start_offset");
  const double first_s = offset && offset->number ? *offset->number : 0.0;
  recording.time_s.resize(force.values.size());
  for (std::size_t i = 0; i < force.values.size(); ++i) {
    recording.time_s[i] = first_s + static_cast<double>(i) * *increment->number;
  }
  if (const TdmsProperty* start = property(force, "wf_start_time")) {
    recording.metadata.emplace_back("tdms_wf_start_time", start->text);
  }
}

// One mapped channel into its column (force, angle, rate, an extra; time is taken
// before): as many values as the force channel, the same waveform increment (when the
// time is the waveform's), the target's unit; its origin as metadata.
void take_mapped_column(const TdmsMapItem& item, const TdmsChannel& channel,
                        const TdmsChannel& force, bool waveform_clock, const std::string& source,
                        Recording& recording) {
  const std::string name = item.group + "/" + item.channel;
  if (channel.values.size() != force.values.size()) {
    throw TdmsError(source + ": " + item.target + ": channel " + name + " has " +
                    std::to_string(channel.values.size()) + " values, the force channel " +
                    std::to_string(force.values.size()));
  }
  if (waveform_clock && item.target != "time") {
    const TdmsProperty* increment = property(channel, "wf_increment");
    const TdmsProperty* force_increment = property(force, "wf_increment");
    if (increment && increment->number && *increment->number != *force_increment->number) {
      throw TdmsError(source + ": " + item.target + ": channel " + name + " has wf_increment " +
                      format_csv_number(*increment->number) + ", the force channel " +
                      format_csv_number(*force_increment->number));
    }
  }
  const std::string expected = item.target == "force"   ? "N"
                               : item.target == "angle" ? "rad"
                               : item.target == "rate"  ? "rad/s"
                               : item.target == "time"  ? "s"
                                                        : "";
  const TdmsProperty* unit = property(channel, "unit_string");
  if (!expected.empty() && unit && !unit->text.empty() && unit->text != expected) {
    throw TdmsError(source + ": " + item.target + ": channel " + name + " is in '" + unit->text +
                    "', not " + expected +
                    " (scale it in the file, or map it as an extra column whose name ends in "
                    "its unit)");
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

}  // namespace

Recording tdms_to_recording(const TdmsFile& file, const std::vector<TdmsMapItem>& map,
                            const std::string& source) {
  Recording recording;
  recording.source = source;
  const TdmsChannel& force = mapped_channel(file, check_map(map, source), source);
  const TdmsMapItem* time_item = map_item(map, "time");
  if (time_item) {
    recording.time_s = mapped_channel(file, *time_item, source).values;
  } else {
    waveform_time(force, source, recording);
  }
  for (const TdmsMapItem& item : map) {
    take_mapped_column(item, mapped_channel(file, item, source), force, time_item == nullptr,
                       source, recording);
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
  return recording;
}

}  // namespace doorbench
