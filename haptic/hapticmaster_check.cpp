#include "haptic/hapticmaster_check.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "core/percentile.h"
#include "haptic/hapticmaster_protocol.h"

namespace doorbench::haptic {
namespace {

std::string ms(double value_ms) {
  std::ostringstream out;
  out.precision(value_ms < 10 ? 3 : 4);
  out << value_ms << " ms";
  return out.str();
}

// The round trips: the driver's own loop at zero force, the tick's part played by this thread
// (one command a millisecond, so the driver's watchdog stays quiet), until `count` are done.
std::vector<double> time_round_trips(HapticMasterDevice& device, int count,
                                     const std::function<void(const std::string&)>& say) {
  const auto began = std::chrono::steady_clock::now();
  auto next_report = began + std::chrono::seconds(1);
  while (device.round_trips() < static_cast<std::uint64_t>(count)) {
    device.command_force(Vec3::Zero());
    const DeviceSample sample = device.read();
    if (!sample.link_ok) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (say && std::chrono::steady_clock::now() >= next_report) {
      say(device.name() + ": round trips " + std::to_string(device.round_trips()) + " of " +
          std::to_string(count));
      next_report += std::chrono::seconds(1);
    }
  }
  device.stop();
  // The I/O thread may finish one more exchange before it stops: report exactly `count`.
  std::vector<double> times = device.round_trip_times_s();
  if (times.size() > static_cast<std::size_t>(count)) times.resize(static_cast<std::size_t>(count));
  return times;
}

}  // namespace

std::string HapticMasterCheckOptions::validate() const {
  if (exchanges < 100 || exchanges > 1000000) return "exchanges must be in [100, 1000000]";
  if (!(inertia_kg >= 2.0 && inertia_kg <= 100.0)) return "inertia_kg must be in [2, 100] kg";
  if (!(test_force_N > 0.0 && test_force_N <= 10.0)) return "test_force_N must be in (0, 10] N";
  if (!(damping_ratio > 0.0 && damping_ratio <= 1.0)) return "damping_ratio must be in (0, 1]";
  return driver.validate();
}

double stiffness_limit_for_delay(double inertia_kg, double delay_s, double damping_ratio) noexcept {
  if (!(delay_s > 0.0)) return 0.0;
  return 4.0 * damping_ratio * damping_ratio * inertia_kg / (delay_s * delay_s);
}

bool HapticMasterCheckReport::passed() const {
  return std::none_of(items.begin(), items.end(),
                      [](const HapticMasterCheckItem& item) { return item.status == "fail"; });
}

std::string HapticMasterCheckReport::text() const {
  std::ostringstream out;
  out << "HapticMaster check of " << device << "\n";
  std::size_t width = 0;
  for (const HapticMasterCheckItem& item : items) width = std::max(width, item.name.size());
  for (const HapticMasterCheckItem& item : items) {
    out << "  " << item.name << std::string(width - item.name.size(), ' ') << "  " << item.status
        << std::string(8 - std::min<std::size_t>(7, item.status.size()), ' ') << item.detail
        << "\n";
  }
  out << (passed() ? "result: passed" : "result: FAILED") << "\n";
  return out.str();
}

std::string HapticMasterCheckReport::json() const {
  nlohmann::ordered_json j;
  j["device"] = device;
  j["passed"] = passed();
  j["startup"] = {{"initial_state", startup.initial_state},
                  {"emergency_button", startup.emergency_button},
                  {"emergency_relay_closed", startup.emergency_relay_closed},
                  {"emergency_signals_reported", startup.emergency_signals_reported},
                  {"base_axis_offset_m", startup.base_axis_offset_m},
                  {"was_calibrated", startup.was_calibrated},
                  {"homing_s", startup.homing_s},
                  {"workspace_source", startup.workspace_source},
                  {"workspace_r_phi_z_min",
                   {startup.workspace_r_phi_z_min.x(), startup.workspace_r_phi_z_min.y(),
                    startup.workspace_r_phi_z_min.z()}},
                  {"workspace_r_phi_z_max",
                   {startup.workspace_r_phi_z_max.x(), startup.workspace_r_phi_z_max.y(),
                    startup.workspace_r_phi_z_max.z()}},
                  {"inertia_read_back_kg", startup.inertia_read_back_kg}};
  j["workspace_box_m"] = {
      {"min", {limits.workspace_min.x(), limits.workspace_min.y(), limits.workspace_min.z()}},
      {"max", {limits.workspace_max.x(), limits.workspace_max.y(), limits.workspace_max.z()}}};
  j["round_trip"] = {{"count", round_trips},
                     {"p50_ms", rtt_p50_ms},
                     {"p99_ms", rtt_p99_ms},
                     {"max_ms", rtt_max_ms},
                     {"mean_ms", rtt_mean_ms},
                     {"loop_period_ms", loop_period_ms},
                     {"effective_delay_ms", effective_delay_ms}};
  j["stiffness_limit_N_per_m"] = stiffness_limit_N_per_m;
  j["disconnect"] = {{"tested", disconnect_tested},
                     {"force_after_N", force_after_disconnect_N},
                     {"state_after", state_after_disconnect}};
  nlohmann::ordered_json checks = nlohmann::ordered_json::array();
  for (const HapticMasterCheckItem& item : items) {
    checks.push_back({{"name", item.name}, {"status", item.status}, {"detail", item.detail}});
  }
  j["checks"] = checks;
  return j.dump(2);
}

namespace {

void add(HapticMasterCheckReport& report, std::string name, std::string status,
         std::string detail) {
  report.items.push_back({std::move(name), std::move(status), std::move(detail)});
}

// 1. Start-up, as playback does it (a refusal is the check's answer: thrown by name).
void check_startup(HapticMasterDevice& device, const HapticMasterCheckOptions& options,
                   HapticMasterCheckReport& report) {
  device.start(options.inertia_kg);
  report.startup = device.startup_report();
  report.limits = device.limits();
  const HapticMasterStartup& s = report.startup;
  add(report, "device answers", "pass", "state '" + s.initial_state + "' before start");
  if (s.emergency_signals_reported) {
    add(report, "emergency button", "pass", "not pushed");
    add(report, "emergency relay", "pass", "closed (the device was started)");
  } else {
    add(report, "emergency button", "warn", "the device does not report it (error reply)");
    add(report, "emergency relay", "warn", "the device does not report it (error reply)");
  }
  add(report, "position calibration", "pass",
      s.was_calibrated ? "calibrated"
                       : "was not calibrated: homed in " +
                             hm::format_device_number(std::round(s.homing_s * 10) / 10) + " s");
  add(report, "effects of other programs", "pass", "removed (remove all)");
  add(report, "workspace", s.workspace_source == "device" ? "pass" : "warn",
      "r " + hm::format_device_number(s.workspace_r_phi_z_min.x()) + ".." +
          hm::format_device_number(s.workspace_r_phi_z_max.x()) + " m, phi " +
          hm::format_device_number(s.workspace_r_phi_z_min.y()) + ".." +
          hm::format_device_number(s.workspace_r_phi_z_max.y()) + " rad, z " +
          hm::format_device_number(s.workspace_r_phi_z_min.z()) + ".." +
          hm::format_device_number(s.workspace_r_phi_z_max.z()) + " m about an axis " +
          hm::format_device_number(s.base_axis_offset_m) + " m behind the origin (" +
          s.workspace_source + ")");
  add(report, "inertia", "pass",
      "set " + hm::format_device_number(options.inertia_kg) + " kg, read back " +
          hm::format_device_number(s.inertia_read_back_kg) + " kg");
}

// The round trips' statistics, the delay they give and the stiffness limit for it.
void summarise_round_trips(const std::vector<double>& rtt_s, bool complete,
                           const HapticMasterCheckOptions& options,
                           HapticMasterCheckReport& report) {
  double sum = 0.0;
  for (const double t : rtt_s) sum += t;
  report.rtt_mean_ms = 1e3 * sum / static_cast<double>(rtt_s.size());
  report.rtt_p50_ms = 1e3 * percentile(rtt_s, 0.50);
  report.rtt_p99_ms = 1e3 * percentile(rtt_s, 0.99);
  report.rtt_max_ms = 1e3 * *std::max_element(rtt_s.begin(), rtt_s.end());
  report.loop_period_ms = 1e3 / options.driver.io_rate_hz;
  report.effective_delay_ms = 0.5 * report.loop_period_ms + report.rtt_p99_ms;
  report.stiffness_limit_N_per_m = stiffness_limit_for_delay(
      options.inertia_kg, 1e-3 * report.effective_delay_ms, options.damping_ratio);
  if (complete) {
    add(report, "round-trip time", report.rtt_p99_ms <= 2.0 ? "pass" : "warn",
        "p50 " + ms(report.rtt_p50_ms) + ", p99 " + ms(report.rtt_p99_ms) + ", max " +
            ms(report.rtt_max_ms) + " over " + std::to_string(report.round_trips) +
            (report.rtt_p99_ms <= 2.0 ? ""
                                      : " (p99 above 2 ms: stiff parts belong on the device)"));
  }
  std::ostringstream limit;
  limit.precision(3);
  limit << report.stiffness_limit_N_per_m << " N/m at " << options.inertia_kg << " kg with "
        << report.effective_delay_ms << " ms delay (half a period + p99 round trip, damping ratio "
        << options.damping_ratio
        << "); a door's stiffest slope played from the host must stay below it";
  add(report, "host-loop stiffness limit", "pass", limit.str());
}

// 2. Round trips.
void check_round_trips(HapticMasterDevice& device, const HapticMasterCheckOptions& options,
                       HapticMasterCheckReport& report) {
  const std::vector<double> rtt_s =
      time_round_trips(device, options.exchanges, options.driver.progress);
  report.round_trips = static_cast<int>(rtt_s.size());
  const std::string lost = device.last_error();
  const bool complete = lost.empty() && report.round_trips >= options.exchanges;
  if (!complete) {
    add(report, "round-trip time", "fail",
        std::to_string(report.round_trips) + " of " + std::to_string(options.exchanges) +
            " round trips" + (lost.empty() ? "" : ": " + lost));
  }
  if (!rtt_s.empty()) summarise_round_trips(rtt_s, complete, options, report);
}

// Pushes the arm on a connection of its own, then drops that connection without a stop.
void push_and_abandon(const std::string& address, const HapticMasterOptions& quiet,
                      const HapticMasterCheckOptions& options) {
  HapticMasterDevice pusher(address, quiet);
  pusher.start(options.inertia_kg);
  pusher.command_force(Vec3(options.test_force_N, 0.0, 0.0));
  const std::uint64_t from = pusher.round_trips();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (pusher.round_trips() < from + 20 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  pusher.abandon_connection_for_test();
}

// 3. What a disconnect leaves on the device (only with the user's word).
void check_disconnect(const std::string& address, const HapticMasterCheckOptions& options,
                      HapticMasterCheckReport& report) {
  const std::string what = "The arm will be pushed with " +
                           hm::format_device_number(options.test_force_N) +
                           " N along +x for about a second, then the connection is closed "
                           "without a stop, as a crashed program would. Keep hands off the arm.";
  if (!options.confirm || !options.confirm(what)) {
    add(report, "disconnect leaves zero force", "skipped", "not confirmed (--yes, or answer y)");
    return;
  }
  HapticMasterOptions quiet = options.driver;
  quiet.command_watchdog_s = 0.0;  // the test itself stops commanding
  push_and_abandon(address, quiet, options);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  HapticMasterDevice reader(address, quiet);
  reader.connect_only();
  report.disconnect_tested = true;
  const hm::Reply state = hm::parse_reply(reader.exchange("get state"));
  report.state_after_disconnect =
      state.kind == hm::Reply::Kind::kString ? state.string : state.text;
  std::string force_text;
  try {
    force_text = reader.exchange("get " + quiet.bias_object + " force");
  } catch (const DeviceError&) {
    force_text = "";  // the object is gone: the device removed it on the disconnect
  }
  const hm::Reply force = hm::parse_reply(force_text);
  report.force_after_disconnect_N =
      force.kind == hm::Reply::Kind::kVector ? force.vector.norm() : 0.0;
  reader.stop();  // zero force, state stop, remove the object: whatever was left
  const bool kept =
      report.force_after_disconnect_N > 0.0 && report.state_after_disconnect == "force";
  add(report, "disconnect leaves zero force", kept ? "warn" : "pass",
      kept ? "the device kept " + hm::format_device_number(report.force_after_disconnect_N) +
                 " N in state force after the connection closed: doorbench's fail-safe "
                 "stops it on a fresh connection, but a killed doorbench or a host power "
                 "loss would leave the force on (use the device's emergency button)"
           : "state '" + report.state_after_disconnect + "', " +
                 hm::format_device_number(report.force_after_disconnect_N) + " N after the close");
}

}  // namespace

HapticMasterCheckReport run_hapticmaster_check(const std::string& address,
                                               const HapticMasterCheckOptions& options) {
  // The check's own thread plays the tick at zero force; on a loaded machine it may sleep
  // longer than a render loop would, and at zero force a longer watchdog is safe.
  HapticMasterOptions driver = options.driver;
  driver.command_watchdog_s = std::max(driver.command_watchdog_s, 1.0);
  HapticMasterDevice device(address, driver);  // checks the address and driver options
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw DeviceError(device.name() + ": option " + problem);
  }
  const auto say = options.driver.progress;
  HapticMasterCheckReport report;
  report.device = device.name();
  if (say) say(device.name() + ": start-up checks");
  check_startup(device, options, report);
  if (say) say(device.name() + ": timing " + std::to_string(options.exchanges) + " round trips");
  check_round_trips(device, options, report);
  check_disconnect(address, options, report);
  return report;
}

}  // namespace doorbench::haptic
