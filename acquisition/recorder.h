#pragma once
// Records a session from a backend: channels, calibration records and metadata first,
// then scans in blocks until the duration is reached, then the backend's extras.
#include <filesystem>
#include <functional>
#include <string>

#include "acquisition/backend.h"
#include "acquisition/session_file.h"

namespace doorbench {

struct RecordOptions {
  double duration_s = 10.0;
  std::size_t block_scans = 100;  // scans per read: 0.1 s at 1 kHz
  SessionWriterOptions writer;
  // Called after each block with the recorded time and scan count (for a status line).
  std::function<void(double recorded_s, std::size_t scans)> progress;
  std::string validate() const;  // empty when usable
};

struct RecordSummary {
  std::size_t scans = 0;
  std::size_t events = 0;
  double duration_s = 0.0;
};

RecordSummary record_session(AcquisitionBackend& backend, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options);

}  // namespace doorbench
