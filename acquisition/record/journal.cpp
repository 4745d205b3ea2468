#include "acquisition/record/journal.h"

#include <fcntl.h>
#include <string.h>  // memmem
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <nlohmann/json.hpp>

#include "core/time_text.h"

namespace doorbench {

static_assert(std::endian::native == std::endian::little,
              "the journal is written in the host's byte order, which must be little-endian");

namespace {

constexpr std::array<char, 8> kMagic = {'D', 'B', 'J', 'R', 'N', 'L', '\r', '\n'};
static_assert(sizeof kJournalMagic == kMagic.size() + 1);
constexpr std::uint32_t kFrameMagic = 0x52464244;  // "DBFR" in the file
constexpr std::size_t kFrameHeaderBytes = 16;      // magic, type, payload length, CRC
// Larger payloads are garbage, not frames (a block of 2^20 scans of 64 channels is 256 MiB).
constexpr std::uint32_t kMaxPayloadBytes = 256u << 20;
constexpr std::uint32_t kMaxHeaderBytes = 64u << 20;

std::string errno_text(int error) {
  return std::strerror(error);
}

template <typename T>
void put(std::uint8_t*& out, T value) {
  std::memcpy(out, &value, sizeof value);
  out += sizeof value;
}

template <typename T>
T get(const std::uint8_t*& in) {
  T value;
  std::memcpy(&value, in, sizeof value);
  in += sizeof value;
  return value;
}

// JSON has no infinities; a channel's range may be ±inf ("unknown").
nlohmann::json number(double value) {
  if (std::isfinite(value)) return value;
  if (std::isnan(value)) return "nan";
  return value > 0 ? "inf" : "-inf";
}

double number_of(const nlohmann::json& value) {
  if (value.is_number()) return value.get<double>();
  const std::string text = value.get<std::string>();
  if (text == "inf") return INFINITY;
  if (text == "-inf") return -INFINITY;
  if (text == "nan") return NAN;
  throw std::invalid_argument("not a number: " + text);
}

std::string header_json(const JournalHeader& header) {
  nlohmann::json json;
  json["format"] = "doorbench-journal";
  json["format_version"] = kJournalFormatVersion;
  json["session_name"] = header.session_name;
  json["scan_rate_hz"] = header.scan_rate_hz;
  json["flush_interval_s"] = header.flush_interval_s;
  json["backend"] = header.backend;
  const SessionMetadata& m = header.metadata;
  json["metadata"] = {{"rig_name", m.rig_name},
                      {"rig_definition", m.rig_definition},
                      {"operator", m.operator_name},
                      {"product_id", m.product_id},
                      {"start_time_utc", m.start_time_utc},
                      {"software_version", m.software_version},
                      {"notes", m.notes}};
  json["channels"] = nlohmann::json::array();
  for (const ChannelInfo& c : header.channels) {
    json["channels"].push_back({{"name", c.name},
                                {"sensor_kind", c.sensor_kind},
                                {"sensor_serial", c.sensor_serial},
                                {"raw_type", c.raw_type == RawType::kCounts ? "counts" : "values"},
                                {"raw_unit", c.raw_unit},
                                {"raw_offset", number(c.raw_offset)},
                                {"raw_scale", number(c.raw_scale)},
                                {"range_min", number(c.range_min)},
                                {"range_max", number(c.range_max)},
                                {"unit", c.unit},
                                {"calibration_id", c.calibration_id},
                                {"sample_rate_hz", number(c.sample_rate_hz)},
                                {"first_sample_time_s", number(c.first_sample_time_s)}});
  }
  // Each record as its own JSON text, which is authoritative (as in the session).
  json["calibrations"] = nlohmann::json::array();
  for (const CalibrationRecord& r : header.calibrations) {
    json["calibrations"].push_back(to_json(r));
  }
  return json.dump();
}

JournalHeader parse_header(const std::string& text, const std::string& source) {
  const nlohmann::json json = nlohmann::json::parse(text);
  if (json.at("format").get<std::string>() != "doorbench-journal") {
    throw std::invalid_argument("format is not doorbench-journal");
  }
  JournalHeader header;
  header.session_name = json.at("session_name").get<std::string>();
  header.scan_rate_hz = number_of(json.at("scan_rate_hz"));
  header.flush_interval_s = number_of(json.at("flush_interval_s"));
  header.backend = json.at("backend").get<std::string>();
  const nlohmann::json& m = json.at("metadata");
  header.metadata.rig_name = m.at("rig_name").get<std::string>();
  header.metadata.rig_definition = m.at("rig_definition").get<std::string>();
  header.metadata.operator_name = m.at("operator").get<std::string>();
  header.metadata.product_id = m.at("product_id").get<std::string>();
  header.metadata.start_time_utc = m.at("start_time_utc").get<std::string>();
  header.metadata.software_version = m.at("software_version").get<std::string>();
  header.metadata.notes = m.at("notes").get<std::string>();
  for (const nlohmann::json& c : json.at("channels")) {
    ChannelInfo info;
    info.name = c.at("name").get<std::string>();
    info.sensor_kind = c.at("sensor_kind").get<std::string>();
    info.sensor_serial = c.at("sensor_serial").get<std::string>();
    info.raw_type =
        c.at("raw_type").get<std::string>() == "counts" ? RawType::kCounts : RawType::kValues;
    info.raw_unit = c.at("raw_unit").get<std::string>();
    info.raw_offset = number_of(c.at("raw_offset"));
    info.raw_scale = number_of(c.at("raw_scale"));
    info.range_min = number_of(c.at("range_min"));
    info.range_max = number_of(c.at("range_max"));
    info.unit = c.at("unit").get<std::string>();
    info.calibration_id = c.at("calibration_id").get<std::string>();
    info.sample_rate_hz = number_of(c.at("sample_rate_hz"));
    info.first_sample_time_s = number_of(c.at("first_sample_time_s"));
    header.channels.push_back(info);
  }
  for (const nlohmann::json& r : json.at("calibrations")) {
    header.calibrations.push_back(calibration_record_from_json(r.get<std::string>(), source));
  }
  // Within the rig file's limits (docs/rig-format.md): a damaged header must not make
  // recovery's clock arithmetic or gap filling unbounded.
  // (0: no DAQ, only polled channels with explicit times.)
  if (!(header.scan_rate_hz == 0.0 ||
        (header.scan_rate_hz >= 1.0 && header.scan_rate_hz <= 200000.0))) {
    char rate[32];
    std::snprintf(rate, sizeof rate, "%g", header.scan_rate_hz);
    throw std::invalid_argument(std::string("scan_rate_hz ") + rate +
                                " is not 0 (no DAQ) or from 1 to 200000 Hz");
  }
  return header;
}

}  // namespace

std::string utc_iso8601_ns(std::int64_t realtime_ns) {
  std::int64_t seconds = realtime_ns / 1000000000;
  std::int64_t nanoseconds = realtime_ns % 1000000000;
  if (nanoseconds < 0) {
    nanoseconds += 1000000000;
    --seconds;
  }
  return iso8601_utc_text(seconds, nanoseconds, 9);
}

std::size_t scan_channel_count(const JournalHeader& header) {
  std::size_t count = 0;
  while (count < header.channels.size() && header.channels[count].sample_rate_hz > 0) ++count;
  return count;
}

std::filesystem::path journal_path_for(const std::filesystem::path& session_path) {
  std::filesystem::path journal = session_path;
  journal += kJournalSuffix;
  return journal;
}

std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
  return static_cast<std::uint32_t>(::crc32_z(crc, bytes.data(), bytes.size()));
}

