#pragma once
// The session file: HDF5, one per recording, the one exchange format between every part
// of doorbench. It keeps the channels' samples as acquired (DAQ counts, or values as
// imported), their times on one session clock, the calibration records they use (in
// full), events, and groups for derived results and (simulated sessions) the truth.
// The layout is in docs/session-format.md; plain HDF5 tools read it without doorbench.
//
// Thread safety: a writer or reader is used by one thread at a time.
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "calibration/calibration_record.h"

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

struct ChannelInfo {
  std::string name;           // unique, [A-Za-z0-9_]+
  std::string sensor_kind;    // load_cell | inclinometer | gyroscope | imported | ...
  std::string sensor_serial;
  RawType raw_type = RawType::kCounts;
  std::string raw_unit = "counts";  // "counts", "V", or a physical unit for imports
  // signal (V, or raw_unit for values) = raw_offset + raw_scale · raw
  double raw_offset = 0.0;
  double raw_scale = 1.0;
  double range_min = -10.0;   // the signal's valid range (V for DAQ channels)
  double range_max = 10.0;
  std::string unit;           // physical unit after calibration
  std::string calibration_id; // empty: the signal already is the physical value
  // Sample times: uniform, time of sample i = first_sample_time_s + i / sample_rate_hz
  // (first_sample_time_s includes the converter's skew); or, when sample_rate_hz is 0,
  // explicit times appended with the samples.
  double sample_rate_hz = 1000.0;
  double first_sample_time_s = 0.0;
};

struct SessionEvent {
  double time_s = 0.0;
  std::string kind;     // trigger | stroke_start | stroke_end | mark | fault | gap
  std::string channel;  // empty when it concerns the whole session
  std::string detail;   // e.g. "opening" / "closing" for strokes, a fault's message
};

struct SessionWriterOptions {
  std::size_t chunk_samples = 16384;  // HDF5 chunk and write-buffer size per channel
  int deflate_level = 0;              // 0: no compression (fastest); 1-9: gzip
  std::string validate() const;       // empty when usable
};

class SessionWriter {
 public:
  // Creates `path` (an existing file is an error: sessions are never overwritten).
  SessionWriter(const std::filesystem::path& path, const SessionMetadata& metadata,
                const SessionWriterOptions& options = {});
  ~SessionWriter();  // closes if close() was not called; never throws
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  // Channels are declared before their first samples; returns the channel's index.
  int add_channel(const ChannelInfo& channel);
  void add_calibration(const calibration::CalibrationRecord& record);

  // Buffered; memory stays bounded (one chunk per channel).
  void append_counts(int channel, std::span<const std::int32_t> counts);
  void append_values(int channel, std::span<const double> values);
  // For channels with sample_rate_hz == 0: times (strictly increasing) with the values.
  void append_timed_values(int channel, std::span<const double> time_s,
                           std::span<const double> values);
  void add_event(const SessionEvent& event);

  // A derived or side group (e.g. "results/fit-1", "truth"): 1-D float64 datasets and
  // text attributes. `uses` names the data it was computed from.
  void write_group_dataset(const std::string& group, const std::string& name,
                           std::span<const double> values);
  void write_group_attribute(const std::string& group, const std::string& name,
                             const std::string& text);

  void close();  // flushes everything; throws SessionError on failure

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct ChannelSlice {
  std::size_t first_index = 0;
  std::vector<double> time_s;
  std::vector<double> raw;  // counts are exact in a double
};

class SessionReader {
 public:
  explicit SessionReader(const std::filesystem::path& path);  // throws SessionError
  ~SessionReader();
  SessionReader(SessionReader&&) noexcept;
  SessionReader& operator=(SessionReader&&) noexcept;

  const std::filesystem::path& path() const;
  const SessionMetadata& metadata() const;
  const std::vector<ChannelInfo>& channels() const;
  const ChannelInfo& channel(const std::string& name) const;  // throws naming it
  std::size_t sample_count(const std::string& channel) const;
  double start_time_s() const;  // earliest sample time
  double end_time_s() const;    // latest sample time
  std::vector<SessionEvent> events() const;
  std::vector<calibration::CalibrationRecord> calibrations() const;

  // Samples with start_s <= time <= end_s, read from disk for that range only.
  ChannelSlice read(const std::string& channel,
                    double start_s = -std::numeric_limits<double>::infinity(),
                    double end_s = std::numeric_limits<double>::infinity()) const;
  // Physical values of a slice: raw → signal → the channel's calibration record.
  std::vector<double> physical(const std::string& channel, const ChannelSlice& slice) const;

  std::vector<std::string> group_datasets(const std::string& group) const;
  std::vector<double> read_group_dataset(const std::string& group, const std::string& name) const;
  std::string read_group_attribute(const std::string& group, const std::string& name) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace doorbench
