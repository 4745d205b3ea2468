// The whole chain against the HapticMaster protocol emulator (a separate process, see
// docs/hapticmaster.md): the render loop plays the reference door through the driver in real
// time; the emulator drops the connection; the loop must end in a safe stop.
#include <catch2/catch.hpp>
#include <cmath>

#include "analysis/model/parameter_file.h"
#include "haptic/hapticmaster_device.h"
#include "haptic/playback.h"
#include "tests/support/hapticmaster_emulator_process.h"
#include "tests/support/temp_dir.h"

using namespace doorbench;
using namespace doorbench::haptic;

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
  CHECK_THAT(device.last_error(), Catch::Contains("127.0.0.1"));
}
