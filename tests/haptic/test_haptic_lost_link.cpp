// The whole chain against the HapticMaster protocol emulator (a separate process, see
// docs/hapticmaster.md): the render loop plays the reference door through the driver in real
// time; the emulator drops the connection; the loop must end in a safe stop.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <regex>
#include <thread>

#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "haptic/hapticmaster_device.h"
#include "haptic/playback.h"
#include "tests/support/hapticmaster_emulator_process.h"

using namespace doorbench;
using namespace doorbench::haptic;

namespace {

// The detail of the session's "stop" event ("" without one).
std::string stop_event_of(const SessionReader& session) {
  for (const SessionEvent& event : session.events()) {
    if (event.kind == "stop") return event.detail;
  }
  return "";
}

// The first "safety" event named `name` ("" without one).
std::string safety_event_of(const SessionReader& session, const std::string& name) {
  for (const SessionEvent& event : session.events()) {
    if (event.kind == "safety" && event.detail.rfind(name + ":", 0) == 0) return event.detail;
  }
  return "";
}

}  // namespace

TEST_CASE("haptic chain: a lost HapticMaster connection ends the playback in a safe stop",
          "[haptic][hapticmaster]") {
  testing::TempDir dir("lost_link");
  // About 0.6 s of round trips (four commands each at 1 kHz), then the emulator hangs up.
  testing::ChildProcess emulator(
      {"/usr/bin/python3",
       std::string(DOORBENCH_SOURCE_DIR)
           .append("/tests/hapticmaster_emulator/hapticmaster_emulator.py"),
       "--drop-after", "2400"});
  const std::string line = emulator.read_line();
  REQUIRE(line.rfind("PORT ", 0) == 0);
  HapticMasterDevice device("127.0.0.1:" + line.substr(5));
  const DoorModel model = reference_model(ModelKind::kSensory);
  PlaybackOptions options;
  options.duration_s = 10.0;  // the link is lost long before
  options.real_time.request_fifo = false;
  // This test is about the link: a loaded machine's late ticks or slow replies must not trip
  // the deadline or stall watchdogs first (those have their own tests in test_haptic_safety).
  options.loop.safety.max_tick_interval_s = 1.0;
  options.loop.safety.max_stale_ticks = 5000;
  const std::filesystem::path path = dir.path / "lost.h5";
  SessionMetadata metadata;
  metadata.rig_name = "HapticMaster emulator";
  PlaybackSummary summary;
  {
    Playback playback(device, model, options, path, metadata,
                      PlaybackSetup{device.name(), "reference door", ""});
    summary = playback.run_real_time([](const RenderLoop::Status&) { return true; }, 0.02);
  }
  INFO(summary.brief_report());
  CHECK(summary.final_state == SafetyState::kStopped);
  CHECK(std::find(summary.safety_events.begin(), summary.safety_events.end(), "link_lost") !=
        summary.safety_events.end());
  CHECK(summary.duration_s < 5.0);

  // In the session: from the link_lost event the commanded force falls to zero within the
  // stop ramp (plus one tick) and stays there.
  const SessionReader session(path);
  double lost_at_s = -1.0;
  for (const SessionEvent& event : session.events()) {
    if (event.kind == "safety" && event.detail.rfind("link_lost", 0) == 0) lost_at_s = event.time_s;
  }
  REQUIRE(lost_at_s > 0.0);
  const ChannelSlice x = session.read("commanded_force_x");
  const ChannelSlice y = session.read("commanded_force_y");
  const ChannelSlice z = session.read("commanded_force_z");
  double zero_from_s = -1.0;
  for (std::size_t i = 0; i < x.raw.size(); ++i) {
    const double force = std::sqrt(x.raw[i] * x.raw[i] + y.raw[i] * y.raw[i] + z.raw[i] * z.raw[i]);
    if (force == 0.0 && zero_from_s < 0.0 && x.time_s[i] >= lost_at_s) zero_from_s = x.time_s[i];
    if (zero_from_s >= 0.0) CHECK(force == 0.0);
  }
  REQUIRE(zero_from_s >= 0.0);
  CHECK(zero_from_s - lost_at_s <= options.loop.safety.shutdown_ramp_s + 0.002);
  // Why, word for word: in the summary, the safety event and the session's stop event.
  const std::string why = "link_lost: hapticmaster://127.0.0.1:" + line.substr(5) +
                          ": connection closed by the device; the device was stopped (zero "
                          "force, state stop)";
  CHECK(summary.stop_cause == why);
  CHECK(stop_event_of(session) == why);
  CHECK(safety_event_of(session, "link_lost") == why);
}

