#pragma once
// The recording journal: an append-only file written while a session is recorded and
// converted to the HDF5 session when the recording ends (docs/crash-safety.md; the byte
// layout is in docs/session-format.md, "The recording journal").
//
// A header (magic, the session's description as JSON, its CRC-32) is followed by framed
// blocks, each with its type, length and CRC-32: the clock's start, scans, timed samples
// of polled channels (version 2), events, and an end mark. A writer killed at any moment leaves a
// valid prefix of frames, possibly followed by one torn frame; the reader stops at the first frame
// that is incomplete or fails its checksum and says how many bytes it did not use.
//
// Errors: JournalError, message starting with "PATH: ".
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/session_file.h"

namespace doorbench {

class JournalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The file ends inside the journal's header and no frame follows: the recording died while
// creating the journal, before its first scan.
class JournalHeaderIncomplete : public JournalError {
 public:
  using JournalError::JournalError;
};

// 2: timed-sample frames and the UTC time of the origin in the start frame; version 1
// journals (scans only) are still read.
inline constexpr int kJournalFormatVersion = 2;
inline constexpr char kJournalSuffix[] = ".journal";
inline constexpr char kJournalMagic[] = "DBJRNL\r\n";  // the first 8 bytes

// The journal beside a session: "PATH.journal".
std::filesystem::path journal_path_for(const std::filesystem::path& session_path);

// CLOCK_REALTIME ns as ISO 8601 UTC with nanoseconds: "2026-11-21T10:30:00.123456789Z".
std::string utc_iso8601_ns(std::int64_t realtime_ns);

// CRC-32 (IEEE 802.3: reflected polynomial 0xEDB88320, initial and final XOR 0xFFFFFFFF),
// zlib's crc32(), continuing from `crc`: crc32(b, crc32(a)) == crc32(a + b). Journals of
// every version use it. Thread-safe.
std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

// What the journal's header holds: everything the HDF5 session needs besides samples
// and events.
struct JournalHeader {
  SessionMetadata metadata;
  // First the counts channels on the scan clock (in every scans frame), then the polled
  // channels with explicit times (sample_rate_hz 0: in timed frames), each followed by its
  // latency channel "<name>_latency" (sensor_kind "poll_latency").
  std::vector<ChannelInfo> channels;
  std::vector<CalibrationRecord> calibrations;
  double scan_rate_hz = 0.0;
  std::string session_name;  // the session file's name (no folder) when recording began
  double flush_interval_s = 0.0;
  std::string backend;  // the backend's description
};

enum class FrameType : std::uint32_t {
  kStart = 1,
  kScans = 2,
  kEvent = 3,
  kEnd = 4,
  kTimed = 5,  // version 2
};

// How many of the header's channels are in the scans frames (the leading channels on a
// sample clock).
std::size_t scan_channel_count(const JournalHeader& header);

// Writes a journal. One thread appends; sync(), bytes_written() and syncs() may also be
// called from one other thread (the recorder's sync thread) while it does.
class JournalWriter {
 public:
  // Creates `path` (it must not exist), takes an exclusive lock on it (flock, released
  // when the process ends however it ends), writes the header and syncs file and folder.
  // `max_block_scans` and `max_timed_samples` size the frame buffer, so appending does
  // not allocate.
  JournalWriter(const std::filesystem::path& path, const JournalHeader& header,
                std::size_t max_block_scans, std::size_t max_timed_samples = 0);
  ~JournalWriter();  // closes (without syncing; call sync() first to keep the tail)
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;

  // The session clock's origin: CLOCK_MONOTONIC time (ns) of session time 0 (scan 0, or
  // the polled sources' start), and CLOCK_REALTIME (ns since 1970, UTC) at that moment
  // (0: unknown).
  void append_start(std::int64_t monotonic_ns, std::int64_t realtime_ns = 0);
  // `scan_count` scans from scan `first_scan`; counts[c * stride + s] is channel c, scan s.
  void append_scans(std::uint64_t first_scan, std::size_t scan_count, const std::int32_t* counts,
                    std::size_t stride);
  // `count` samples of explicit-time channel `channel` (an index into the header's
  // channels): session time and latency in ns, raw values.
  void append_timed(std::uint32_t channel, std::size_t count, const std::int64_t* time_ns,
                    const std::int64_t* latency_ns, const double* raw);
  void append_event(double time_s, std::string_view kind, std::string_view channel,
                    std::string_view detail);
  void append_end(std::uint64_t total_scans);
  // fdatasync: everything appended so far survives a power loss.
  void sync();
  void close();  // syncs and closes; idempotent

