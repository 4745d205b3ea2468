#include "acquisition/recorder.h"

#include <cmath>
#include <stdexcept>

namespace doorbench {

ScanBlock::ScanBlock(std::size_t channels, std::size_t max_scans, std::size_t max_events)
    : counts(channels, std::vector<std::int32_t>(max_scans)) {
  events.reserve(max_events);
}

std::string RecordOptions::validate() const {
  if (!(duration_s > 0) || !std::isfinite(duration_s)) return "record duration_s must be > 0";
  if (block_scans == 0) return "record block_scans must be > 0";
  return writer.validate();
}

RecordSummary record_session(AcquisitionBackend& backend, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  const std::vector<ChannelInfo> channels = backend.channels();
  if (channels.empty()) throw std::invalid_argument(backend.description() + ": no channels");
  const auto total_scans =
      static_cast<std::size_t>(std::llround(options.duration_s * backend.scan_rate_hz()));

  SessionWriter writer(path, metadata, options.writer);
  std::vector<int> indices;
  for (const ChannelInfo& channel : channels) indices.push_back(writer.add_channel(channel));
  for (const calibration::CalibrationRecord& record : backend.calibrations()) {
    writer.add_calibration(record);
  }

  ScanBlock block(channels.size(), options.block_scans);
  RecordSummary summary;
  backend.start();
  while (summary.scans < total_scans) {
    block.events.clear();
    const std::size_t got = backend.read(block);
    if (got == 0) break;
    const std::size_t keep = std::min(got, total_scans - summary.scans);
    for (std::size_t c = 0; c < channels.size(); ++c) {
      writer.append_counts(indices[c], std::span<const std::int32_t>(block.counts[c].data(), keep));
    }
    for (const SessionEvent& event : block.events) {
      writer.add_event(event);
      ++summary.events;
    }
    summary.scans += keep;
    if (options.progress) options.progress(summary.scans / backend.scan_rate_hz(), summary.scans);
  }
  backend.stop();
  backend.write_extras(writer);
  writer.close();
  summary.duration_s = summary.scans / backend.scan_rate_hz();
  return summary;
}

}  // namespace doorbench
