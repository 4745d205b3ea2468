// The plan of a recording (internal/recording_plan.h).
#include "acquisition/record/internal/recording_plan.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace doorbench::record_detail {

namespace {

// The scan backend's channels (counts only), rate, calibrations and description.
void plan_scan_backend(AcquisitionBackend& backend, RecordingPlan& plan) {
  plan.channels = backend.channels();
  if (plan.channels.empty()) throw std::invalid_argument(backend.description() + ": no channels");
  plan.rate_hz = backend.scan_rate_hz();
  if (!(plan.rate_hz > 0) || !std::isfinite(plan.rate_hz)) {
    throw std::invalid_argument(backend.description() + ": scan rate must be > 0");
  }
  for (const ChannelInfo& channel : plan.channels) {
    if (channel.raw_type != RawType::kCounts) {
      throw std::invalid_argument(backend.description() + ": channel " + channel.name +
                                  " holds values; the recorder records counts");
    }
  }
  plan.scan_channels = plan.channels.size();
  plan.calibrations = backend.calibrations();
  plan.description = backend.description();
}

// The latency channel recorded next to polled channel `channel`.
ChannelInfo latency_channel(const ChannelInfo& channel) {
  ChannelInfo latency;
  latency.name = channel.name + "_latency";
  latency.sensor_kind = "poll_latency";
  latency.sensor_serial = channel.sensor_serial;
  latency.raw_type = RawType::kValues;
  latency.raw_unit = "s";
  latency.unit = "s";
  latency.range_min = 0.0;
  latency.range_max = 3600.0;
  latency.sample_rate_hz = 0.0;
  return latency;
}

// One polled source's channels (explicit-time values only), each followed by its latency
// channel, with a batch of `polled_batch` samples per channel.
void plan_polled_source(PolledSource& source, std::size_t polled_batch, RecordingPlan& plan) {
  PolledState state;
  state.source = &source;
  const std::vector<ChannelInfo> source_channels = source.channels();
  if (source_channels.empty()) throw std::invalid_argument(source.description() + ": no channels");
  for (const ChannelInfo& channel : source_channels) {
    if (channel.sample_rate_hz != 0 || channel.raw_type != RawType::kValues) {
      throw std::invalid_argument(source.description() + ": channel " + channel.name +
                                  " must hold values at explicit times (sample_rate_hz 0)");
    }
    TimedBatch batch;
    batch.journal_channel = static_cast<std::uint32_t>(plan.channels.size());
    plan.channels.push_back(channel);
    plan.channels.push_back(latency_channel(channel));
    batch.time_ns.resize(polled_batch);
    batch.latency_ns.resize(polled_batch);
    batch.raw.resize(polled_batch);
    state.batches.push_back(std::move(batch));
  }
  for (CalibrationRecord& record : source.calibrations()) {
    plan.calibrations.push_back(std::move(record));
  }
  if (!plan.description.empty()) plan.description += "; ";
  plan.description += source.description();
  plan.polled.push_back(std::move(state));
}

void check_unique_channel_names(const std::vector<ChannelInfo>& channels,
                                const std::filesystem::path& path) {
  std::set<std::string> names;
  for (const ChannelInfo& channel : channels) {
    if (!names.insert(channel.name).second) {
      throw std::invalid_argument(path.string() + ": channel name " + channel.name +
                                  " is used twice among the sources");
    }
  }
}

}  // namespace

void refuse_files_in_the_way(const std::filesystem::path& path,
                             const std::filesystem::path& journal_path) {
  if (std::filesystem::exists(path)) {
    throw SessionError(path.string() + ": already exists (sessions are never overwritten)");
  }
  if (std::filesystem::exists(journal_path)) {
    throw JournalError(journal_path.string() +
                       ": an unfinished recording's journal is in the way; recover it first "
                       "(doorbench recover " +
                       journal_path.string() + ")");
  }
}

RecordingPlan plan_recording(const RecordSources& sources, const std::filesystem::path& path,
                             const RecordOptions& options) {
  RecordingPlan plan;
  plan.backend = sources.scans;
  if (plan.backend == nullptr && sources.polled.empty()) {
    throw std::invalid_argument(path.string() +
                                ": nothing to record (no scan backend and no polled source)");
  }
  if (plan.backend != nullptr) plan_scan_backend(*plan.backend, plan);
  for (PolledSource* source : sources.polled) {
    if (source == nullptr) throw std::invalid_argument(path.string() + ": a polled source is null");
    plan_polled_source(*source, options.polled_batch, plan);
  }
  check_unique_channel_names(plan.channels, path);
  plan.block_scans =
      plan.backend == nullptr ? 1
      : options.block_scans > 0
          ? options.block_scans
          : std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(plan.rate_hz * 0.01)));
  plan.total_scans = static_cast<std::uint64_t>(std::llround(options.duration_s * plan.rate_hz));
  plan.duration_ns = static_cast<std::int64_t>(std::llround(options.duration_s * 1e9));
  plan.journal_path = journal_path_for(path);
  return plan;
}

JournalHeader journal_header(const RecordingPlan& plan, const SessionMetadata& metadata,
                             const std::filesystem::path& path, const RecordOptions& options) {
  JournalHeader header;
  header.metadata = metadata;
  header.channels = plan.channels;
  header.calibrations = plan.calibrations;
  header.scan_rate_hz = plan.rate_hz;
  header.session_name = path.filename().string();
  header.flush_interval_s = options.flush_interval_s;
  header.backend = plan.description;
  return header;
}

}  // namespace doorbench::record_detail
