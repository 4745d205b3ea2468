// Stiff parts on the device against a slow link: the reference door played through the
// HapticMaster driver on the protocol emulator with injected round-trip latency, the arc
// constraint and the end stops rendered by the host (streamed as bias force) or by the
// device's own springs (docs/hapticmaster.md, "Stiff parts on the device"). A steady push of
// the user's hand across the arc shows how each holds. Real time, a few seconds per case.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <sstream>

#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "fixtures/temp_dir.h"
#include "haptic/hapticmaster_device.h"
#include "haptic/playback.h"
#include "tests/support/hapticmaster_emulator_process.h"

using namespace doorbench;
using namespace doorbench::haptic;

namespace {

struct Held {
  PlaybackSummary summary;
  double max_axial_m = 0.0, max_radial_m = 0.0;      // from 1.5 s to the stop
  double axial_swing_m = 0.0, radial_swing_m = 0.0;  // peak to peak, the same span
};

Held play_with_latency(double latency_ms, bool on_device, const std::string& push,
                       double duration_s, double heaviness = 1.0) {
  testing::TempDir dir("hm_latency");
  testing::HapticMasterEmulator emulator(
      {"--latency-ms", std::to_string(latency_ms), "--jitter-ms", "0.5", "--ext-force", push});
  HapticMasterOptions driver;
  driver.reply_timeout_s = 0.5;
  HapticMasterDevice device(emulator.address(), driver);
  const DoorModel model = perceptual::set(reference_model(ModelKind::kSensory),
                                          perceptual::Control::kHeaviness, heaviness);
  PlaybackOptions options;
  options.duration_s = duration_s;
  options.stiff_parts_on_device = on_device;
  // This test is about the rendering: a loaded machine's late ticks must not end it.
  options.loop.safety.max_tick_stall_s = 1.0;
  options.loop.safety.max_stale_ticks = 5000;
  const auto path = dir.path / "latency.h5";
  SessionMetadata metadata;
  metadata.rig_name = "HapticMaster emulator, latency";
  Held held;
  {
    Playback playback(device, model, options, path, metadata,
                      PlaybackSetup{device.name(), "reference door", ""});
    held.summary = playback.run_real_time([](const RenderLoop::Status&) { return true; }, 0.05);
  }
  const SessionReader session(path);
  const ChannelSlice axial = session.read("axial_error");
  const ChannelSlice radial = session.read("radial_error");
  const double end_s = axial.time_s.empty() ? 0.0 : axial.time_s.back();
  double a_lo = 1e9, a_hi = -1e9, r_lo = 1e9, r_hi = -1e9;
  for (std::size_t i = 0; i < axial.raw.size(); ++i) {
    // After the start (the end-effector pulled onto the arc) and before the stop's ramp.
    if (axial.time_s[i] < 1.5 || axial.time_s[i] > end_s - 0.2) continue;
    a_lo = std::min(a_lo, axial.raw[i]);
    a_hi = std::max(a_hi, axial.raw[i]);
    r_lo = std::min(r_lo, radial.raw[i]);
    r_hi = std::max(r_hi, radial.raw[i]);
    held.max_axial_m = std::max(held.max_axial_m, std::abs(axial.raw[i]));
    held.max_radial_m = std::max(held.max_radial_m, std::abs(radial.raw[i]));
  }
  held.axial_swing_m = a_hi - a_lo;
  held.radial_swing_m = r_hi - r_lo;
  return held;
}

}  // namespace

std::string describe(const Held& h) {
  std::ostringstream out;
  out << "axial " << h.max_axial_m * 1e3 << " mm (swing " << h.axial_swing_m * 1e3
      << " mm), radial " << h.max_radial_m * 1e3 << " mm (swing " << h.radial_swing_m * 1e3
      << " mm) from 1.5 s to the stop; " << h.summary.brief_report();
  return out.str();
}