namespace {

// The HapticMaster driver behind a tick that is held up once: the `stall_at`-th read() sleeps
// `stall_s`, as a loaded machine can hold up the tick's thread; every call is forwarded.
class TickHeldUpOnce : public HapticDevice {
 public:
  TickHeldUpOnce(HapticDevice& device, int stall_at, double stall_s)
      : device_(device), stall_at_(stall_at), stall_s_(stall_s) {}
  std::string name() const override { return device_.name(); }
  DeviceLimits limits() const override { return device_.limits(); }
  void start(double inertia) override { device_.start(inertia); }
  void stop() noexcept override { device_.stop(); }
  std::string stop_reason() const override { return device_.stop_reason(); }
  double first_command_arrival_s() const noexcept override {
    return device_.first_command_arrival_s();
  }
  DeviceSample read() noexcept override {
    if (++reads_ == stall_at_) {
      std::this_thread::sleep_for(std::chrono::duration<double>(stall_s_));
    }
    return device_.read();
  }
  void command_force(const Vec3& force) noexcept override { device_.command_force(force); }
  void command_inertia(double inertia) noexcept override { device_.command_inertia(inertia); }
  void brake() noexcept override { device_.brake(); }
  bool render_stiff_parts_on_device(const DoorMapping& mapping, double theta_min_rad,
                                    double theta_max_rad) override {
    return device_.render_stiff_parts_on_device(mapping, theta_min_rad, theta_max_rad);
  }

 private:
  HapticDevice& device_;
  int stall_at_;
  double stall_s_;
  int reads_ = 0;
};

}  // namespace

TEST_CASE("haptic chain: a tick held up past the HapticMaster's watchdog ends the run, saying why",
          "[haptic][hapticmaster]") {
  testing::TempDir dir("watchdog_stop");
  testing::HapticMasterEmulator emulator;
  HapticMasterDevice driver(emulator.address());  // command_watchdog_s 0.1 s
  // The 500th tick waits 0.4 s before it reads the device: the driver's watchdog stops the
  // device 0.1 s into it. The safety layer's own stall limit is set above the hold-up, so
  // that the driver's watchdog, not the tick's clock, is what ends the run.
  TickHeldUpOnce device(driver, 500, 0.4);
  PlaybackOptions options;
  options.duration_s = 5.0;
  options.real_time.request_fifo = false;
  options.loop.safety.max_tick_stall_s = 1.0;
  options.loop.safety.max_stale_ticks = 5000;
  const std::filesystem::path path = dir.path / "watchdog.h5";
  PlaybackSummary summary;
  {
    Playback playback(device, reference_model(ModelKind::kSensory), options, path,
                      SessionMetadata{}, PlaybackSetup{device.name(), "reference door", ""});
    summary = playback.run_real_time([](const RenderLoop::Status&) { return true; }, 0.02);
  }
  INFO(summary.brief_report());
  CHECK(summary.duration_s < 2.0);
  const std::string error = driver.last_error();
  // "...: watchdog: the render loop sent no command for 0.101 s (limit 0.1 s); the device was
  // stopped (zero force, state stop)", the silence to the millisecond as the driver saw it.
  const std::regex text(
      "hapticmaster://127\\.0\\.0\\.1:[0-9]+: watchdog: the render loop sent no "
      "command for 0\\.1[0-9]* s \\(limit 0\\.1 s\\); the device was stopped "
      "\\(zero force, state stop\\)");
  CHECK(std::regex_match(error, text));
  const SessionReader session(path);
  CHECK(summary.stop_cause == "link_lost: " + error);
  CHECK(stop_event_of(session) == "link_lost: " + error);
  CHECK(safety_event_of(session, "link_lost") == "link_lost: " + error);
  // The start-up figures: the first tick and its command came after the device's start.
  REQUIRE(summary.startup);
  CHECK(summary.startup->device_start_s > 0.0);
  CHECK(summary.startup->first_tick_after_s > 0.0);
  CHECK(summary.startup->first_command_after_s >= summary.startup->first_tick_after_s);
  CHECK(summary.startup->first_command_after_s < 5.0);
}
