#pragma once
// What a recording is made of, planned before it starts (acquisition/record/ only;
// recording_plan.cpp, used by recorder.cpp and session_recording.cpp): the sources'
// channels checked (scan channels, then each polled channel followed by its latency
// channel), the calibration records, the sizes that follow from the scan rate, the
// journal's header; and the per-channel state of the polled sources. Errors are
// std::invalid_argument naming the session or the source.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "acquisition/record/journal.h"
#include "acquisition/record/recorder.h"

namespace doorbench::record_detail {

// signal = raw_offset + raw_scale · raw, then the channel's calibration record (if the
// recording has it): the value a status display shows.
struct LiveConversion {
  double offset = 0.0;
  double scale = 1.0;
  const CalibrationRecord* record = nullptr;
  double operator()(double raw) const {
    const double signal = offset + scale * raw;
    if (record == nullptr) return signal;
    try {
      return record->apply(signal);
    } catch (const std::exception&) {
      return std::nan("");
    }
  }
};

// One polled channel's samples waiting for their timed frame.
struct TimedBatch {
  std::uint32_t journal_channel = 0;
  std::uint32_t stage_index = 0;  // among every polled value channel (the trigger stage's)
  std::size_t status_index = 0;
  std::vector<std::int64_t> time_ns;
  std::vector<std::int64_t> latency_ns;
  std::vector<double> raw;
  std::size_t count = 0;
  double first_time_s = 0.0;
  LiveConversion conversion;
};

struct PolledState {
  PolledSource* source = nullptr;
  std::vector<TimedBatch> batches;  // per channel of the source
};

// What the sources bring to a recording, checked: every channel (scan channels, then each
// polled channel followed by its latency channel), the calibration records, and the sizes
// that follow from the scan rate.
struct RecordingPlan {
  AcquisitionBackend* backend = nullptr;
  std::vector<ChannelInfo> channels;
  std::vector<CalibrationRecord> calibrations;
  std::string description;
  double rate_hz = 0.0;
  std::size_t scan_channels = 0;
  std::vector<PolledState> polled;
  std::size_t block_scans = 1;
  std::uint64_t total_scans = 0;
  std::int64_t duration_ns = 0;
  std::filesystem::path journal_path;
};

// The plan of a recording from `sources` into `path`; throws when there is nothing to
// record, a source is null or unusable, or two channels share a name.
RecordingPlan plan_recording(const RecordSources& sources, const std::filesystem::path& path,
                             const RecordOptions& options);

// Refused before recording, not after it.
void refuse_files_in_the_way(const std::filesystem::path& path,
                             const std::filesystem::path& journal_path);

// The journal's header: the metadata, the channels, the calibrations, the rate.
JournalHeader journal_header(const RecordingPlan& plan, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options);

}  // namespace doorbench::record_detail
