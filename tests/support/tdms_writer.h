#pragma once
// A TDMS writer for tests, from NI's published description of the format ("TDMS File Format
// Internal Structure"): segments of a 28-byte lead-in ("TDSm", the ToC flags, the version,
// the next segment's and the raw data's offsets), metadata (objects with their raw data
// indexes and properties) and raw data, little-endian, or big-endian after the ToC (which
// is always little-endian) when the ToC has kTocBigEndian. Every piece of bytes carries its
// byte order (Bytes::big_endian); segment() refuses pieces of the other order. It writes
// exactly what a test asks for, including layouts the reader refuses.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace doorbench::testing::tdms {

inline constexpr std::uint32_t kTocMetaData = 1u << 1;
inline constexpr std::uint32_t kTocNewObjList = 1u << 2;
inline constexpr std::uint32_t kTocRawData = 1u << 3;
inline constexpr std::uint32_t kTocInterleavedData = 1u << 5;
inline constexpr std::uint32_t kTocBigEndian = 1u << 6;
inline constexpr std::uint32_t kTocDAQmxRawData = 1u << 7;

inline constexpr std::uint32_t kI32 = 3, kU32 = 7, kSingle = 9, kDouble = 10, kExtended = 11,
                               kString = 0x20, kTimeStamp = 0x44;

struct Bytes {
  std::vector<std::uint8_t> data;
  bool big_endian = false;  // the order put() writes numbers in
  template <typename T>
  void put(T value) {
    // resize and copy (an insert of a local array trips GCC 12's -Wstringop-overflow)
    const std::size_t at = data.size();
    data.resize(at + sizeof(T));
    std::memcpy(data.data() + at, &value, sizeof(T));
    if (big_endian) std::reverse(data.begin() + static_cast<std::ptrdiff_t>(at), data.end());
  }
  void text(const std::string& value) {
    put<std::uint32_t>(static_cast<std::uint32_t>(value.size()));
    data.insert(data.end(), value.begin(), value.end());
  }
  void append(const Bytes& other) { data.insert(data.end(), other.data.begin(), other.data.end()); }
};

struct Property {
  std::string name;
  std::uint32_t type;
  Bytes value;
};
inline Property text_property(const std::string& name, const std::string& value,
                              bool big_endian = false) {
  Property p{name, kString, {{}, big_endian}};
  p.value.text(value);
  return p;
}
inline Property double_property(const std::string& name, double value, bool big_endian = false) {
  Property p{name, kDouble, {{}, big_endian}};
  p.value.put(value);
  return p;
}
inline Property i32_property(const std::string& name, std::int32_t value, bool big_endian = false) {
  Property p{name, kI32, {{}, big_endian}};
  p.value.put(value);
  return p;
}
// Little-endian: the fractions, then the seconds; big-endian: the seconds first.
inline Property time_property(const std::string& name, std::int64_t seconds_since_1904,
                              std::uint64_t fractions, bool big_endian = false) {
  Property p{name, kTimeStamp, {{}, big_endian}};
  if (big_endian) {
    p.value.put(seconds_since_1904);
    p.value.put(fractions);
  } else {
    p.value.put(fractions);
    p.value.put(seconds_since_1904);
  }
  return p;
}

// One object of a segment's metadata. raw: kNone (0xFFFFFFFF), kSame (0x00000000), kNew (an
// index with type and count), or kRawIndex (the 4 bytes `raw_index` as they are, e.g. a
// DAQmx index).
struct Object {
  enum Raw { kNone, kSame, kNew, kRawIndex } raw = kNone;
  std::string path;
  std::uint32_t type = kDouble;
  std::uint64_t count = 0;
  std::uint64_t string_bytes = 0;  // strings: the raw data's total size in bytes
  std::uint32_t raw_index = 0;
  Bytes index_tail;  // kRawIndex: what follows raw_index (a DAQmx index's body)
  std::vector<Property> properties;
};

// One scaler of a DAQmx raw data index: DAQmx's type code (0 U8, 1 I8, 2 U16, 3 I16, 4 U32,
// 5 I32, 6 U64, 7 I64, 8 SGL, 9 DBL), its raw buffer, its byte offset in the buffer's stride
// (a digital line scaler: its bit offset), its scale id.
struct DaqmxScalerSpec {
  std::uint32_t type, buffer, offset, scale_id;
};

