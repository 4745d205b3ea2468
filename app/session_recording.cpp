// Recording a session from a rig (app/session_recording.h): what `doorbench record` and the
// demo share: the live status display, the trigger's set-up, one function per kind of rig.
#include "app/session_recording.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "acquisition/record/recorder.h"
#include "acquisition/record/recovery.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/output_file.h"
#include "acquisition/session/printable.h"
#include "acquisition/session/session_csv.h"
#include "acquisition/session/tdms.h"
#include "app/commands.h"
#include "app/limit_watcher.h"
#include "calibration/range_warnings.h"
#include "core/time_text.h"
#include "sensors/rig_recording.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::app {

RigDefinition load_rig(const std::string& rig_path) {
  if (rig_path.empty()) {
    return parse_rig(simulated_dishwasher_rig_text(), "built-in rig simulated-dishwasher",
                     std::filesystem::current_path());
  }
  return read_rig_file(rig_path);
}

// What every new recording's session says about itself, whichever backend records it.
SessionMetadata new_session_metadata(const RigDefinition& rig,
                                     const SessionRecordingOptions& options) {
  SessionMetadata metadata;
  metadata.rig_name = rig.name;
  metadata.rig_definition = rig.text;
  metadata.operator_name = options.operator_name;
  metadata.product_id = options.product_id;
  metadata.start_time_utc = utc_now_iso8601();
  metadata.software_version = std::string("doorbench ") + DOORBENCH_VERSION;
  metadata.notes = options.notes;
  return metadata;
}

namespace {

// A recording's live status on stderr. On a terminal: one group of lines (the status line,
// then each channel's latest value) rewritten in place at most 10 times a second; when
// stderr is not a terminal (a log), one line with every value at each quarter of the
// duration, so that logs stay short.
class StatusDisplay {
 public:
  StatusDisplay(std::string path, double duration_s)
      : path_(std::move(path)), duration_s_(duration_s), terminal_(isatty(STDERR_FILENO) != 0) {}

  // `limits`: the limit watcher's text for the status line ("" when none).
  void show(const RecordStatus& status, const std::string& limits = "") {
    limits_ = limits;
    const auto now = std::chrono::steady_clock::now();
    if (terminal_) {
      if (now < next_draw_) {
        last_ = status;
        pending_ = true;
        return;
      }
      next_draw_ = now + std::chrono::milliseconds(100);
      draw(status);
      return;
    }
    if (status.recorded_s < next_report_s_) return;
    next_report_s_ = status.recorded_s + std::max(duration_s_ / 4, 1.0);
    std::string text = status_line(status);
    for (const ChannelStatus& channel : status.channels) {
      char value[128];
      std::snprintf(value, sizeof value, "; %s %.5g %s", channel.name.c_str(), channel.latest,
                    channel.unit.c_str());
      text += value;
    }
    std::fprintf(stderr, "%s\n", text.c_str());
  }

  // Shows the last status if it was held back.
  void finish() {
    if (terminal_ && pending_) draw(last_);
    std::fflush(stderr);
  }

 private:
  void draw(const RecordStatus& status) {
    pending_ = false;
    std::string text;
    if (lines_ > 0) text += "\r\033[" + std::to_string(lines_) + "A\033[J";
    text += status_line(status) + "\n";
    lines_ = 1;
    for (const ChannelStatus& channel : status.channels) {
      char line[192];
      std::snprintf(line, sizeof line, "  %-20s %12.5g %-6s %10llu samples %9.2f Hz%s\n",
                    channel.name.c_str(), channel.latest, channel.unit.c_str(),
                    static_cast<unsigned long long>(channel.samples), channel.achieved_rate_hz,
                    channel.polled ? " (polled)" : "");
      text += line;
      ++lines_;
    }
    std::fputs(text.c_str(), stderr);
  }

  std::string status_line(const RecordStatus& status) const {
    char line[320];
    std::snprintf(
        line, sizeof line, "recording %s: %.1f / %.1f s, %llu scans at %.2f Hz, %llu faults%s%s%s",
        path_.c_str(), status.recorded_s, duration_s_,
        static_cast<unsigned long long>(status.scans), status.achieved_scan_rate_hz,
        static_cast<unsigned long long>(status.faults), status.trigger_state.empty() ? "" : " [",
        status.trigger_state.c_str(), status.trigger_state.empty() ? "" : "]");
    return line + limits_;
  }

  std::string path_;
  std::string limits_;
  double duration_s_;
  bool terminal_;
  int lines_ = 0;
  bool pending_ = false;
  RecordStatus last_;
  double next_report_s_ = 0.0;
  std::chrono::steady_clock::time_point next_draw_{};
};

// Records `rig` with the common options of every rig (flush interval, Ctrl-C, the live
// status display and the warnings of sensors at their range's end).
RecordSummary record_with_status(const RigDefinition& rig, const SessionRecordingOptions& options,
                                 const std::filesystem::path& out_path) {
  sensors::RigRecordingOptions recording;
  recording.duration_s = options.duration_s;
  recording.max_wait_s = options.max_wait_s;
  recording.flush_interval_s = options.flush_interval_s;
  recording.stop_requested = options.stop_requested;
  recording.notice = [](const std::string& line) { std::cerr << line << "\n"; };
  if (std::string problem = recording.problem(rig); !problem.empty()) throw UsageError(problem);
  sensors::RigRecording sources(rig, recording, simulated_bench::simulated_scans);
  const bool show = options.show_progress;
  if (show) std::cerr << sources.setup_report();
  StatusDisplay display(out_path.string(), sources.display_duration_s());
  // Sensors at their range's end, live on the status line and in the summary.
  LimitWatcher limits(rig_channel_limits(rig));
  std::function<void(const RecordStatus&)> progress;
  if (show) {
    progress = [&display, &limits](const RecordStatus& status) {
      limits.update(status);
      display.show(status, limits.status_text());
    };
  }
  const RecordSummary summary =
      sources.record(new_session_metadata(rig, options), out_path, std::move(progress));
  if (show) display.finish();
  if (const std::string warning = sources.end_warning(); !warning.empty()) {
    std::cerr << "doorbench: " << out_path.string() << ": " << warning << "\n";
  }
  if (show && !limits.empty()) {
    limits.measure(SessionReader(out_path));  // the summary's times from every sample
    for (const std::string& line : limits.summary()) std::cerr << "warning: " << line << "\n";
  }
  return summary;
}

}  // namespace

RecordSummary record_simulated_session(const RigDefinition& rig,
                                       const SessionRecordingOptions& options,
                                       const std::filesystem::path& out_path) {
  RigDefinition simulated = rig;
  simulated.daq_backend = "simulated";
  return record_with_status(simulated, options, out_path);
}

RecordSummary record_rig_session(const RigDefinition& rig, const SessionRecordingOptions& options,
                                 const std::filesystem::path& out_path) {
  return record_with_status(rig, options, out_path);
}

}  // namespace doorbench::app
