#pragma once
// The session file: HDF5, one per recording, the one exchange format between every part
// of doorbench. It keeps the channels' samples as acquired (DAQ counts, or values as
// imported), their times on one session clock, the calibration records they use (in
// full), events, and groups for derived results and (simulated sessions) the truth.
// The layout is in docs/session-format.md; plain HDF5 tools read it without doorbench.
//
// Errors: SessionError for the file (cannot create, read or write it, not a session, no
// such channel or group); std::invalid_argument for arguments the writer refuses;
// std::logic_error for use of a closed writer. Every message starts with "PATH: ".
//
// Thread safety: a writer or reader is used by one thread at a time. Different writers
// and readers may be used from different threads (Debian's HDF5 is built thread-safe and
// serializes them). Reading a session while its writer has it open is not supported.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"

namespace doorbench {

class SessionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;  // messages start with the file's path
};

inline constexpr int kSessionFormatVersion = 1;

struct SessionMetadata {
  std::string rig_name;
  std::string rig_definition;  // the rig file's whole text
  std::string operator_name;
  std::string product_id;      // the door or product under test
  std::string start_time_utc;  // ISO 8601, e.g. 2026-11-21T10:30:00Z
  std::string software_version;
  std::string notes;
};

enum class RawType { kCounts, kValues };  // int32 DAQ counts, or float64 values

// The raw count that marks a lost scan (a ring overflow kept on the clock by the recorder,
// docs/crash-safety.md): outside every DAQ's range of counts. It is never a measurement:
// every reader gives such a sample as missing (NaN), never as a number.
inline constexpr std::int32_t kGapFillCount = std::numeric_limits<std::int32_t>::min();

struct ChannelInfo {
  std::string name;         // unique, [A-Za-z0-9_]+
  std::string sensor_kind;  // load_cell | inclinometer | gyroscope | imported | ...
  std::string sensor_serial;
  RawType raw_type = RawType::kCounts;
  std::string raw_unit = "counts";  // "counts", "V", or a physical unit for imports
  // signal (V, or raw_unit for values) = raw_offset + raw_scale · raw
  double raw_offset = 0.0;
  double raw_scale = 1.0;
  double range_min = -10.0;  // the signal's valid range (V for DAQ channels)
  double range_max = 10.0;
  std::string unit;            // physical unit after calibration
  std::string calibration_id;  // empty: the signal already is the physical value
  // Sample times: uniform, time of sample i = first_sample_time_s + i / sample_rate_hz
  // (first_sample_time_s includes the converter's skew); or, when sample_rate_hz is 0,
  // explicit times appended with the samples.
  double sample_rate_hz = 1000.0;
  double first_sample_time_s = 0.0;
  // Load cells: the geometry record (sensor_kind "geometry": handle radius and the cell's
  // mounting angle) that readers of the session for analysis apply on top; empty: none.
  std::string geometry_calibration_id{};
};

struct SessionEvent {
  double time_s = 0.0;
  std::string kind;     // trigger | stroke_start | stroke_end | mark | fault | gap
  std::string channel;  // empty when it concerns the whole session
  std::string detail;   // e.g. "opening" / "closing" for strokes, a fault's message
};

struct SessionWriterOptions {
  std::size_t chunk_samples = 16384;  // HDF5 chunk and write-buffer size per channel, 1…2^24
  int deflate_level = 0;              // 0: no compression (fastest); 1-9: shuffle + gzip
  std::string validate() const;       // empty when usable
};

class SessionWriter {
 public:
  // Creates `path` (an existing file is an error: sessions are never overwritten) and
  // writes the metadata. If creating fails half-way, the incomplete file is removed.
  SessionWriter(const std::filesystem::path& path, const SessionMetadata& metadata,
                const SessionWriterOptions& options = {});
  // Closes if close() was not called (keeping what was recorded); never throws: a failure
  // is printed as one line on stderr.
  ~SessionWriter();
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  // Declares a channel; returns its index (0, 1, … in the order added). A channel may be
  // added at any time, also after other channels have samples (each has its own clock).
  // Explicit-time channels (sample_rate_hz 0) hold values, not counts.
  int add_channel(const ChannelInfo& channel);
  // Stores a record in full. Adding the same record again is allowed; a different record
  // with the same id is not. A channel's record must be added before that channel's first
  // sample (or, for a channel without samples, before close()); when both give a unit,
  // the channel's unit must be the record's.
  void add_calibration(const CalibrationRecord& record);

  // Buffered; memory stays bounded (one chunk per channel). The call must match the
  // channel: append_counts for counts, append_values for values on a uniform clock,
  // append_timed_values for explicit times.
  void append_counts(int channel, std::span<const std::int32_t> counts);
  void append_values(int channel, std::span<const double> values);
  // For channels with sample_rate_hz == 0: finite times, strictly increasing (also across
  // calls), as many as values.
  void append_timed_values(int channel, std::span<const double> time_s,
                           std::span<const double> values);
  // Stored in the order added (not sorted). A non-empty `channel` must be a channel of
  // the session; kind must not be empty.
  void add_event(const SessionEvent& event);

