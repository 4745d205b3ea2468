// The HapticMaster driver's fail-safe and start-up checks against the protocol emulator as a
// real process (docs/haptic-safety.md, "The HapticMaster's fail-safe"; docs/hapticmaster.md).
//
// Every failure path must end with the device's force at zero and its state "stop", seen by
// the device itself: the emulator writes time-stamped lines (CLOCK_MONOTONIC, the clock of
// std::chrono::steady_clock here) whenever its state or its applied bias force changes, and
// when it injects a fault. Each test measures from the fault to the first "state=stop
// bias=0" and checks the stated time.
#include <signal.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.h"
#include "fixtures/temp_dir.h"
#include "haptic/hapticmaster_device.h"
#include "haptic/hapticmaster_protocol.h"
#include "tests/support/hapticmaster_emulator_process.h"
#include "tests/support/run_doorbench.h"

using namespace doorbench::haptic;
using doorbench::testing::TempDir;

namespace {

using Emulator = doorbench::testing::HapticMasterEmulator;

// The stated times (docs/haptic-safety.md). A fault the I/O thread sees at once (error reply,
// corrupt stream, closed connection, brake): zero force and "stop" within two emergency
// attempts (2 x emergency_timeout_s = 0.2 s) plus one I/O period; the tests allow 0.1 s more
// for a loaded machine's scheduling of the Python emulator.
constexpr double kImmediateBound_s = 0.2 + 0.001 + 0.1;

struct Line {
  double time_s = 0.0;
  std::string text;
};

std::vector<Line> events_of(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<Line> lines;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    Line parsed;
    fields >> parsed.time_s;
    std::getline(fields >> std::ws, parsed.text);
    lines.push_back(parsed);
  }
  return lines;
}

// The time of the first line starting with `prefix` at or after `after_s`; -1 if none.
double first_at(const std::vector<Line>& lines, const std::string& prefix, double after_s = 0.0) {
  for (const Line& line : lines) {
    if (line.time_s >= after_s && line.text.rfind(prefix, 0) == 0) return line.time_s;
  }
  return -1.0;
}

constexpr const char* kStopped = "device state=stop bias=0.0";