// ---------------------------------------------------------------------------------------
// Writer

JournalWriter::JournalWriter(const std::filesystem::path& path, const JournalHeader& header,
                             std::size_t max_block_scans, std::size_t max_timed_samples)
    : path_(path),
      channels_(scan_channel_count(header)),
      all_channels_(header.channels.size()),
      max_timed_(max_timed_samples) {
  if (header.channels.empty()) throw std::invalid_argument(path.string() + ": no channels");
  for (std::size_t c = channels_; c < all_channels_; ++c) {
    if (header.channels[c].sample_rate_hz != 0) {
      throw std::invalid_argument(path.string() + ": channel " + header.channels[c].name +
                                  " has a sample clock but follows explicit-time channels");
    }
  }
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    const int error = errno;
    throw JournalError(path.string() + ": cannot create the journal: " + errno_text(error));
  }
  try {
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      throw JournalError(path.string() + ": cannot lock the journal: " + errno_text(errno));
    }
    const std::size_t largest_event = 8 + 3 * 4 + 4096;
    frame_.resize(kFrameHeaderBytes +
                  std::max({16 + max_block_scans * channels_ * sizeof(std::int32_t),
                            8 + max_timed_samples * 24, largest_event}));
    const std::string json = header_json(header);
    std::vector<std::uint8_t> head(kMagic.size() + 12 + json.size());
    std::uint8_t* out = head.data();
    std::memcpy(out, kMagic.data(), kMagic.size());
    out += kMagic.size();
    put<std::uint32_t>(out, kJournalFormatVersion);
    put<std::uint32_t>(out, static_cast<std::uint32_t>(json.size()));
    put<std::uint32_t>(out,
                       crc32({reinterpret_cast<const std::uint8_t*>(json.data()), json.size()}));
    std::memcpy(out, json.data(), json.size());
    write_all(head.data(), head.size());
    sync();
    // The new name must survive a power loss too.
    const std::filesystem::path folder =
        path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
    const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir >= 0) {
      ::fsync(dir);
      ::close(dir);
    }
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
    throw;
  }
}

