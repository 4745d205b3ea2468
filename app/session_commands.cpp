// doorbench record, recover, info, export and import: sessions on the command line.
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

#include "acquisition/output_file.h"
#include "acquisition/printable.h"
#include "acquisition/recorder.h"
#include "acquisition/recovery.h"
#include "acquisition/rig_file.h"
#include "acquisition/session_csv.h"
#include "acquisition/tdms.h"
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
  const DoorModel model = sensors::simulated_door_model(rig);
  std::unique_ptr<sensors::StrokeForce> hand = sensors::simulated_hand(rig, model);
  const double duration_s =
      options.duration_s > 0 ? options.duration_s : hand->natural_duration_s();
  sensors::SimulatedBench bench(rig, model, std::move(hand), duration_s);

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

struct RecordCommandOptions {
  std::string rig_path;
  std::string out_path;
  SessionRecordingOptions recording;
};

// Set by SIGINT/SIGTERM while recording; the recorder polls it (a lock-free atomic is
// async-signal-safe).
std::atomic<bool> g_stop_recording{false};

extern "C" void request_stop(int signal_number) {
  g_stop_recording.store(true);
  // A second Ctrl-C ends doorbench at once; the journal keeps what was recorded.
  ::signal(signal_number, SIG_DFL);
}

// Recovers every unfinished session (a journal no running recording holds) in `folder`.
void recover_unfinished_sessions(const std::filesystem::path& folder) {
  for (const std::filesystem::path& journal : find_unfinished_sessions(folder)) {
    std::cerr << "found an unfinished session: " << journal.string() << "\n";
    try {
      const ConvertResult result = recover_session(journal);
      std::cerr << "recovered " << result.brief_report() << "\n";
    } catch (const std::exception& error) {
      std::cerr << "could not recover it: " << error.what() << "\n";
    }
  }
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

namespace {

void run_record(const RecordCommandOptions& options) {
  const RigDefinition rig = load_rig(options.rig_path);
  const std::filesystem::path out(options.out_path);
  recover_unfinished_sessions(out.parent_path().empty() ? std::filesystem::path(".")
                                                        : out.parent_path());
  // After recovery, which may have made it (docs/output-files.md).
  std::vector<std::filesystem::path> inputs;
  if (!options.rig_path.empty()) inputs.emplace_back(options.rig_path);
  check_output_session(out, inputs);
  SessionRecordingOptions recording = options.recording;
  recording.stop_requested = &g_stop_recording;
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  struct sigaction old_int {
  }, old_term{};
  ::sigaction(SIGINT, &action, &old_int);
  ::sigaction(SIGTERM, &action, &old_term);
  struct Restore {
    const struct sigaction &old_int, &old_term;
    ~Restore() {
      ::sigaction(SIGINT, &old_int, nullptr);
      ::sigaction(SIGTERM, &old_term, nullptr);
    }
  } restore{old_int, old_term};
  const RecordSummary summary = record_rig_session(rig, recording, options.out_path);
  if (summary.stopped_by_request) {
    std::cerr << "stopped by request after " << summary.duration_s << " s\n";
  }
  if (summary.dropped_scans > 0 || summary.dropped_events > 0) {
    std::cerr << "faults: " << summary.brief_report() << "\n";
  }
  if (!summary.trigger_report.empty()) std::cerr << "trigger: " << summary.trigger_report << "\n";
  std::cerr << "wrote " << options.out_path << ": " << rig.channels.size() << " channels, "
            << summary.scans << " scans";
  if (summary.polled_samples > 0) std::cerr << ", " << summary.polled_samples << " polled samples";
  std::cerr << " (" << summary.duration_s << " s), " << summary.events << " events\n";
}

struct RecoverCommandOptions {
  std::string file;
  std::string out_path;
};

void run_recover(const RecoverCommandOptions& options) {
  RecoverOptions recover;
  recover.out = options.out_path;
  const ConvertResult result = recover_session(options.file, recover);
  std::cerr << "recovered " << result.brief_report() << "\n";
}

std::string format_seconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f s", seconds);
  return text;
}

// The geometry analysis uses: a load cell's geometry record (its handle radius replaces the
// door parameter file's in fit and loop, its mounting angle corrects the force on read).
void print_geometry(const SessionReader& session) {
  bool any = false;
  for (const ChannelInfo& c : session.channels()) {
    if (c.geometry_calibration_id.empty()) continue;
    any = true;
    std::cout << "geometry: " << c.name << " uses " << printable(c.geometry_calibration_id);
    for (const calibration::CalibrationRecord& r : session.calibrations()) {
      if (r.id != c.geometry_calibration_id) continue;
      for (const char* name : {"handle_radius_m", "mounting_angle_deg"}) {
        if (const calibration::CalibrationQuantity* q = r.quantity(name)) {
          std::cout << ", " << name << " " << q->value << " ± " << q->standard_uncertainty;
        }
      }
    }
    std::cout << "\n  fit and loop use its handle radius (not the door file's); the force is "
                 "divided by cos(mounting angle) on read\n";
  }
  if (!any) {
    std::cout << "geometry: no geometry record; fit and loop take the handle radius from the "
                 "door parameter file\n";
  }
}

// The calibration's range warnings (docs/calibration.md): where a sensor left its range.
void print_range_warnings(const SessionReader& session) {
  try {
    const std::vector<std::string> warnings = calibration::range_warnings(session);
    for (const std::string& warning : warnings) std::cout << "warning: " << printable(warning) << "\n";
  } catch (const std::exception& error) {
    std::cout << "warning: ranges not checked: " << error.what() << "\n";
  }
}

// Samples lost in recording (a recovered ring overflow, an imported empty cell): every run
// of each channel, runs at the same place in several channels on one line.
void print_gaps(const SessionReader& session) {
  struct Gap {
    LostRun run;
    std::string channels;
  };
  std::vector<Gap> gaps;
  for (const ChannelInfo& c : session.channels()) {
    ChannelSlice slice;
    try {
      slice = session.read(c.name);
    } catch (const SessionError& error) {
      std::cout << "gaps: not checked: " << printable(error.what()) << "\n";
      return;
    }
    for (const LostRun& run : lost_runs(c, slice)) {
      auto same = std::find_if(gaps.begin(), gaps.end(), [&](const Gap& g) {
        // The same scans: channels on one clock differ only by the converter's skew.
        return g.run.first_index == run.first_index && g.run.count == run.count &&
               std::abs(g.run.first_time_s - run.first_time_s) < 1e-3;
      });
      if (same == gaps.end()) {
        gaps.push_back({run, c.name});
      } else {
        same->channels += ", " + c.name;
      }
    }
  }
  std::sort(gaps.begin(), gaps.end(),
            [](const Gap& a, const Gap& b) { return a.run.first_time_s < b.run.first_time_s; });
  std::uint64_t samples = 0;
  for (const Gap& g : gaps) samples += g.run.count;
  std::cout << "gaps: " << gaps.size();
  if (!gaps.empty()) std::cout << " (" << samples << " samples lost; they read as missing)";
  std::cout << "\n";
  for (std::size_t i = 0; i < gaps.size() && i < 20; ++i) {
    const LostRun& r = gaps[i].run;
    std::printf("  %10.3f s to %10.3f s  %8zu samples  %s\n", r.first_time_s, r.last_time_s,
                r.count, gaps[i].channels.c_str());
  }
  if (gaps.size() > 20) std::printf("  ... %zu more\n", gaps.size() - 20);
  std::fflush(stdout);
}

// A haptic playback (tick_recorder.h): its channels keep each tick's own time (explicit
// times, so a late tick or a dropped record is where it was), and the group `haptic` states
// the nominal tick rate; one line with both and the intervals the ticks kept. Nothing for
// other sessions.
void print_playback_clock(const SessionReader& session) {
  std::string nominal_hz;
  try {
    nominal_hz = session.read_group_attribute("haptic", "rate_hz");
  } catch (const std::exception&) {
    return;  // not a playback
  }
  const ChannelInfo* timed = nullptr;
  for (const ChannelInfo& c : session.channels()) {
    if (c.sample_rate_hz == 0.0 && timed == nullptr) timed = &c;
  }
  if (timed == nullptr) return;
  const std::vector<double> times = session.read(timed->name).time_s;
  std::vector<double> intervals_ms;
  for (std::size_t i = 1; i < times.size(); ++i) {
    intervals_ms.push_back(1e3 * (times[i] - times[i - 1]));
  }
  std::printf(
      "playback clock: nominal %s Hz (haptic/rate_hz); the channels keep each tick's own "
      "time (rate \"times\")",
      printable(nominal_hz).c_str());
  if (!intervals_ms.empty()) {
    const double largest = *std::max_element(intervals_ms.begin(), intervals_ms.end());
    std::nth_element(intervals_ms.begin(), intervals_ms.begin() + intervals_ms.size() / 2,
                     intervals_ms.end());
    std::printf(": intervals median %.4g ms, largest %.4g ms over %zu ticks",
                intervals_ms[intervals_ms.size() / 2], largest, times.size());
  }
  std::printf("\n");
  std::fflush(stdout);
}

void run_info(const std::string& session_path) {
  const SessionReader session(session_path);
  const SessionMetadata& m = session.metadata();
  std::cout << "session " << session_path << "\n"
            << "  rig        " << printable(m.rig_name) << "\n"
            << "  operator   " << printable(m.operator_name) << "\n"
            << "  product    " << printable(m.product_id) << "\n"
            << "  started    " << printable(m.start_time_utc) << "\n"
            << "  software   " << printable(m.software_version) << "\n"
            << "  duration   " << format_seconds(session.end_time_s() - session.start_time_s())
            << " (" << format_seconds(session.start_time_s()) << " to "
            << format_seconds(session.end_time_s()) << ")\n";
  if (!m.notes.empty()) std::cout << "  notes      " << printable(m.notes) << "\n";
  std::cout << "channels:\n";
  // Columns as wide as their longest entry, so that every row lines up with the header.
  int name_w = 14, sensor_w = 13, raw_w = 7, unit_w = 6;
  for (const ChannelInfo& c : session.channels()) {
    name_w = std::max(name_w, int(printable(c.name).size()));
    sensor_w = std::max(sensor_w, int(printable(c.sensor_kind).size()));
    raw_w = std::max(raw_w, int(printable(c.raw_unit).size()));
    unit_w = std::max(unit_w, int(printable(c.unit).size()));
  }
  std::printf("  %-*s %-*s %10s %10s %-*s %-*s %s\n", name_w, "name", sensor_w, "sensor", "samples",
              "rate Hz", raw_w, "raw", unit_w, "unit", "calibration");
  std::fflush(stdout);
  for (const ChannelInfo& c : session.channels()) {
    // Explicit times (sample_rate_hz 0): "times", not a rate of 0.
    char rate[32] = "times";
    if (c.sample_rate_hz > 0) std::snprintf(rate, sizeof rate, "%g", c.sample_rate_hz);
    std::printf(
        "  %-*s %-*s %10zu %10s %-*s %-*s %s%s%s\n", name_w, printable(c.name).c_str(), sensor_w,
        printable(c.sensor_kind).c_str(), session.sample_count(c.name), rate, raw_w,
        printable(c.raw_unit).c_str(), unit_w, printable(c.unit).c_str(),
        c.calibration_id.empty() ? "(values are physical)" : printable(c.calibration_id).c_str(),
        c.geometry_calibration_id.empty() ? "" : ", geometry ",
        printable(c.geometry_calibration_id).c_str());
  }
  std::fflush(stdout);
  print_playback_clock(session);
  print_geometry(session);
  print_range_warnings(session);
  print_gaps(session);
  const std::vector<SessionEvent> events = session.events();
  std::map<std::string, int> by_kind;
  for (const SessionEvent& e : events) ++by_kind[e.kind];
  std::cout << "events: " << events.size();
  std::string separator = " (";
  for (const auto& [kind, count] : by_kind) {
    std::cout << separator << printable(kind) << " " << count;
    separator = ", ";
  }
  std::cout << (events.empty() ? "" : ")") << "\n";
  for (std::size_t i = 0; i < events.size() && i < 12; ++i) {
    std::printf("  %10.3f s  %-13s %s%s%s\n", events[i].time_s, printable(events[i].kind).c_str(),
                printable(events[i].channel).c_str(), events[i].channel.empty() ? "" : " ",
                printable(events[i].detail).c_str());
  }
  if (events.size() > 12) std::printf("  ... %zu more\n", events.size() - 12);
  std::fflush(stdout);
  std::cout << "calibrations:\n";
  for (const calibration::CalibrationRecord& r : session.calibrations()) {
    std::cout << "  " << printable(r.id) << "  " << printable(r.sensor_kind) << " "
              << printable(r.sensor_serial) << "  " << printable(r.unit) << " = ";
    for (std::size_t k = 0; k < r.coefficients.size(); ++k) {
      std::cout << (k ? " + " : "") << r.coefficients[k]
                << (k == 0   ? ""
                    : k == 1 ? "·x"
                             : "·x^" + std::to_string(k));
    }
    std::cout << "  (" << printable(r.method) << ")\n";
  }
}

// Metadata keys export writes and import reads (docs/csv-format.md).
constexpr const char* kCsvRigKey = "rig";
constexpr const char* kCsvOperatorKey = "operator";
constexpr const char* kCsvProductKey = "product";
constexpr const char* kCsvStartKey = "start_time_utc";

// A metadata value on one line: line breaks become spaces.
std::string one_line(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

struct ExportOptions {
  std::string session_path;
  std::string csv_path;
  bool overwrite = false;
};

void run_export(const ExportOptions& options) {
  const std::string& session_path = options.session_path;
  const std::string& csv_path = options.csv_path;
  check_output_file(csv_path, {session_path}, options.overwrite);
  const SessionReader session(session_path);
  Recording recording = session_to_recording(session);
  // Who, what and when, so that import gives them back (docs/csv-format.md).
  const SessionMetadata& m = session.metadata();
  for (const auto& [key, value] : {std::pair<std::string, std::string>{kCsvRigKey, m.rig_name},
                                   {kCsvOperatorKey, m.operator_name},
                                   {kCsvProductKey, m.product_id},
                                   {kCsvStartKey, m.start_time_utc}}) {
    if (!value.empty()) recording.metadata.emplace_back(key, one_line(value));
  }
  write_recording_csv_file(csv_path, recording);
  std::cerr << "wrote " << csv_path << ": " << recording.size() << " rows\n";
}

struct ImportOptions {
  std::string csv_path;
  std::string out_path;
  std::string operator_name, product_id, notes;
  std::string tdms_map;  // TDMS files: TARGET=GROUP/CHANNEL,... (acquisition/tdms.h)
};

// A TDMS file (by its .tdms extension, any case) through --map, else the CSV exchange format.
Recording read_import(const ImportOptions& options) {
  std::string extension = std::filesystem::path(options.csv_path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".tdms") {
    if (!options.tdms_map.empty()) throw UsageError("--map is for TDMS files (*.tdms)");
    return read_recording_csv(options.csv_path, EmptyCells::kMissing);  // empty: lost samples
  }
  if (options.tdms_map.empty()) {
    throw UsageError("a TDMS file needs --map force=GROUP/CHANNEL,angle=GROUP/CHANNEL (or rate=)");
  }
  std::vector<TdmsMapItem> map;
  try {
    map = parse_tdms_map(options.tdms_map);
  } catch (const std::invalid_argument& error) {
    throw UsageError(error.what());
  }
  const TdmsFile file = read_tdms(options.csv_path);
  return tdms_to_recording(file, map, options.csv_path);
}

void run_import(const ImportOptions& options) {
  check_output_session(options.out_path, {options.csv_path});
  const Recording recording = read_import(options);
  // The recording's own rig, operator, product and start (an exported session's) unless
  // given; else "imported" and now.
  auto from_csv = [&recording](const char* key, const std::string& otherwise) {
    for (const auto& [k, value] : recording.metadata) {
      if (k == key && !value.empty()) return value;
    }
    return otherwise;
  };
  SessionMetadata metadata;
  metadata.rig_name = from_csv(kCsvRigKey, "imported");
  metadata.operator_name =
      options.operator_name.empty() ? from_csv(kCsvOperatorKey, "") : options.operator_name;
  metadata.product_id =
      options.product_id.empty() ? from_csv(kCsvProductKey, "") : options.product_id;
  metadata.start_time_utc = from_csv(kCsvStartKey, utc_now_iso8601());
  metadata.software_version = std::string("doorbench ") + DOORBENCH_VERSION;
  metadata.notes = options.notes.empty() ? "imported from " + options.csv_path : options.notes;
  recording_to_session(recording, options.out_path, metadata);
  std::cerr << "wrote " << options.out_path << ": " << recording.size() << " samples\n";
}

}  // namespace

void add_session_commands(CLI::App& app, Action& action) {
  auto record = std::make_shared<RecordCommandOptions>();
  CLI::App* record_command = app.add_subcommand(
      "record",
      "Record a session from a rig: the simulated bench (the rig's door opened and closed by "
      "the virtual hand, through its sensor models) or a comedi DAQ card (needs --duration-s)");
  record_command->add_option("--rig", record->rig_path,
                             "Rig file (TOML); default: the built-in simulated-dishwasher rig");
  record_command
      ->add_option("--duration-s", record->recording.duration_s,
                   "How long to record (from the trigger when the rig has a [recording] "
                   "table); default: the rig's hand cycles")
      ->check(CLI::Range(0.001, 86400.0));
  record_command
      ->add_option("--max-wait-s", record->recording.max_wait_s,
                   "With a rig trigger: how long to wait, armed, for the start condition")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 86400.0));
  record_command->add_option("--out", record->out_path, "The new session file (HDF5)")->required();
  record_command->add_option("--operator", record->recording.operator_name, "Who records");
  record_command->add_option("--product", record->recording.product_id, "The door or product");
  record_command->add_option("--notes", record->recording.notes, "Free text kept in the session");
  record_command
      ->add_option("--flush-interval-s", record->recording.flush_interval_s,
                   "How often the recording journal is synced to disk: at most about this much "
                   "is lost if the machine dies (docs/crash-safety.md)")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 10.0));
  record_command->callback([record, &action] { action = [record] { run_record(*record); }; });

  auto recover = std::make_shared<RecoverCommandOptions>();
  CLI::App* recover_command = app.add_subcommand(
      "recover",
      "Make the session of a recording that was killed, lost power or ran out of disk from "
      "its journal (S.h5.journal); `record` does this by itself for its output folder");
  recover_command
      ->add_option("FILE", recover->file, "The journal (S.h5.journal), or the session S.h5")
      ->required();
  recover_command->add_option("--out", recover->out_path,
                              "The session to write; default: the journal's name without "
                              ".journal");
  recover_command->callback([recover, &action] { action = [recover] { run_recover(*recover); }; });

  auto info_path = std::make_shared<std::string>();
  CLI::App* info = app.add_subcommand(
      "info", "Show a session: metadata, channels, rates, duration, events, calibration");
  info->add_option("SESSION", *info_path, "Session file (HDF5)")->required();
  info->callback([info_path, &action] { action = [info_path] { run_info(*info_path); }; });

  auto export_options = std::make_shared<ExportOptions>();
  CLI::App* export_command = app.add_subcommand(
      "export",
      "Write a session as CSV (the exchange format: physical units, strokes marked, the force "
      "signed by the load cell's mounting)");
  export_command->add_option("SESSION", export_options->session_path, "Session file (HDF5)")
      ->required();
  export_command->add_option("--csv", export_options->csv_path, "The CSV file to write")
      ->required();
  export_command->add_flag("--overwrite", export_options->overwrite, "Replace an existing CSV file");
  export_command->callback([export_options, &action] {
    action = [export_options] { run_export(*export_options); };
  });

  auto import = std::make_shared<ImportOptions>();
  CLI::App* import_command = app.add_subcommand(
      "import",
      "Make a session of a recording from elsewhere: the CSV exchange format, or a TDMS file "
      "(LabVIEW, SignalExpress, DAQmx logging) with --map (docs/tdms.md)");
  import_command
      ->add_option("CSV", import->csv_path, "Recording (CSV exchange format, or *.tdms with --map)")
      ->required();
  import_command->add_option("--out", import->out_path, "The new session file (HDF5)")->required();
  import_command->add_option("--operator", import->operator_name, "Who recorded it");
  import_command->add_option("--product", import->product_id, "The door or product");
  import_command->add_option("--notes", import->notes, "Free text kept in the session");
  import_command->add_option("--map", import->tdms_map,
                             "TDMS channels: force=GROUP/CHANNEL,angle=GROUP/CHANNEL[,rate=...]"
                             "[,time=...][,NAME_UNIT=...]");
  import_command->callback([import, &action] { action = [import] { run_import(*import); }; });
}

}  // namespace doorbench::app