// Waits until the emulator's events show `prefix` (after `after_s`) or `timeout_s` passes.
double wait_for(const std::filesystem::path& file, const std::string& prefix, double after_s = 0.0,
                double timeout_s = 5.0) {
  const double end = doorbench::monotonic_now_s() + timeout_s;
  for (;;) {
    const double at = first_at(events_of(file), prefix, after_s);
    if (at >= 0.0 || doorbench::monotonic_now_s() > end) return at;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// The tick's part, on a thread: commands `force` every 1 ms until told to stop. The last
// command's moment is bracketed by the clock read just before and just after it: under load
// the thread can be held between the command and its join for longer than a bound allows.
class Ticker {
 public:
  Ticker(HapticMasterDevice& device, const Vec3& force)
      : thread_([this, &device, force] {
          while (!quit_.load()) {
            before_last_s_.store(doorbench::monotonic_now_s());
            device.command_force(force);
            after_last_s_.store(doorbench::monotonic_now_s());
            (void)device.read();
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
          }
        }) {}
  ~Ticker() { halt(); }
  Ticker(const Ticker&) = delete;
  Ticker& operator=(const Ticker&) = delete;

  // Stops the thread; the clock just before and just after its last command.
  struct LastCommand {
    double before_s = 0.0, after_s = 0.0;
  };
  LastCommand halt() {
    if (thread_.joinable()) {
      quit_.store(true);
      thread_.join();
    }
    return {before_last_s_.load(), after_last_s_.load()};
  }

 private:
  std::atomic<bool> quit_{false};
  std::atomic<double> before_last_s_{0.0}, after_last_s_{0.0};
  std::thread thread_;
};

// Runs the device with a 5 N force commanded every tick until its link is lost (or 5 s).
// Returns the last sample.
DeviceSample run_until_lost(HapticMasterDevice& device) {
  Ticker ticker(device, Vec3(5.0, 0.0, 0.0));
  const double end = doorbench::monotonic_now_s() + 5.0;
  DeviceSample s = device.read();
  while (s.link_ok && doorbench::monotonic_now_s() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    s = device.read();
  }
  return s;
}

const std::size_t kCommandsOfStart = 17;  // what start() sends (test_hapticmaster_device.cpp)

}  // namespace

TEST_CASE("hapticmaster fail-safe: an error reply at start stops the device on the open connection",
          "[hapticmaster][failsafe]") {
  TempDir dir("hm_failsafe_error");
  const auto events = dir / "events.log";
  Emulator emulator({"--events", events.string(), "--fail", "get measforce=Force sensor overload"});
  // The error comes in the first reading: start() fails and leaves the device stopped.
  {
    HapticMasterDevice device(emulator.address());
    CHECK_THROWS_WITH(device.start(5.0),
                      emulator.name() + ": 'get measforce' failed: Force sensor overload");
    CHECK(device.device_stopped());
    CHECK(wait_for(events, kStopped) >= 0.0);
  }
}

TEST_CASE("hapticmaster fail-safe: each failure in the loop ends at zero force in state stop",
          "[hapticmaster][failsafe]") {
  struct Case {
    std::string name;
    std::vector<std::string> options;
    std::string fault;  // the emulator's fault line
    std::string error;  // what last_error() says first
    double bound_s;
  };
  // About 0.1 s of round trips with the force on, then the fault.
  const std::string after = std::to_string(kCommandsOfStart + 4 * 100);
  const std::vector<Case> cases = {
      {"corrupt reply",
       {"--garbage-after", after},
       "fault garbage",
       "not the HapticMaster protocol",
       kImmediateBound_s},
      {"dropped connection",
       {"--drop-after", after},
       "fault drop",
       "connection closed by the device",
       kImmediateBound_s},
      // A connection that stops answering: seen after reply_timeout_s (0.2 s here).
      {"stalled device",
       {"--stall-after", after},
       "fault stall",
       "no reply within 0.2 s",
       0.2 + kImmediateBound_s},
  };
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.name) {
      TempDir dir("hm_failsafe_loop");
      const auto events = dir / "events.log";
      std::vector<std::string> options = {"--events", events.string()};
      options.insert(options.end(), c.options.begin(), c.options.end());
      Emulator emulator(options);
      HapticMasterOptions driver;
      driver.reply_timeout_s = 0.2;
      HapticMasterDevice device(emulator.address(), driver);
      device.start(5.0);
      const DeviceSample s = run_until_lost(device);
      REQUIRE_FALSE(s.link_ok);
      CHECK_THAT(device.last_error(), Catch::Contains(c.error));
      CHECK_THAT(device.last_error(),
                 Catch::EndsWith("; the device was stopped (zero force, state stop)"));
      CHECK(device.device_stopped());
      const std::vector<Line> lines = events_of(events);
      const double force_on = first_at(lines, "device state=force bias=5.0");
      const double fault = first_at(lines, c.fault);
      REQUIRE(force_on >= 0.0);
      REQUIRE(fault >= force_on);
      const double stopped = wait_for(events, kStopped, fault);
      REQUIRE(stopped >= 0.0);
      INFO(c.name << ": zero force and state stop " << stopped - fault << " s after the fault");
      CHECK(stopped - fault <= c.bound_s);
      device.stop();
    }
  }
}

TEST_CASE("hapticmaster fail-safe: an error reply in the loop stops the device at once",
          "[hapticmaster][failsafe]") {
  TempDir dir("hm_failsafe_error_loop");
  const auto events = dir / "events.log";
  // The 5 N force is accepted; the device refuses 6 N (as one refusing a force would).
  Emulator emulator({"--events", events.string(), "--fail",
                     "set doorbench_bias force [6,0,0]=Force not allowed"});
  HapticMasterDevice device(emulator.address());
  device.start(5.0);
  double refused_at = -1.0;
  {
    Ticker five(device, Vec3(5.0, 0.0, 0.0));
    REQUIRE(wait_for(events, "device state=force bias=5.0") >= 0.0);
  }
  {
    Ticker six(device, Vec3(6.0, 0.0, 0.0));
    refused_at = wait_for(events, "fault fail");
    REQUIRE(refused_at >= 0.0);
    const double stopped = wait_for(events, kStopped, refused_at);
    REQUIRE(stopped >= 0.0);
    INFO("zero force and state stop " << stopped - refused_at << " s after the error reply");
    CHECK(stopped - refused_at <= kImmediateBound_s);
  }
  CHECK_FALSE(device.read().link_ok);
  CHECK(device.last_error() == emulator.name() +
                                   ": 'set doorbench_bias force [6,0,0]' failed: Force not "
                                   "allowed; the device was stopped (zero force, state stop)");
  // The open connection was still in step, so the stop went on it: no second connection.
  const std::vector<Line> lines = events_of(events);
  CHECK(first_at(lines, "cmd set state stop", refused_at) >= 0.0);
  device.stop();
}