JournalWriter::~JournalWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void JournalWriter::write_all(const std::uint8_t* data, std::size_t size) {
  while (size > 0) {
    const ssize_t written = ::write(fd_, data, size);
    if (written < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      throw JournalError(path_.string() + ": cannot write the journal: " + errno_text(error));
    }
    data += written;
    size -= static_cast<std::size_t>(written);
    bytes_.fetch_add(static_cast<std::uint64_t>(written), std::memory_order_release);
  }
}

void JournalWriter::write_frame(FrameType type, std::size_t payload_bytes) {
  if (fd_ < 0) throw std::logic_error(path_.string() + ": the journal is closed");
  std::uint8_t* out = frame_.data();
  put<std::uint32_t>(out, kFrameMagic);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(type));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(payload_bytes));
  // The CRC covers type, length and payload: a frame is whole or it is dropped.
  std::uint32_t crc = crc32({frame_.data() + 4, 8});
  crc = crc32({frame_.data() + kFrameHeaderBytes, payload_bytes}, crc);
  put<std::uint32_t>(out, crc);
  write_all(frame_.data(), kFrameHeaderBytes + payload_bytes);
}

void JournalWriter::append_start(std::int64_t monotonic_ns, std::int64_t realtime_ns) {
  std::uint8_t* out = frame_.data() + kFrameHeaderBytes;
  put<std::int64_t>(out, monotonic_ns);
  put<std::int64_t>(out, realtime_ns);
  write_frame(FrameType::kStart, 16);
}

void JournalWriter::append_timed(std::uint32_t channel, std::size_t count,
                                 const std::int64_t* time_ns, const std::int64_t* latency_ns,
                                 const double* raw) {
  const std::size_t payload = 8 + count * 24;
  if (channel < channels_ || channel >= all_channels_) {
    throw std::invalid_argument(path_.string() + ": channel index " + std::to_string(channel) +
                                " is not an explicit-time channel of the journal");
  }
  if (count > max_timed_ || kFrameHeaderBytes + payload > frame_.size()) {
    throw std::invalid_argument(path_.string() + ": a block of " + std::to_string(count) +
                                " timed samples is larger than the journal was made for");
  }
  std::uint8_t* out = frame_.data() + kFrameHeaderBytes;
  put<std::uint32_t>(out, channel);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(count));
  std::memcpy(out, time_ns, count * 8);
  out += count * 8;
  std::memcpy(out, latency_ns, count * 8);
  out += count * 8;
  std::memcpy(out, raw, count * 8);
  write_frame(FrameType::kTimed, payload);
}

