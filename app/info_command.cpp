// doorbench info: what a session holds, its gaps, calibrations and clock.
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
namespace {

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
    for (const CalibrationRecord& r : session.calibrations()) {
      if (r.id != c.geometry_calibration_id) continue;
      for (const char* name : {"handle_radius_m", "mounting_angle_deg"}) {
        if (const CalibrationQuantity* q = r.quantity(name)) {
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
    for (const std::string& warning : warnings)
      std::cout << "warning: " << printable(warning) << "\n";
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

// SessionReader::problems(), each on a "problem:" line; returns how many make the session
// unusable as it is.
int print_session_problems(const SessionReader& session) {
  int unusable = 0;
  for (const SessionProblem& problem : session.problems()) {
    std::cout << "problem: " << problem.message << "\n";
    if (problem.unusable) ++unusable;
  }
  return unusable;
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
  const int unusable = print_session_problems(session);
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
  for (const CalibrationRecord& r : session.calibrations()) {
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
  std::cout.flush();
  if (unusable > 0) {
    throw std::runtime_error(session_path + ": cannot be used as it is (" +
                             std::to_string(unusable) + " problem" + (unusable == 1 ? "" : "s") +
                             " above)");
  }
}

}  // namespace

void add_info_command(CLI::App& app, Action& action) {
  auto info_path = std::make_shared<std::string>();
  CLI::App* info = app.add_subcommand(
      "info", "Show a session: metadata, channels, rates, duration, events, calibration");
  info->add_option("SESSION", *info_path, "Session file (HDF5)")->required();
  info->callback([info_path, &action] { action = [info_path] { run_info(*info_path); }; });
}

}  // namespace doorbench::app
