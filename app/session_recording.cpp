// Recording a session from a rig (app/session_recording.h): what `doorbench record` and the
// demo share: the live status display, the trigger's set-up, one function per kind of rig.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include "acquisition/record/recorder.h"
#include "acquisition/record/recovery.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/output_file.h"
#include "acquisition/session/printable.h"
#include "acquisition/session/session_csv.h"
#include "acquisition/session/tdms.h"
#include "app/commands.h"
#include "app/limit_watcher.h"
#include "app/session_recording.h"
#include "calibration/range_warnings.h"
#include "sensors/comedi_backend.h"
#include "sensors/modbus_source.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::app {

std::string utc_now_iso8601() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

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

// Set by the Enter key for a rig with a manual trigger: the first Enter starts, the next
// one stops (docs/triggering.md). The key reader is a detached thread blocked on stdin.
std::atomic<bool> g_manual_start{false};
std::atomic<bool> g_manual_stop{false};

void start_manual_keys(const TriggerOptions& trigger) {
  static std::atomic<bool> started{false};
  if (started.exchange(true)) return;
  g_manual_start.store(trigger.start != TriggerOptions::Start::kManual);
  std::thread([] {
    std::string line;
    while (std::getline(std::cin, line)) {
      if (!g_manual_start.exchange(true)) continue;
      g_manual_stop.store(true);
    }
  }).detach();
}

// The duration a status line counts towards: the trigger's, else the recording's.
double display_duration_s(const SessionRecordingOptions& options, const RecordOptions& record) {
  if (record.trigger && record.trigger->duration_s > 0) return record.trigger->duration_s;
  return options.duration_s > 0 ? options.duration_s : record.duration_s;
}

// A rig with a [recording] table records through a trigger stage: its start and stop
// conditions, pre-trigger buffer and stroke markers. --duration-s then counts from the
// trigger. Returns the time the acquisition may take in all (armed wait included), or 0
// when the rig has no [recording] table.
double configure_triggering(const RigDefinition& rig, const SessionRecordingOptions& options,
                            RecordOptions& record) {
  if (rig.recording.line == 0) return 0.0;
  TriggerOptions trigger = trigger_options_from_rig(rig);
  if (options.duration_s > 0) trigger.duration_s = options.duration_s;
  if (trigger.start == TriggerOptions::Start::kManual ||
      trigger.stop == TriggerOptions::Stop::kManual) {
    start_manual_keys(trigger);
    trigger.manual_start = &g_manual_start;
    trigger.manual_stop = &g_manual_stop;
    if (trigger.start == TriggerOptions::Start::kManual) {
      std::cerr << "armed: press Enter to start recording"
                << (trigger.stop == TriggerOptions::Stop::kManual ? ", Enter again to stop\n"
                                                                  : "\n");
    } else {
      std::cerr << "press Enter to stop recording\n";
    }
  }
  record.trigger = trigger;
  // Without a duration the stop condition or Ctrl-C ends it; an hour bounds it.
  return options.max_wait_s + (trigger.duration_s > 0 ? trigger.duration_s : 3600.0);
}

// A source that runs until stopped (a card, polled sensors) records for --duration-s, or
// through the rig's triggers (then bounded by the armed wait plus their duration).
void set_timed_recording(const RigDefinition& rig, const SessionRecordingOptions& options,
                         const std::string& what, RecordOptions& record) {
  const double triggered_limit_s = configure_triggering(rig, options, record);
  if (!(options.duration_s > 0) && triggered_limit_s == 0) {
    throw UsageError(what +
                     " records for a set time: give --duration-s (or a [recording] "
                     "table with its triggers)");
  }
  record.duration_s = triggered_limit_s > 0 ? triggered_limit_s : options.duration_s;
}

// Records `sources` with the common options of every rig (flush interval, Ctrl-C, the live
// status display) added to `record`.
RecordSummary record_with_status(const RecordSources& sources, const RigDefinition& rig,
                                 const SessionRecordingOptions& options,
                                 const std::filesystem::path& out_path, RecordOptions record,
                                 double display_s) {
  record.flush_interval_s = options.flush_interval_s;
  record.stop_requested = options.stop_requested;
  StatusDisplay display(out_path.string(), display_s);
  // Sensors at their range's end, live on the status line and in the summary.
  LimitWatcher limits(rig_channel_limits(rig));
  const bool show = options.show_progress;
  if (show) {
    record.progress = [&display, &limits](const RecordStatus& status) {
      limits.update(status);
      display.show(status, limits.status_text());
    };
  }
  const RecordSummary summary =
      record_session(sources, new_session_metadata(rig, options), out_path, record);
  if (show) display.finish();
  if (show && !limits.empty()) {
    limits.measure(SessionReader(out_path));  // the summary's times from every sample
    for (const std::string& line : limits.summary()) std::cerr << "warning: " << line << "\n";
  }
  return summary;
}

}  // namespace