TEST_CASE(
    "hapticmaster latency: device-side stiff parts hold the arc at 3 and 20 ms round "
    "trips, the host-side constraint rings at 20 ms",
    "[hapticmaster][latency]") {
  // The user pushes 10 N along the hinge axis and 5 N outward from it, steadily: the springs'
  // 8000 N/m give 1.25 mm and 0.63 mm when the arc is held (docs/hapticmaster.md).
  const std::string push = "[0,10,5]";
  for (const double latency_ms : {3.0, 20.0}) {
    const Held held = play_with_latency(latency_ms, true, push, 3.0);
    INFO(latency_ms << " ms, device-side: " << describe(held));
    CHECK(held.summary.constraint_on_device);
    CHECK(held.max_axial_m == Approx(1.25e-3).margin(0.2e-3));
    CHECK(held.max_radial_m == Approx(0.63e-3).margin(0.2e-3));
    CHECK(held.axial_swing_m < 0.05e-3);
    CHECK(held.radial_swing_m < 0.05e-3);
  }
  // Host-side, 3 ms: holds too on this door (10.9 kg on the device; measured, see the docs).
  const Held host_3 = play_with_latency(3.0, false, push, 3.0);
  INFO("3 ms, host-side: " << describe(host_3));
  CHECK_FALSE(host_3.summary.constraint_on_device);
  CHECK(host_3.max_axial_m == Approx(1.25e-3).margin(0.2e-3));
  // Host-side, 20 ms: the constraint streamed as bias force rings and runs away (until the
  // safety layer trips on the speed or the workspace, if it gets there first).
  const Held host_20 = play_with_latency(20.0, false, push, 3.0);
  INFO("20 ms, host-side: " << describe(host_20));
  const auto& events = host_20.summary.safety_events;
  const bool tripped = std::find(events.begin(), events.end(), "velocity_trip") != events.end() ||
                       std::find(events.begin(), events.end(), "workspace_trip") != events.end();
  CHECK((host_20.axial_swing_m > 10e-3 || host_20.radial_swing_m > 10e-3 || tripped));
}

TEST_CASE(
    "hapticmaster fail-safe: a velocity trip in playback brakes the device before the "
    "shutdown",
    "[hapticmaster][failsafe]") {
  testing::TempDir dir("hm_velocity_trip");
  const auto events = dir.path / "events.log";
  // The user pushes the door open along the arc's tangent at the closed end (+x) hard enough
  // to pass 0.05 m/s within a fraction of a second.
  testing::HapticMasterEmulator emulator({"--events", events.string(), "--ext-force", "[25,0,0]"});
  HapticMasterDevice device(emulator.address());
  const DoorModel model = reference_model(ModelKind::kSensory);
  PlaybackOptions options;
  options.duration_s = 5.0;
  options.loop.safety.velocity_trip = 0.05;  // m/s
  options.loop.safety.max_tick_stall_s = 1.0;
  options.loop.safety.max_stale_ticks = 5000;
  SessionMetadata metadata;
  metadata.rig_name = "HapticMaster emulator";
  PlaybackSummary summary;
  {
    Playback playback(device, model, options, dir.path / "trip.h5", metadata,
                      PlaybackSetup{device.name(), "reference door", ""});
    summary = playback.run_real_time([](const RenderLoop::Status&) { return true; }, 0.02);
  }
  INFO(summary.brief_report());
  const auto& names = summary.safety_events;
  REQUIRE(std::find(names.begin(), names.end(), "velocity_trip") != names.end());
  CHECK(summary.duration_s < 4.0);
  // In the device's own log: zero force and state stop came first from the brake (a "set
  // state stop" of its own), and only later from the shutdown, which then removes the
  // objects; nothing brought the force state back in between.
  std::ifstream in(events);
  double stopped_s = -1.0, removed_s = -1.0;
  int stop_commands = 0;
  bool force_after_stop = false;
  for (std::string line; std::getline(in, line);) {
    const double t = std::stod(line);
    const std::string text = line.substr(line.find(' ') + 1);
    if (stopped_s < 0 && text == "device state=stop bias=0.0") stopped_s = t;
    if (removed_s < 0 && text == "cmd remove doorbench_bias") removed_s = t;
    if (text == "cmd set state stop") ++stop_commands;
    if (stopped_s >= 0 && text.rfind("device state=force", 0) == 0) force_after_stop = true;
  }
  REQUIRE(stopped_s > 0.0);
  REQUIRE(removed_s > 0.0);
  CHECK(stop_commands == 2);  // the brake's, then the shutdown's
  CHECK_FALSE(force_after_stop);
  CHECK(device.last_error() == "");
}