void JournalWriter::append_scans(std::uint64_t first_scan, std::size_t scan_count,
                                 const std::int32_t* counts, std::size_t stride) {
  const std::size_t payload = 16 + scan_count * channels_ * sizeof(std::int32_t);
  if (kFrameHeaderBytes + payload > frame_.size() || scan_count > stride) {
    throw std::invalid_argument(path_.string() + ": a block of " + std::to_string(scan_count) +
                                " scans is larger than the journal was made for");
  }
  std::uint8_t* out = frame_.data() + kFrameHeaderBytes;
  put<std::uint64_t>(out, first_scan);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(scan_count));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(channels_));
  for (std::size_t c = 0; c < channels_; ++c) {
    std::memcpy(out, counts + c * stride, scan_count * sizeof(std::int32_t));
    out += scan_count * sizeof(std::int32_t);
  }
  write_frame(FrameType::kScans, payload);
}

void JournalWriter::append_event(double time_s, std::string_view kind, std::string_view channel,
                                 std::string_view detail) {
  // Texts are cut to 4 KiB in all, so an event always fits the frame buffer.
  const std::size_t kind_bytes = std::min<std::size_t>(kind.size(), 256);
  const std::size_t channel_bytes = std::min<std::size_t>(channel.size(), 256);
  const std::size_t detail_bytes = std::min<std::size_t>(detail.size(), 3584);
  std::uint8_t* out = frame_.data() + kFrameHeaderBytes;
  put<double>(out, time_s);
  for (const auto& [text, bytes] : {std::pair{kind, kind_bytes}, std::pair{channel, channel_bytes},
                                    std::pair{detail, detail_bytes}}) {
    put<std::uint32_t>(out, static_cast<std::uint32_t>(bytes));
    std::memcpy(out, text.data(), bytes);
    out += bytes;
  }
  write_frame(FrameType::kEvent, static_cast<std::size_t>(out - frame_.data()) - kFrameHeaderBytes);
}

void JournalWriter::append_end(std::uint64_t total_scans) {
  std::uint8_t* out = frame_.data() + kFrameHeaderBytes;
  put<std::uint64_t>(out, total_scans);
  write_frame(FrameType::kEnd, 8);
}

void JournalWriter::sync() {
  if (fd_ < 0) return;
  if (::fdatasync(fd_) != 0) {
    const int error = errno;
    throw JournalError(path_.string() + ": cannot sync the journal: " + errno_text(error));
  }
  ++syncs_;
}

void JournalWriter::close() {
  if (fd_ < 0) return;
  sync();
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) {
    const int error = errno;
    throw JournalError(path_.string() + ": cannot close the journal: " + errno_text(error));
  }
}

// ---------------------------------------------------------------------------------------
// Reader

