// The recorder (recorder.h): its options and summary, and record_session(), which plans
// the recording (internal/recording_plan.h), runs it (internal/session_recording.h) and
// converts its journal into the session. The reading side is realtime_reader.cpp.
#include "acquisition/record/recorder.h"

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "acquisition/record/internal/recording_plan.h"
#include "acquisition/record/internal/session_recording.h"
#include "acquisition/record/recovery.h"

namespace doorbench {

using namespace record_detail;

ScanBlock::ScanBlock(std::size_t channels, std::size_t max_scans, std::size_t max_events)
    : counts(channels, std::vector<std::int32_t>(max_scans)) {
  events.reserve(max_events);
}

std::string RecordOptions::validate() const {
  if (!(duration_s > 0) || !std::isfinite(duration_s)) return "record duration_s must be > 0";
  if (!(flush_interval_s > 0) || !(flush_interval_s <= 10.0)) {
    return "record flush_interval_s must be > 0 and <= 10";
  }
  if (!(ring_s > 0) || !std::isfinite(ring_s)) return "record ring_s must be > 0";
  if (ring_events == 0) return "record ring_events must be >= 1";
  if (polled_batch == 0 || polled_batch > (1u << 20)) {
    return "record polled_batch must be >= 1 and <= 1048576";
  }
  if (trigger) {
    if (std::string problem = trigger->validate(); !problem.empty()) return problem;
  }
  return writer.validate();
}

std::string RecordSummary::brief_report() const {
  char text[256];
  std::snprintf(text, sizeof text, "%zu scans (%.3f s), %zu events; journal %.1f kB, %llu syncs",
                scans, duration_s, events, journal_bytes / 1000.0,
                static_cast<unsigned long long>(journal_syncs));
  std::string report = text;
  if (polled_samples > 0) report += "; " + std::to_string(polled_samples) + " polled samples";
  if (faults > 0) report += "; " + std::to_string(faults) + " faults";
  if (stopped_by_request) report += "; stopped by request";
  if (!trigger_report.empty()) report += "; " + trigger_report;
  if (dropped_scans > 0) {
    report += "; " + std::to_string(dropped_scans) + " scans lost to ring overflows";
  }
  if (dropped_events > 0) {
    report += "; " + std::to_string(dropped_events) + " events lost to a full event ring";
  }
  return report;
}

RecordSummary record_session(AcquisitionBackend& backend, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  RecordSources sources;
  sources.scans = &backend;
  return record_session(sources, metadata, path, options);
}

namespace {

// The journal (kept open, and locked, until the session is complete, so that another
// doorbench does not take it for an unfinished recording meanwhile) into the session.
void convert_to_session(const RecordingPlan& plan, const std::filesystem::path& path,
                        const RecordOptions& options, double session_origin_s) {
  ConvertOptions convert;
  convert.writer = options.writer;
  if (AcquisitionBackend* const backend = plan.backend) {
    convert.extras = [backend, session_origin_s](SessionWriter& writer) {
      backend->write_extras(writer, session_origin_s);
    };
  }
  try {
    convert_journal(plan.journal_path, path, convert);
  } catch (const std::exception& error) {
    // E.g. the disk filled up during the conversion: the journal is whole and synced.
    const std::string journal = plan.journal_path.string();
    throw SessionError(std::string(error.what()) + "; the recording is kept in " + journal +
                       " (free space, then: doorbench recover " + journal + ")");
  }
  // This recording's own journal, whole, in a complete session that is synced under its
  // name: the one journal doorbench removes (recovery keeps those it converts).
  std::error_code ignored;
  std::filesystem::remove(plan.journal_path, ignored);
  const std::filesystem::path folder =
      plan.journal_path.parent_path().empty() ? "." : plan.journal_path.parent_path();
  if (const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

RecordSummary record_session(const RecordSources& sources, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  RecordingPlan plan = plan_recording(sources, path, options);
  refuse_files_in_the_way(path, plan.journal_path);
  JournalWriter journal(plan.journal_path, journal_header(plan, metadata, path, options),
                        plan.block_scans, options.polled_batch);
  SessionRecording recording(plan, journal, options);
  recording.start_polled_sources();
  recording.start_threads();
  recording.write_until_done();
  const RecordSummary summary = recording.finish();
  convert_to_session(plan, path, options, recording.session_origin_s());
  if (recording.read_error()) std::rethrow_exception(recording.read_error());
  return summary;
}

}  // namespace doorbench