  // A derived or side group (e.g. "results/fit-1", "truth"; parents are created): 1-D
  // float64 datasets and text attributes, each written once. By convention an attribute
  // `uses` names the data the group was computed from. The groups the session writes
  // itself (metadata, channels, calibrations, events) are refused.
  void write_group_dataset(const std::string& group, const std::string& name,
                           std::span<const double> values);
  void write_group_attribute(const std::string& group, const std::string& name,
                             const std::string& text);

  // Flushes everything and closes the file; throws SessionError on failure (the file is
  // closed all the same). Any later call throws std::logic_error.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct ChannelSlice {
  std::size_t first_index = 0;  // of raw[0]; for an empty slice, where it would start
  std::vector<double> time_s;
  std::vector<double> raw;  // counts are exact in a double
};

// True when `raw` of a sample of `channel` is missing: a counts channel's mark of a lost
// scan (kGapFillCount), or a values channel's NaN (an imported empty cell). Readers give
// such a sample as NaN.
inline bool is_lost_sample(const ChannelInfo& channel, double raw) {
  return channel.raw_type == RawType::kCounts ? raw == static_cast<double>(kGapFillCount)
                                              : std::isnan(raw);
}

// A run of lost samples of one channel: indices [first_index, first_index + count), times
// of the first and last lost sample.
struct LostRun {
  std::size_t first_index = 0;
  std::size_t count = 0;
  double first_time_s = 0.0;
  double last_time_s = 0.0;
};
// The runs of lost samples in a slice of `channel`, in order.
std::vector<LostRun> lost_runs(const ChannelInfo& channel, const ChannelSlice& slice);

// A problem of a session as a whole, named on one line (SessionReader::problems()).
struct SessionProblem {
  std::string message;  // names the channel (printable) and what is wrong
  // The session cannot be used as it is: export and fit refuse it. Otherwise a warning.
  bool unusable = false;
};

class SessionReader {
 public:
  // Opens read-only and loads metadata, channel infos, events and calibration records
  // (samples stay on disk). Throws SessionError.
  explicit SessionReader(const std::filesystem::path& path);
  ~SessionReader();
  // A moved-from reader may only be destroyed or assigned to.
  SessionReader(SessionReader&&) noexcept;
  SessionReader& operator=(SessionReader&&) noexcept;

  const std::filesystem::path& path() const;
  const SessionMetadata& metadata() const;
  const std::vector<ChannelInfo>& channels() const;  // in the order they were added
  // An unknown name throws SessionError naming it and listing the channels.
  const ChannelInfo& channel(const std::string& name) const;
  std::size_t sample_count(const std::string& channel) const;
  double start_time_s() const;  // earliest sample time of any channel; 0 without samples
  double end_time_s() const;    // latest sample time of any channel; 0 without samples
  std::vector<SessionEvent> events() const;  // in the order they were added
  std::vector<CalibrationRecord> calibrations() const;

  // The session checked as a whole, in channel order: a calibration record a channel names
  // but the session lacks (unusable); explicit times that are not finite or do not
  // increase (unusable; reads every time of such a channel); a channel on a sample clock
  // that ends more than one sample period before the last one to end (a warning: export
  // leaves its cells empty from there, fit uses only the time where every channel has
  // samples). Empty when none. Throws SessionError only when the file cannot be read.
  std::vector<SessionProblem> problems() const;

  // At most this many samples are read by one call (2^28: 2 GiB of values and 2 GiB of
  // times); a longer range is a SessionError naming the dataset, not an allocation failure.
  static constexpr std::uint64_t kMaxReadSamples = std::uint64_t{1} << 28;

  // Samples with start_s <= time <= end_s (NaN: std::invalid_argument). Uniform
  // channels: the index range comes from the clock and only it is read; time_s[i] is
  // first_sample_time_s + (first_index + i) / sample_rate_hz. Explicit-time channels:
  // all times are read to find the range, then only its samples.
  ChannelSlice read(const std::string& channel,
                    double start_s = -std::numeric_limits<double>::infinity(),
                    double end_s = std::numeric_limits<double>::infinity()) const;
  // Physical values of a slice of this channel: signal = raw_offset + raw_scale · raw,
  // then the channel's calibration record (none: the signal is the physical value).
  // A lost sample (is_lost_sample) is NaN: a gap, never a number.
  std::vector<double> physical(const std::string& channel, const ChannelSlice& slice) const;

  // Names of the datasets directly in `group` ("truth", "results/fit-1"), by name.
  std::vector<std::string> group_datasets(const std::string& group) const;
  std::vector<double> read_group_dataset(const std::string& group, const std::string& name) const;
  std::string read_group_attribute(const std::string& group, const std::string& name) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Makes `channel` of an existing session use `record` from now on: the record is added to
// /calibrations (in full; an id already there must hold the same record), the channel's
// calibration_id is changed (for a record of sensor_kind "geometry": its
// geometry_calibration_id, and the channel must be a load cell), and an event of kind
// "calibration" for the channel says what was applied and what it replaced. Raw samples
// and every earlier record stay as they were, so the change can be undone by applying the
// earlier record again. The record must give the channel's unit. Returns the id the
// channel used before. Throws SessionError.
std::string apply_calibration(const std::filesystem::path& path, const std::string& channel,
                              const CalibrationRecord& record, const std::string& note = "");

}  // namespace doorbench