JournalReader::JournalReader(const std::filesystem::path& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) {
    const int error = errno;
    throw JournalError(path.string() + ": " +
                       (error == ENOENT ? std::string("no such file") : errno_text(error)));
  }
  struct stat status {};
  ::fstat(fd_, &status);
  file_bytes_ = static_cast<std::uint64_t>(status.st_size);
  try {
    read_header();
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

namespace {

constexpr std::uint64_t kHeadBytes = kMagic.size() + 12;

// The raw CRC register (no initial or final XOR) of the byte `value` followed by zeros:
// by CRC-32's linearity, crc32(a) ^ crc32(a with that byte XORed by `value` at the
// position k bytes before the end) is the register after k more zero bytes.
std::uint32_t crc_register_of(std::uint32_t value) {
  for (int bit = 0; bit < 8; ++bit) value = (value & 1u) ? (value >> 1) ^ 0xEDB88320u : value >> 1;
  return value;
}

// The one flipped bit that makes `text` match `crc`: its byte index and bit, or -1.
std::pair<long long, int> single_flipped_bit(const std::string& text, std::uint32_t crc) {
  const std::uint32_t difference =
      crc32({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}) ^ crc;
  if (difference == 0) return {-1, 0};
  std::array<std::uint32_t, 8> registers{};
  for (int bit = 0; bit < 8; ++bit) registers[bit] = crc_register_of(1u << bit);
  for (std::size_t after = 0; after < text.size(); ++after) {
    for (int bit = 0; bit < 8; ++bit) {
      if (registers[bit] == difference) {
        return {static_cast<long long>(text.size() - 1 - after), bit};
      }
      registers[bit] = crc_register_of(registers[bit] & 0xFFu) ^ (registers[bit] >> 8);
    }
  }
  return {-1, 0};
}

// Differs from `crc` in one byte of the checksum field only (that field was damaged).
bool differs_in_one_byte(std::uint32_t a, std::uint32_t b) {
  const std::uint32_t difference = a ^ b;
  for (int byte = 0; byte < 4; ++byte) {
    if ((difference & ~(0xFFu << (8 * byte))) == 0) return true;
  }
  return false;
}

}  // namespace

std::string JournalReader::read_bytes(std::uint64_t at, std::uint64_t count) const {
  std::string bytes(count, '\0');
  if (count > 0 &&
      ::pread(fd_, bytes.data(), count, static_cast<off_t>(at)) != static_cast<ssize_t>(count)) {
    throw JournalError(path_.string() + ": cannot read " + std::to_string(count) +
                       " bytes at byte " + std::to_string(at) + ": " + errno_text(errno));
  }
  return bytes;
}

void JournalReader::note_repair(const std::string& what) {
  header_repair_ += (header_repair_.empty() ? "" : "; ") + what;
}

bool JournalReader::frame_checks_out(std::uint64_t at, std::vector<std::uint8_t>& payload) const {
  if (at + kFrameHeaderBytes > file_bytes_) return false;
  std::array<std::uint8_t, kFrameHeaderBytes> head{};
  if (::pread(fd_, head.data(), head.size(), static_cast<off_t>(at)) !=
      static_cast<ssize_t>(head.size())) {
    return false;
  }
  const std::uint8_t* in = head.data();
  const auto magic = get<std::uint32_t>(in);
  const auto type = get<std::uint32_t>(in);
  const auto payload_bytes = get<std::uint32_t>(in);
  const auto crc = get<std::uint32_t>(in);
  if (magic != kFrameMagic || type < 1 || type > 5 || payload_bytes > kMaxPayloadBytes ||
      file_bytes_ - at - kFrameHeaderBytes < payload_bytes) {
    return false;
  }
  payload.resize(payload_bytes);
  if (::pread(fd_, payload.data(), payload_bytes, static_cast<off_t>(at + kFrameHeaderBytes)) !=
      static_cast<ssize_t>(payload_bytes)) {
    return false;
  }
  return crc32(payload, crc32({head.data() + 4, 8})) == crc;
}

std::uint64_t JournalReader::find_frame(std::uint64_t from) const {
  constexpr std::size_t kChunk = 1u << 20;
  std::vector<std::uint8_t> chunk, payload;
  for (std::uint64_t at = from; at + kFrameHeaderBytes <= file_bytes_; at += kChunk) {
    // 3 bytes more, so that a marker across two chunks is found.
    const auto size =
        static_cast<std::size_t>(std::min<std::uint64_t>(kChunk + 3, file_bytes_ - at));
    chunk.resize(size);
    if (::pread(fd_, chunk.data(), size, static_cast<off_t>(at)) != static_cast<ssize_t>(size)) {
      return file_bytes_;
    }
    const std::uint8_t* begin = chunk.data();
    const std::uint8_t* const end = chunk.data() + size;
    while (begin < end) {
      const void* found = ::memmem(begin, static_cast<std::size_t>(end - begin), "DBFR", 4);
      if (found == nullptr) break;
      const auto index =
          static_cast<std::size_t>(static_cast<const std::uint8_t*>(found) - chunk.data());
      if (index >= kChunk) break;  // the next chunk starts there
      if (frame_checks_out(at + index, payload)) return at + index;
      begin = static_cast<const std::uint8_t*>(found) + 1;
    }
  }
  return file_bytes_;
}

std::uint64_t JournalReader::skip_to_next_frame() {
  if (stop_reason_.empty() || offset_ >= file_bytes_) return 0;
  const std::uint64_t found = find_frame(offset_ + 1);
  if (found >= file_bytes_) return 0;
  const std::uint64_t skipped = found - offset_;
  offset_ = found;
  return skipped;
}

// The JSON text of the header, found by its CRC; its end is where the frames begin.
std::string JournalReader::locate_header_json(std::uint32_t json_bytes, std::uint32_t json_crc) {
  const auto matches = [&](const std::string& text) {
    return crc32({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}) == json_crc;
  };
  const bool length_plausible =
      json_bytes <= kMaxHeaderBytes && kHeadBytes + json_bytes <= file_bytes_;
  std::string by_length;
  if (length_plausible) {
    by_length = read_bytes(kHeadBytes, json_bytes);
    if (matches(by_length)) return by_length;
  }
  const std::uint64_t first_frame = find_frame(kHeadBytes);
  if (first_frame >= file_bytes_ && !length_plausible) {
    throw JournalHeaderIncomplete(
        path_.string() +
        ": the journal's header is incomplete (the recording died while creating it)");
  }
  const std::string before_frames =
      read_bytes(kHeadBytes, std::min<std::uint64_t>(first_frame - kHeadBytes, kMaxHeaderBytes));
  const auto length_repaired = [&](std::size_t size) {
    note_repair("its length field (bytes 12-15) said " + std::to_string(json_bytes) +
                " bytes, but the header's text is " + std::to_string(size) +
                " bytes long (ending at byte " + std::to_string(kHeadBytes + size) + ")");
  };
  // The text ends at the first frame, or (a damaged first frame) at a closing brace: one
  // pass, the CRC continued from brace to brace.
  std::uint32_t running = 0;
  std::size_t done = 0;
  for (std::size_t size = 1; size <= before_frames.size(); ++size) {
    if (before_frames[size - 1] != '}' && size != before_frames.size()) continue;
    running = crc32(
        {reinterpret_cast<const std::uint8_t*>(before_frames.data()) + done, size - done}, running);
    done = size;
    if (running != json_crc) continue;
    if (size != json_bytes) length_repaired(size);
    return before_frames.substr(0, size);
  }
  // One flipped bit (the checksum locates it), or a damaged checksum field.
  for (const std::string* candidate :
       std::array<const std::string*, 2>{&by_length, &before_frames}) {
    if (candidate->empty()) continue;
    std::string text = *candidate;
    const auto [at, bit] = single_flipped_bit(text, json_crc);
    if (at >= 0) {
      text[static_cast<std::size_t>(at)] =
          static_cast<char>(text[static_cast<std::size_t>(at)] ^ (1 << bit));
      if (text.size() != json_bytes) length_repaired(text.size());
      note_repair("bit " + std::to_string(bit) + " of byte " + std::to_string(kHeadBytes + at) +
                  " was flipped (found by the header's checksum) and is set right");
      return text;
    }
    const std::uint32_t crc =
        crc32({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
    if (differs_in_one_byte(crc, json_crc) && nlohmann::json::accept(text)) {
      if (text.size() != json_bytes) length_repaired(text.size());
      note_repair("its checksum field (bytes 16-19) is damaged; the text it covers is whole");
      return text;
    }
  }
  std::string where = "bytes " + std::to_string(kHeadBytes) + "-" +
                      std::to_string(kHeadBytes + before_frames.size());
  try {
    const nlohmann::json parsed = nlohmann::json::parse(before_frames);
  } catch (const nlohmann::json::parse_error& error) {
    where += ", first unreadable at byte " + std::to_string(kHeadBytes + error.byte - 1);
  }
  throw JournalError(path_.string() + ": the journal's header is damaged (" + where +
                     ": checksum mismatch, more than one flipped bit); the frames from byte " +
                     std::to_string(first_frame) +
                     " on check out, but their channels, scan rate and calibration are described "
                     "only in the header, so they cannot be recovered without it; the journal is "
                     "left as it is");
}

void JournalReader::read_header() {
  const auto damaged = [&](const std::string& why) {
    return JournalError(path_.string() + ": " + why);
  };
  std::array<std::uint8_t, kHeadBytes> head{};
  const ssize_t got = ::pread(fd_, head.data(), head.size(), 0);
  if (got < 0) throw damaged(errno_text(errno));
  const auto have = static_cast<std::size_t>(got);
  const bool magic_ok =
      have >= kMagic.size() && std::memcmp(head.data(), kMagic.data(), kMagic.size()) == 0;
  if (have < head.size()) {
    if (std::memcmp(head.data(), kMagic.data(), std::min(have, kMagic.size())) == 0) {
      throw JournalHeaderIncomplete(
          damaged("the journal's header is incomplete (the recording died while creating it)")
              .what());
    }
    throw damaged("not a doorbench journal");
  }
  if (!magic_ok) {
    // A damaged magic, or not a journal at all: the JSON text that follows says.
    const std::string start =
        read_bytes(kHeadBytes, std::min<std::uint64_t>(file_bytes_ - kHeadBytes, 4096));
    if (start.empty() || start[0] != '{' ||
        start.find("\"doorbench-journal\"") == std::string::npos) {
      throw damaged("not a doorbench journal");
    }
    note_repair("its magic (bytes 0-7) is damaged; the text after it is a journal's header");
  }
  const std::uint8_t* in = head.data() + kMagic.size();
  const auto version = get<std::uint32_t>(in);
  const auto json_bytes = get<std::uint32_t>(in);
  const auto json_crc = get<std::uint32_t>(in);
  const auto newer = [&](std::uint64_t v) {
    return damaged("journal format version " + std::to_string(v) +
                   " is newer than this doorbench (" + std::to_string(kJournalFormatVersion) + ")");
  };
  std::string json;
  try {
    json = locate_header_json(json_bytes, json_crc);
  } catch (const JournalHeaderIncomplete&) {
    if (version > static_cast<std::uint32_t>(kJournalFormatVersion) && version < 256)
      throw newer(version);
    throw;
  } catch (const JournalError&) {
    if (version > static_cast<std::uint32_t>(kJournalFormatVersion) && version < 256)
      throw newer(version);
    throw;
  }
  std::uint64_t own_version = version;
  try {
    const nlohmann::json parsed = nlohmann::json::parse(json);
    if (parsed.contains("format_version") && parsed["format_version"].is_number_unsigned()) {
      own_version = parsed["format_version"].get<std::uint64_t>();
    }
  } catch (const std::exception&) {
    // parse_header below says what is wrong
  }
  const auto known = [](std::uint64_t v) {
    return v >= 1 && v <= static_cast<std::uint64_t>(kJournalFormatVersion);
  };
  if (known(version)) {
    own_version = version;  // the field decides the frames' layout
  } else if (known(own_version)) {
    note_repair("its version field (bytes 8-11) said " + std::to_string(version) +
                "; the header's text says format_version " + std::to_string(own_version));
  } else if (version > static_cast<std::uint32_t>(kJournalFormatVersion)) {
    throw newer(version);
  } else {
    throw damaged("its version field (bytes 8-11) says " + std::to_string(version) +
                  ", which no doorbench writes");
  }
  try {
    header_ = parse_header(json, path_.string() + " (journal header)");
  } catch (const std::exception& error) {
    throw damaged(std::string("the journal's header is not valid: ") + error.what());
  }
  version_ = static_cast<int>(own_version);
  offset_ = kHeadBytes + json.size();
}

JournalReader::~JournalReader() {
  if (fd_ >= 0) ::close(fd_);
}

std::uint64_t JournalReader::refresh() {
  struct stat status {};
  if (fd_ >= 0 && ::fstat(fd_, &status) == 0) {
    file_bytes_ = static_cast<std::uint64_t>(status.st_size);
  }
  stop_reason_.clear();
  return file_bytes_;
}

bool JournalReader::fail(std::string reason) {
  stop_reason_ = std::move(reason);
  return false;
}

bool JournalReader::next(JournalFrame& frame) {
  if (offset_ >= file_bytes_) return false;
  const std::string at = " at byte " + std::to_string(offset_);
  if (file_bytes_ - offset_ < kFrameHeaderBytes) return fail("incomplete frame header" + at);
  std::array<std::uint8_t, kFrameHeaderBytes> head{};
  if (::pread(fd_, head.data(), head.size(), static_cast<off_t>(offset_)) !=
      static_cast<ssize_t>(head.size())) {
    return fail("cannot read" + at + ": " + errno_text(errno));
  }
  const std::uint8_t* in = head.data();
  const auto magic = get<std::uint32_t>(in);
  const auto type = get<std::uint32_t>(in);
  const auto payload_bytes = get<std::uint32_t>(in);
  const auto crc = get<std::uint32_t>(in);
  if (magic != kFrameMagic) return fail("no frame" + at + " (damaged or unwritten bytes)");
  if (payload_bytes > kMaxPayloadBytes) return fail("implausible frame length" + at);
  if (file_bytes_ - offset_ - kFrameHeaderBytes < payload_bytes) {
    return fail("incomplete frame" + at + " (" + std::to_string(payload_bytes) +
                " bytes of data announced, " +
                std::to_string(file_bytes_ - offset_ - kFrameHeaderBytes) + " present)");
  }
  payload_.resize(payload_bytes);
  if (::pread(fd_, payload_.data(), payload_bytes,
              static_cast<off_t>(offset_ + kFrameHeaderBytes)) !=
      static_cast<ssize_t>(payload_bytes)) {
    return fail("cannot read" + at + ": " + errno_text(errno));
  }
  std::uint32_t check = crc32({head.data() + 4, 8});
  check = crc32(payload_, check);
  if (check != crc) return fail("checksum mismatch in the frame" + at);

  frame.type = static_cast<FrameType>(type);
  frame.offset = offset_;
  in = payload_.data();
  const std::uint8_t* const end = payload_.data() + payload_.size();
  const auto has = [&](std::size_t bytes) { return static_cast<std::size_t>(end - in) >= bytes; };
  switch (frame.type) {
    case FrameType::kStart:
      // Version 1: the monotonic time only.
      if (payload_bytes != 8 && payload_bytes != 16) return fail("malformed start frame" + at);
      frame.monotonic_ns = get<std::int64_t>(in);
      frame.realtime_ns = payload_bytes == 16 ? get<std::int64_t>(in) : 0;
      break;
    case FrameType::kTimed: {
      if (!has(8)) return fail("malformed timed frame" + at);
      frame.channel = get<std::uint32_t>(in);
      frame.scan_count = get<std::uint32_t>(in);
      const std::size_t scan_channels = scan_channel_count(header_);
      if (frame.channel < scan_channels || frame.channel >= header_.channels.size() ||
          payload_bytes != 8 + std::uint64_t{frame.scan_count} * 24) {
        return fail("malformed timed frame" + at);
      }
      frame.time_ns.resize(frame.scan_count);
      frame.latency_ns.resize(frame.scan_count);
      frame.raw.resize(frame.scan_count);
      std::memcpy(frame.time_ns.data(), in, frame.scan_count * 8);
      std::memcpy(frame.latency_ns.data(), in + frame.scan_count * 8, frame.scan_count * 8);
      std::memcpy(frame.raw.data(), in + frame.scan_count * 16, frame.scan_count * 8);
      break;
    }
    case FrameType::kEnd:
      if (payload_bytes != 8) return fail("malformed end frame" + at);
      frame.first_scan = get<std::uint64_t>(in);
      break;
    case FrameType::kScans: {
      if (!has(16)) return fail("malformed scans frame" + at);
      frame.first_scan = get<std::uint64_t>(in);
      frame.scan_count = get<std::uint32_t>(in);
      const auto channels = get<std::uint32_t>(in);
      if (channels != scan_channel_count(header_) ||
          payload_bytes != 16 + std::uint64_t{channels} * frame.scan_count * 4) {
        return fail("malformed scans frame" + at);
      }
      frame.counts.resize(std::size_t{channels} * frame.scan_count);
      std::memcpy(frame.counts.data(), in, frame.counts.size() * sizeof(std::int32_t));
      break;
    }
    case FrameType::kEvent: {
      if (!has(8)) return fail("malformed event frame" + at);
      frame.event.time_s = get<double>(in);
      for (std::string* text : {&frame.event.kind, &frame.event.channel, &frame.event.detail}) {
        if (!has(4)) return fail("malformed event frame" + at);
        const auto bytes = get<std::uint32_t>(in);
        if (!has(bytes)) return fail("malformed event frame" + at);
        text->assign(reinterpret_cast<const char*>(in), bytes);
        in += bytes;
      }
      break;
    }
    default:
      return fail("unknown frame type " + std::to_string(type) + at);
  }
  offset_ += kFrameHeaderBytes + payload_bytes;
  return true;
}

}  // namespace doorbench