// A channel of DAQmx raw data as DAQmx logging writes its raw data index: the bytes
// 69 12 00 00 (format-changing scalers) or 69 13 00 00 (digital line scalers), data type
// 0xFFFFFFFF, dimension 1, values per chunk, the scalers (20 bytes each; 17 for digital
// lines, whose sample format bitmap is one byte), the raw buffers' widths.
inline Object daqmx_channel(const std::string& path, std::uint64_t count,
                            const std::vector<DaqmxScalerSpec>& scalers,
                            const std::vector<std::uint32_t>& widths, bool digital,
                            std::vector<Property> properties = {}, bool big_endian = false) {
  Object object;
  object.raw = Object::kRawIndex;
  object.path = path;
  object.raw_index = digital ? 0x00001369u : 0x00001269u;
  Bytes& tail = object.index_tail;
  tail.big_endian = big_endian;
  tail.put<std::uint32_t>(0xFFFFFFFFu);
  tail.put<std::uint32_t>(1u);
  tail.put<std::uint64_t>(count);
  tail.put<std::uint32_t>(static_cast<std::uint32_t>(scalers.size()));
  for (const DaqmxScalerSpec& scaler : scalers) {
    tail.put<std::uint32_t>(scaler.type);
    tail.put<std::uint32_t>(scaler.buffer);
    tail.put<std::uint32_t>(scaler.offset);
    if (digital) {
      tail.put<std::uint8_t>(0);
    } else {
      tail.put<std::uint32_t>(0);
    }
    tail.put<std::uint32_t>(scaler.scale_id);
  }
  tail.put<std::uint32_t>(static_cast<std::uint32_t>(widths.size()));
  for (std::uint32_t width : widths) tail.put<std::uint32_t>(width);
  object.properties = std::move(properties);
  return object;
}

// A whole segment: the lead-in, the metadata (when the ToC says so) and `raw`, in the byte
// order the ToC gives. Throws std::logic_error for raw data, a property or an index tail
// written in the other order.
inline Bytes segment(std::uint32_t toc, const std::vector<Object>& objects, const Bytes& raw,
                     std::uint32_t version = 4713) {
  const bool big_endian = (toc & kTocBigEndian) != 0;
  const auto check = [big_endian](const Bytes& piece, const std::string& what) {
    if (!piece.data.empty() && piece.big_endian != big_endian) {
      throw std::logic_error("tdms_writer: " + what + " is in the other byte order");
    }
  };
  check(raw, "the raw data");
  Bytes meta;
  meta.big_endian = big_endian;
  if (toc & kTocMetaData) {
    meta.put<std::uint32_t>(static_cast<std::uint32_t>(objects.size()));
    for (const Object& object : objects) {
      meta.text(object.path);
      switch (object.raw) {
        case Object::kNone:
          meta.put<std::uint32_t>(0xFFFFFFFFu);
          break;
        case Object::kSame:
          meta.put<std::uint32_t>(0u);
          break;
        case Object::kRawIndex:
          check(object.index_tail, "the raw data index of " + object.path);
          meta.put<std::uint32_t>(object.raw_index);
          meta.append(object.index_tail);
          break;
        case Object::kNew:
          meta.put<std::uint32_t>(object.type == kString ? 28u : 20u);
          meta.put<std::uint32_t>(object.type);
          meta.put<std::uint32_t>(1u);
          meta.put<std::uint64_t>(object.count);
          if (object.type == kString) meta.put<std::uint64_t>(object.string_bytes);
          break;
      }
      meta.put<std::uint32_t>(static_cast<std::uint32_t>(object.properties.size()));
      for (const Property& property : object.properties) {
        check(property.value, "property " + property.name);
        meta.text(property.name);
        meta.put<std::uint32_t>(property.type);
        meta.append(property.value);
      }
    }
  }
  Bytes out;
  out.data = {'T', 'D', 'S', 'm'};
  out.put<std::uint32_t>(toc);  // always little-endian
  out.big_endian = big_endian;
  out.put<std::uint32_t>(version);
  out.put<std::uint64_t>(meta.data.size() + raw.data.size());
  out.put<std::uint64_t>(meta.data.size());
  out.append(meta);
  out.append(raw);
  return out;
}

}  // namespace doorbench::testing::tdms