RecordSummary record_simulated_session(const RigDefinition& rig,
                                       const SessionRecordingOptions& options,
                                       const std::filesystem::path& out_path,
                                       const std::vector<PolledSource*>& polled) {
  for (const RigChannel& channel : rig.channels) {
    if (channel.backend != "simulated") {
      throw std::runtime_error(rig.source + ": channel " + channel.name + " uses backend " +
                               channel.backend +
                               ", which doorbench cannot record yet (only simulated)");
    }
  }
  const DoorModel model = simulated_bench::simulated_door_model(rig);
  std::unique_ptr<simulated_bench::StrokeForce> hand = simulated_bench::simulated_hand(rig, model);
  const double duration_s =
      options.duration_s > 0 ? options.duration_s : hand->natural_duration_s();
  simulated_bench::SimulatedBench bench(rig, model, std::move(hand), duration_s);

  RecordOptions record;
  record.duration_s = duration_s;
  // An unpaced simulated bench computes scans on demand and can wait for the writer; a
  // paced one stands for a DAQ that cannot (a full ring is then a recorded fault).
  const bool paced = rig.simulation && rig.simulation->realtime;
  record.when_ring_full = paced ? RingFullPolicy::kDropAndRecordFault : RingFullPolicy::kWait;
  // The bench plays its hand cycles whatever the trigger keeps of them.
  configure_triggering(rig, options, record);
  RecordSources sources;
  sources.scans = &bench;
  sources.polled = polled;
  const double display_s =
      record.trigger && record.trigger->duration_s > 0 ? record.trigger->duration_s : duration_s;
  return record_with_status(sources, rig, options, out_path, record, display_s);
}

namespace {

// A rig whose DAQ is a comedi card: a hardware-timed command for a set duration.
RecordSummary record_comedi_session(const RigDefinition& rig,
                                    const SessionRecordingOptions& options,
                                    const std::filesystem::path& out_path,
                                    const std::vector<PolledSource*>& polled) {
  RecordOptions record;
  set_timed_recording(rig, options, "a comedi rig", record);
  sensors::ComediOptions comedi;
  comedi.duration_s = record.duration_s;
  sensors::ComediBackend backend(rig, sensors::selected_comedi_api(), comedi);
  if (options.show_progress) std::cerr << backend.setup().brief_report();

  // Blocks of about 20 ms, whatever the rate.
  record.block_scans =
      std::max<std::size_t>(1, static_cast<std::size_t>(backend.scan_rate_hz() / 50));
  // The card runs on its own clock: a writer that falls behind must cost a recorded gap,
  // never a stalled read that overruns the card's buffer.
  record.when_ring_full = RingFullPolicy::kDropAndRecordFault;
  RecordSources sources;
  sources.scans = &backend;
  sources.polled = polled;
  const RecordSummary summary = record_with_status(sources, rig, options, out_path, record,
                                                   display_duration_s(options, record));
  if (backend.overran()) {
    std::cerr << "doorbench: " << out_path.string() << ": " << backend.end_reason()
              << "; the session keeps what was read before it\n";
  }
  return summary;
}

// A rig without a DAQ (daq.backend "none"): its polled sensors alone, for a set time or
// through its triggers.
RecordSummary record_polled_session(const RigDefinition& rig,
                                    const SessionRecordingOptions& options,
                                    const std::filesystem::path& out_path,
                                    const std::vector<PolledSource*>& polled) {
  RecordOptions record;
  set_timed_recording(rig, options, "a rig of polled sensors", record);
  RecordSources sources;
  sources.polled = polled;
  return record_with_status(sources, rig, options, out_path, record,
                            display_duration_s(options, record));
}

}  // namespace

RecordSummary record_rig_session(const RigDefinition& rig, const SessionRecordingOptions& options,
                                 const std::filesystem::path& out_path) {
  // The rig's Modbus sensors are polled beside its DAQ (if it has one), which sees only
  // its own channels.
  std::unique_ptr<sensors::ModbusSource> modbus;
  RigDefinition daq_rig = rig;
  std::erase_if(daq_rig.channels,
                [](const RigChannel& channel) { return channel.backend == "modbus"; });
  if (daq_rig.channels.size() < rig.channels.size()) {
    modbus = std::make_unique<sensors::ModbusSource>(rig);
  }
  std::vector<PolledSource*> polled;
  if (modbus) polled.push_back(modbus.get());
  return rig.daq_backend == "none" ? record_polled_session(rig, options, out_path, polled)
         : rig.daq_backend == "comedi"
             ? record_comedi_session(daq_rig, options, out_path, polled)
             : record_simulated_session(daq_rig, options, out_path, polled);
}

}  // namespace doorbench::app