TEST_CASE(
    "hapticmaster fail-safe: the I/O thread's watchdog stops the device when the tick "
    "stalls",
    "[hapticmaster][failsafe]") {
  TempDir dir("hm_failsafe_watchdog");
  const auto events = dir / "events.log";
  Emulator emulator({"--events", events.string()});
  HapticMasterOptions options;  // command_watchdog_s 0.1 s
  HapticMasterDevice device(emulator.address(), options);
  device.start(5.0);
  Ticker::LastCommand last;
  {
    Ticker ticker(device, Vec3(5.0, 0.0, 0.0));
    REQUIRE(wait_for(events, "device state=force bias=5.0") >= 0.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    last = ticker.halt();  // the tick stops publishing; nobody calls stop()
  }
  const double stopped = wait_for(events, kStopped, last.before_s);
  REQUIRE(stopped >= 0.0);
  INFO("zero force and state stop " << stopped - last.before_s << " to " << stopped - last.after_s
                                    << " s after the tick's last command");
  CHECK(stopped - last.before_s >= options.command_watchdog_s - 0.002);
  CHECK(stopped - last.after_s <= options.command_watchdog_s + kImmediateBound_s);
  CHECK_FALSE(device.read().link_ok);
  CHECK_THAT(device.last_error(), Catch::Contains("watchdog: the render loop sent no command for"));
  device.stop();
}

TEST_CASE("hapticmaster fail-safe: the watchdog arms at the render loop's first command",
          "[hapticmaster][failsafe]") {
  SECTION("a first command 0.5 s after start() finds the link up and is applied") {
    TempDir dir("hm_watchdog_late_first");
    const auto events = dir / "events.log";
    Emulator emulator({"--events", events.string()});
    HapticMasterDevice device(emulator.address());  // command_watchdog_s 0.1 s
    device.start(5.0);
    // What lies before a first tick on a busy machine: five times the watchdog's limit.
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    CHECK(device.read().link_ok);
    CHECK(std::isnan(device.first_command_arrival_s()));
    const double commanded_s = doorbench::monotonic_now_s();
    {
      Ticker ticker(device, Vec3(5.0, 0.0, 0.0));
      REQUIRE(wait_for(events, "device state=force bias=5.0") >= 0.0);
    }
    CHECK(device.last_error() == "");
    CHECK(device.first_command_arrival_s() > commanded_s);
    CHECK(device.first_command_arrival_s() < commanded_s + 1.0);
    device.stop();
  }
  SECTION("no first command within first_command_timeout_s: the device is stopped, saying so") {
    TempDir dir("hm_watchdog_no_first");
    const auto events = dir / "events.log";
    Emulator emulator({"--events", events.string()});
    HapticMasterOptions options;
    options.first_command_timeout_s = 0.3;
    HapticMasterDevice device(emulator.address(), options);
    const double started_s = doorbench::monotonic_now_s();
    device.start(5.0);
    const double stopped = wait_for(events, kStopped, started_s);
    REQUIRE(stopped >= 0.0);
    CHECK(stopped - started_s >= 0.3);
    CHECK_FALSE(device.read().link_ok);
    const std::string error = device.last_error();
    INFO(error);
    const std::string head =
        emulator.name() + ": watchdog: the render loop sent no first command within 0.3";
    CHECK(error.rfind(head, 0) == 0);
    const std::string tail =
        " s of the device's start (limit 0.3 s); the device was stopped (zero force, state stop)";
    CHECK(error.size() > tail.size());
    CHECK(error.substr(error.size() - std::min(error.size(), tail.size())) == tail);
    CHECK(device.stop_reason() == error);
    device.stop();
  }
}

TEST_CASE("hapticmaster fail-safe: brake() zeroes the force and stops the device",
          "[hapticmaster][failsafe]") {
  TempDir dir("hm_failsafe_brake");
  const auto events = dir / "events.log";
  Emulator emulator({"--events", events.string(), "--ext-force", "[0,0,3]"});
  HapticMasterDevice device(emulator.address());
  device.start(5.0);
  double braked_s = 0.0;
  {
    Ticker ticker(device, Vec3(5.0, 0.0, 0.0));
    REQUIRE(wait_for(events, "device state=force bias=5.0") >= 0.0);
    braked_s = doorbench::monotonic_now_s();
    device.brake();  // what the render loop does on a velocity or workspace trip
    const double stopped = wait_for(events, kStopped, braked_s);
    REQUIRE(stopped >= 0.0);
    INFO("zero force and state stop " << stopped - braked_s << " s after brake()");
    CHECK(stopped - braked_s <= kImmediateBound_s);
  }
  CHECK(device.last_error() == "");  // a brake is not a link failure
  device.stop();
  // stop() removes the bias object afterwards on the same, intact connection.
  CHECK(first_at(events_of(events), "cmd remove doorbench_bias", braked_s) >= 0.0);
}

TEST_CASE("hapticmaster fail-safe: Ctrl-C and SIGTERM during doorbench play stop the device",
          "[hapticmaster][failsafe][cli]") {
  for (const int signal_number : {SIGINT, SIGTERM}) {
    DYNAMIC_SECTION((signal_number == SIGINT ? "SIGINT" : "SIGTERM")) {
      TempDir dir("hm_failsafe_signal");
      const auto events = dir / "events.log";
      Emulator emulator({"--events", events.string()});
      doorbench::testing::ChildProcess play({DOORBENCH_EXECUTABLE, "play", "--device",
                                             "hapticmaster://" + emulator.address(), "--duration-s",
                                             "30", "--max-tick-stall-ms", "1000", "--out",
                                             (dir / "play.h5").string()});
      // SCHED_FIFO where permitted (as a lab runs it): a best-effort tick and I/O thread can
      // stall past max_stale_ticks on a loaded machine and trip before the signal comes.
      // Playing: the device is in state force (its force follows the door, near zero at rest).
      REQUIRE(wait_for(events, "device state=force", 0.0, 20.0) >= 0.0);
      std::this_thread::sleep_for(std::chrono::milliseconds(700));
      const double signalled_s = doorbench::monotonic_now_s();
      play.send_signal(signal_number);
      const int status = play.wait_exit(10.0);
      CHECK(status == 0);
      const double stopped = wait_for(events, kStopped, signalled_s);
      REQUIRE(stopped >= 0.0);
      INFO("zero force and state stop " << stopped - signalled_s << " s after the signal");
      // The control thread sees the signal within its 0.1 s status interval, the safety layer
      // ramps down over 0.02 s, then the brake: within 0.3 s (docs/haptic-safety.md).
      CHECK(stopped - signalled_s <= 0.3 + 0.1);
      CHECK(std::filesystem::exists(dir / "play.h5"));
    }
  }
}

TEST_CASE("hapticmaster start-up: homing, emergency signals, other programs' effects, workspace",
          "[hapticmaster][startup]") {
  SECTION("an uncalibrated device is homed first, with progress") {
    TempDir dir("hm_startup_homing");
    const auto events = dir / "events.log";
    Emulator emulator({"--events", events.string(), "--uncalibrated", "--homing-s", "1.2"});
    HapticMasterOptions options;
    std::vector<std::string> progress;
    options.progress = [&](const std::string& line) { progress.push_back(line); };
    HapticMasterDevice device(emulator.address(), options);
    device.start(5.0);
    const HapticMasterStartup& report = device.startup_report();
    CHECK_FALSE(report.was_calibrated);
    CHECK(report.homing_s > 1.1);
    CHECK(report.homing_s < 3.0);
    REQUIRE(progress.size() >= 2);
    CHECK(progress.front() == emulator.name() +
                                  ": position not calibrated: homing (set state init); keep "
                                  "clear of the arm");
    CHECK_THAT(progress.back(), Catch::StartsWith(emulator.name() + ": homing done in "));
    const std::vector<Line> lines = events_of(events);
    const double init = first_at(lines, "cmd set state init");
    const double force = first_at(lines, "cmd set state force");
    REQUIRE(init >= 0.0);
    CHECK(force > init + 1.1);
    device.stop();
  }
  SECTION("a pushed emergency button is refused by name, and nothing is created") {
    TempDir dir("hm_startup_button");
    const auto log = dir / "commands.log";
    Emulator emulator({"--emergency-button", "--log", log.string()});
    HapticMasterDevice device(emulator.address());
    CHECK_THROWS_WITH(
        device.start(5.0),
        emulator.name() + ": the emergency button is pushed: release it, then start again");
    std::ifstream in(log);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    CHECK(text.find("create biasforce") == std::string::npos);
    CHECK(text.find("set state force") == std::string::npos);
  }
  SECTION("an open emergency relay (the device not started) is refused by name") {
    Emulator emulator({"--relay-off"});
    HapticMasterDevice device(emulator.address());
    CHECK_THROWS_WITH(device.start(5.0),
                      emulator.name() +
                          ": the emergency relay is open: the HapticMaster is not started (push "
                          "its start button), then start again");
  }
  SECTION("a device that does not report the emergency signals starts, and says so") {
    Emulator emulator({"--answer", "get emergencybuttonpushed=--- ERROR: Unknown parameter",
                       "--answer", "get emergencyrelay=--- ERROR: Unknown parameter"});
    HapticMasterDevice device(emulator.address());
    device.start(5.0);
    CHECK_FALSE(device.startup_report().emergency_signals_reported);
    device.stop();
  }
  SECTION("effects another program left are removed before the force state") {
    TempDir dir("hm_startup_leftover");
    const auto events = dir / "events.log";
    Emulator emulator({"--events", events.string(), "--leftover", "their_push"});
    REQUIRE(wait_for(events, "device state=off bias=5.0") >= 0.0);
    HapticMasterDevice device(emulator.address(), HapticMasterOptions{});
    device.start(5.0);
    const std::vector<Line> lines = events_of(events);
    const double removed = first_at(lines, "cmd remove all");
    const double force = first_at(lines, "cmd set state force");
    REQUIRE(removed >= 0.0);
    CHECK(force > removed);
    // In state force the only bias is ours, at zero.
    CHECK(first_at(lines, "device state=force bias=0.0") >= 0.0);
    CHECK(first_at(lines, "device state=force bias=5.0") < 0.0);
    device.stop();
  }
  SECTION("the workspace is read from the device and the inertia read back") {
    Emulator emulator;
    HapticMasterDevice device(emulator.address());
    const DeviceLimits assumed = device.limits();
    device.start(7.25);
    const HapticMasterStartup& report = device.startup_report();
    CHECK(report.workspace_source == "device");
    CHECK(report.workspace_r_phi_z_min.isApprox(Vec3(0.28, -0.5, -0.2)));
    CHECK(report.workspace_r_phi_z_max.isApprox(Vec3(0.64, 0.5, 0.2)));
    CHECK(report.base_axis_offset_m == 0.45);
    CHECK(report.inertia_read_back_kg == 7.25);
    const DeviceLimits read = device.limits();
    // The box lies inside the sector: every corner within r 0.28..0.64 m and |phi| <= 0.5
    // about the base axis 0.45 m behind the origin.
    for (int corner = 0; corner < 4; ++corner) {
      const double x = (corner & 1 ? read.workspace_max.x() : read.workspace_min.x()) + 0.45;
      const double y = corner & 2 ? read.workspace_max.y() : read.workspace_min.y();
      const double r = std::hypot(x, y);
      INFO("corner " << corner << ": r " << r << " phi " << std::atan2(y, x));
      CHECK(r >= 0.28 - 1e-9);
      CHECK(r <= 0.64 + 1e-9);
      CHECK(std::abs(std::atan2(y, x)) <= 0.5 + 1e-9);
    }
    CHECK(read.workspace_min.z() == -0.2);
    CHECK(read.workspace_max.z() == 0.2);
    // The box is no smaller than the assumed one it replaces.
    const double area = (read.workspace_max - read.workspace_min).head<2>().prod();
    const double assumed_area = (assumed.workspace_max - assumed.workspace_min).head<2>().prod();
    CHECK(area >= assumed_area * 0.95);
    device.stop();
  }
  SECTION("an inertia the device does not keep is an error") {
    Emulator emulator({"--answer", "get inertia=3.0"});
    HapticMasterDevice device(emulator.address());
    CHECK_THROWS_WITH(
        device.start(5.0),
        emulator.name() + ": 'set inertia 5' was accepted but the device reports 3.0 kg");
  }
  SECTION("workspace replies of another shape are refused by name") {
    Emulator emulator({"--answer", "get workspace_r=[0.28,0.64]"});
    HapticMasterDevice device(emulator.address());
    CHECK_THROWS_WITH(
        device.start(5.0),
        emulator.name() + ": 'get workspace_r' answered '[0.28,0.64]', not [low,axis,high]");
  }
}

TEST_CASE("doorbench hapticmaster check: start-up, latency, stiffness limit and disconnect",
          "[hapticmaster][cli]") {
  TempDir dir("hm_check");
  Emulator emulator({"--uncalibrated", "--homing-s", "0.3", "--leftover", "their_push"});
  const auto json = dir / "check.json";
  const auto run = doorbench::testing::run_doorbench_shell(
      "hapticmaster check hapticmaster://" + emulator.address() +
          " --exchanges 500 --yes --json '" + json.string() + "'",
      dir);
  INFO(run.out << run.err);
  CHECK(run.status == 0);
  for (const std::string name :
       {"device answers", "emergency button", "emergency relay", "position calibration",
        "effects of other programs", "workspace", "inertia", "round-trip time",
        "host-loop stiffness limit", "disconnect leaves zero force"}) {
    CHECK_THAT(run.out, Catch::Contains("  " + name + " "));
  }
  CHECK_THAT(run.out, Catch::Contains("was not calibrated: homed in"));
  CHECK_THAT(run.out, Catch::Contains("over 500"));
  // The emulator keeps a bias force after a disconnect, as the public record says the device
  // does: a warning, with the fact.
  CHECK_THAT(run.out, Catch::Contains("disconnect leaves zero force  warn    the device kept 2 N "
                                      "in state force"));
  CHECK_THAT(run.out, Catch::EndsWith("result: passed\n"));
  std::ifstream in(json);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK_THAT(text, Catch::Contains("\"p99_ms\""));
  CHECK_THAT(text, Catch::Contains("\"stiffness_limit_N_per_m\""));
  CHECK_THAT(text, Catch::Contains("\"force_after_N\": 2.0"));
  // The report is an output like any other: an existing one is refused before the device is
  // touched (exit 2), --overwrite replaces it.
  const auto again = doorbench::testing::run_doorbench_shell(
      "hapticmaster check hapticmaster://" + emulator.address() + " --exchanges 200 --json '" +
          json.string() + "'",
      dir);
  CHECK(again.status == 2);
  CHECK_THAT(again.err,
             Catch::Contains(json.string() + ": exists (give --overwrite to replace it)"));
  const auto replaced = doorbench::testing::run_doorbench_shell(
      "hapticmaster check hapticmaster://" + emulator.address() + " --exchanges 200 --json '" +
          json.string() + "' --overwrite",
      dir);
  CHECK(replaced.status == 0);

  // Refusals name the step; without a terminal or --yes the disconnect test is skipped.
  Emulator pushed({"--emergency-button"});
  const auto refused = doorbench::testing::run_doorbench_shell(
      "hapticmaster check hapticmaster://" + pushed.address(), dir);
  CHECK(refused.status == 1);
  CHECK(refused.err.find("doorbench: hapticmaster://" + pushed.address() +
                         ": the emergency button is pushed: release it, then start again\n") !=
        std::string::npos);
  Emulator plain;
  const auto skipped = doorbench::testing::run_doorbench_shell(
      "hapticmaster check hapticmaster://" + plain.address() + " --exchanges 200", dir);
  CHECK(skipped.status == 0);
  CHECK_THAT(skipped.out, Catch::Contains("disconnect leaves zero force  skipped"));
  const auto bad = doorbench::testing::run_doorbench_shell("hapticmaster check sim", dir);
  CHECK(bad.status == 2);
  CHECK_THAT(bad.err, Catch::Contains("'sim' is not hapticmaster://HOST[:PORT]"));
}