  const std::filesystem::path& path() const { return path_; }
  std::uint64_t bytes_written() const { return bytes_.load(std::memory_order_acquire); }
  std::uint64_t syncs() const { return syncs_.load(); }

 private:
  void write_frame(FrameType type, std::size_t payload_bytes);
  void write_all(const std::uint8_t* data, std::size_t size);

  std::filesystem::path path_;
  int fd_ = -1;
  std::size_t channels_;  // in scans frames
  std::size_t all_channels_;
  std::size_t max_timed_;            // samples per timed frame
  std::vector<std::uint8_t> frame_;  // 16-byte frame header + payload
  std::atomic<std::uint64_t> bytes_{0};
  std::atomic<std::uint64_t> syncs_{0};
};

// One frame as read back.
struct JournalFrame {
  FrameType type = FrameType::kScans;
  std::uint64_t offset = 0;  // of the frame in the file
  // kStart (realtime_ns 0 in version 1 journals)
  std::int64_t monotonic_ns = 0;
  std::int64_t realtime_ns = 0;
  // kScans: counts[c * scan_count + s]; kEnd: total scans in first_scan
  std::uint64_t first_scan = 0;
  std::size_t scan_count = 0;
  std::vector<std::int32_t> counts;
  // kEvent
  SessionEvent event;
  // kTimed: `channel` indexes the header's channels; scan_count samples
  std::uint32_t channel = 0;
  std::vector<std::int64_t> time_ns;
  std::vector<std::int64_t> latency_ns;
  std::vector<double> raw;
};

// Reads a journal frame by frame, without loading it whole.
class JournalReader {
 public:
  // Opens and reads the header; throws JournalError ("not a doorbench journal", "its
  // header is damaged ... at byte N", a newer version), JournalHeaderIncomplete.
  // A header whose fixed fields are damaged is rebuilt where the bytes allow it, and
  // header_repair() says what was repaired: a damaged magic (when the JSON text that
  // follows is a journal's), length field (the header ends where the first frame that
  // checks out begins, or at the end of the JSON text whose CRC matches), checksum field
  // (the JSON text parses and only one byte of the checksum differs), version field (the
  // JSON's own format_version), or one flipped bit of the JSON text (located by its CRC).
  explicit JournalReader(const std::filesystem::path& path);
  ~JournalReader();
  JournalReader(const JournalReader&) = delete;
  JournalReader& operator=(const JournalReader&) = delete;

  const JournalHeader& header() const { return header_; }
  int format_version() const { return version_; }
  // The next frame, or false at the end of the valid frames. After false, bytes_dropped()
  // and stop_reason() say what (if anything) followed the last valid frame.
  bool next(JournalFrame& frame);
  // Takes the file's current size, for a reader following a journal that is still being
  // written: next() then resumes at the end of the last valid frame (a frame that was
  // incomplete before may be whole now). Returns the size.
  std::uint64_t refresh();
  std::uint64_t valid_bytes() const { return offset_; }
  std::uint64_t file_bytes() const { return file_bytes_; }
  std::uint64_t bytes_dropped() const { return file_bytes_ - offset_; }
  const std::string& stop_reason() const { return stop_reason_; }  // "" at a clean end
  // After next() returned false with a stop reason: looks in the rest of the file for the
  // next frame whose header and CRC check out (a frame marker "DBFR" found byte by byte);
  // if there is one, next() continues there and the bytes skipped are returned, else 0
  // (what is left is a damaged tail) and nothing changes. Reads the rest of the file in
  // chunks of 1 MiB.
  std::uint64_t skip_to_next_frame();
  // "" when the header was intact; otherwise what was repaired ("its length field ...").
  const std::string& header_repair() const { return header_repair_; }

 private:
  bool fail(std::string reason);
  void read_header();
  std::string locate_header_json(std::uint32_t json_bytes, std::uint32_t json_crc);
  std::string read_bytes(std::uint64_t at, std::uint64_t count) const;
  bool frame_checks_out(std::uint64_t at, std::vector<std::uint8_t>& payload) const;
  std::uint64_t find_frame(std::uint64_t from) const;  // file_bytes_ when there is none
  void note_repair(const std::string& what);
  std::filesystem::path path_;
  int fd_ = -1;
  JournalHeader header_;
  int version_ = 0;
  std::uint64_t offset_ = 0;
  std::uint64_t file_bytes_ = 0;
  std::string stop_reason_;
  std::string header_repair_;
  std::vector<std::uint8_t> payload_;
};

}  // namespace doorbench
