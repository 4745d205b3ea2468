// The render loop's tick, its parameter hand-off and its recording, on a small rotary test
// device in simulated time (tests/support/haptic_test_device.h).
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "acquisition/session/session_csv.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "analysis/model/sensory_model.h"
#include "fixtures/temp_dir.h"
#include "haptic/playback.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/haptic_test_device.h"

using namespace doorbench;
using namespace doorbench::haptic;

namespace {

// A gentle opening to 0.5 rad and back over 4 s.
double reference_angle(double time_s) {
  if (time_s < 0.5 || time_s > 3.5) return 0.0;
  return 0.25 * (1.0 - std::cos(2.0 * 3.14159265358979 * (time_s - 0.5) / 3.0));
}

// The test device is rotary: its velocity trip is in rad/s (a brisk door swings at 2 rad/s).
RenderLoopOptions rotary_options() {
  RenderLoopOptions options;
  options.safety.velocity_trip = 6.0;
  return options;
}

SessionMetadata metadata() {
  SessionMetadata metadata;
  metadata.rig_name = "test rotary device";
  metadata.start_time_utc = "2026-11-21T00:00:00Z";
  return metadata;
}

// The reference sensory door's render loop on a started rotary test device (unit device
// inertia). Built in place: the loop holds the device and the mapping by reference.
struct ReferenceDoorLoop {
  testing::RotaryTestDevice device;
  const DoorModel model = reference_model(ModelKind::kSensory);
  const DoorMapping mapping{Kinematics::kRotary1, ArcGeometry{}, model.geometry().handle_radius_m};
  RenderLoop loop{started(device), mapping,
                  std::make_unique<PlaybackParameters>(model, mapping, "start"), rotary_options()};

  static testing::RotaryTestDevice& started(testing::RotaryTestDevice& device) {
    device.start(1.0);
    return device;
  }
};

}  // namespace

TEST_CASE("render loop: a tick allocates nothing and a parameter change lands at the next tick",
          "[haptic][loop]") {
  testing::RotaryTestDevice device;
  device.reference_angle_rad = reference_angle;
  const DoorModel model = reference_model(ModelKind::kSensory);
  const DoorMapping mapping(Kinematics::kRotary1, ArcGeometry{}, model.geometry().handle_radius_m);
  device.start(mapping.inertia_on_device(model.inertia_kg_m2()));
  RenderLoop loop(device, mapping, std::make_unique<PlaybackParameters>(model, mapping, "start"),
                  rotary_options());
  CHECK(loop.mailbox().in_use() == 1);

  // Warm up past the start ramp, then count allocations over many ticks.
  double time_s = 0.0;
  for (int i = 0; i < 600; ++i, time_s += 1e-3) {
    device.advance_to(time_s);
    loop.tick(time_s);
  }
  const long long before = testing::allocations();
  for (int i = 0; i < 2000; ++i, time_s += 1e-3) {
    device.advance_to(time_s);
    loop.tick(time_s);
  }
  CHECK(testing::allocations() - before == 0);

  // A heavier door: published on the control side, taken whole at the next tick.
  const DoorModel heavier = perceptual::set(model, perceptual::Control::kHeaviness, 1.5);
  int id = 0;
  REQUIRE(loop.publish(std::make_unique<PlaybackParameters>(heavier, mapping, "heavier"), &id) ==
          "");
  CHECK(id == 2);
  CHECK(loop.mailbox().in_use() == 1);
  CHECK(device.inertia_commands == 0);
  device.advance_to(time_s);
  loop.tick(time_s);
  CHECK(loop.mailbox().in_use() == 2);
  CHECK(device.inertia_commands == 1);
  CHECK(device.inertia() == Approx(1.5));
  CHECK(loop.counters().parameter_changes == 1);

  // Every tick was recorded, each with the set it used.
  std::size_t records = 0;
  int last_set = 0;
  while (const TickRecord* record = loop.records().consumer_slot()) {
    last_set = record->parameter_set;
    ++records;
    loop.records().release();
  }
  CHECK(records == 2601);
  CHECK(last_set == 2);
  CHECK(loop.counters().records_dropped == 0);
}

TEST_CASE("render loop: a velocity trip brakes the device in the same tick, a stop ends braked",
          "[haptic][loop][failsafe]") {
  const DoorModel model = reference_model(ModelKind::kSensory);
  const DoorMapping mapping(Kinematics::kRotary1, ArcGeometry{}, model.geometry().handle_radius_m);
  SECTION("velocity trip") {
    testing::RotaryTestDevice device;
    device.reference_angle_rad = reference_angle;  // peaks near 0.26 rad/s
    device.start(mapping.inertia_on_device(model.inertia_kg_m2()));
    RenderLoopOptions options = rotary_options();
    options.safety.velocity_trip = 0.1;  // rad/s: the gentle opening trips it
    RenderLoop loop(device, mapping, std::make_unique<PlaybackParameters>(model, mapping, "start"),
                    options);
    double time_s = 0.0;
    int trip_tick = -1;
    for (int i = 0; i < 4000 && trip_tick < 0; ++i, time_s += 1e-3) {
      device.advance_to(time_s);
      loop.tick(time_s);
      while (const TickRecord* record = loop.records().consumer_slot()) {
        if (record->events & kEventVelocityTrip) trip_tick = i;
        loop.records().release();
      }
      if (trip_tick < 0) CHECK(device.brake_calls == 0);
    }
    REQUIRE(trip_tick > 0);
    CHECK(device.brake_calls == 1);  // in the trip's own tick, not after the 20 ms ramp
    // The ramp down and the stop that follow do not brake again.
    for (int i = 0; i < 100; ++i, time_s += 1e-3) {
      device.advance_to(time_s);
      loop.tick(time_s);
    }
    CHECK(loop.stopped());
    CHECK(device.brake_calls == 1);
  }
  SECTION("a requested stop ends braked") {
    testing::RotaryTestDevice device;
    device.start(mapping.inertia_on_device(model.inertia_kg_m2()));
    RenderLoop loop(device, mapping, std::make_unique<PlaybackParameters>(model, mapping, "start"),
                    rotary_options());
    double time_s = 0.0;
    for (int i = 0; i < 700; ++i, time_s += 1e-3) {
      device.advance_to(time_s);
      loop.tick(time_s);
    }
    CHECK(device.brake_calls == 0);
    loop.request_stop();
    for (int i = 0; i < 100 && !loop.stopped(); ++i, time_s += 1e-3) {
      device.advance_to(time_s);
      loop.tick(time_s);
    }
    CHECK(loop.stopped());
    CHECK(device.brake_calls == 1);
  }
}

TEST_CASE("render loop: the model's torque is what the device gets, and the hand feels the door",
          "[haptic][loop]") {
  ReferenceDoorLoop rig;
  auto& [device, model, mapping, loop] = rig;
  // Held at 0.3 rad (free movement) after the start ramp: the command is the model's torque.
  device.reference_angle_rad = [](double) { return 0.3; };
  double time_s = 0.0;
  for (int i = 0; i < 3000; ++i, time_s += 1e-3) {
    device.advance_to(time_s);
    loop.tick(time_s);
  }
  const RenderLoop::Status status = loop.status();
  const double expected = model.torque_Nm(status.theta_rad, status.omega_rad_s);
  CHECK(device.command() == Approx(expected).margin(1e-9));
  CHECK(status.theta_rad == Approx(0.3).margin(0.05));
}

TEST_CASE("render loop: refuses a parameter set it cannot play, naming the reason",
          "[haptic][loop]") {
  ReferenceDoorLoop rig;
  auto& [device, model, mapping, loop] = rig;
  // J = 20 kg*m^2 is beyond what this device renders (max 10).
  const DoorModel too_heavy = perceptual::set(model, perceptual::Control::kHeaviness, 4.9);
  CHECK(loop.publish(std::make_unique<PlaybackParameters>(too_heavy, mapping, "x")) == "");
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  values[sensory::kJ] = 20.0;
  auto bounds =
      std::vector<Bounds>(model.parameter_bounds().begin(), model.parameter_bounds().end());
  bounds[sensory::kJ] = {0.1, 50.0};
  const DoorModel heavy(ModelKind::kSensory, model.geometry(), values, bounds);
  CHECK_THAT(loop.publish(std::make_unique<PlaybackParameters>(heavy, mapping, "y")),
             Catch::Contains("needs 20 kg on the device, outside its range [0.01, 10] kg"));

  RenderLoopOptions fast = rotary_options();
  fast.rate_hz = 5000.0;
  CHECK_THROWS_WITH(RenderLoop(device, mapping,
                               std::make_unique<PlaybackParameters>(model, mapping, "start"), fast),
                    "render loop: rate_hz must be in [100, 4000] Hz (got 5000)");
}

TEST_CASE("playback: ticks, parameter changes and events stream into a session a fit can read",
          "[haptic][loop][session]") {
  testing::TempDir dir("playback");
  testing::RotaryTestDevice device;
  device.reference_angle_rad = reference_angle;
  const DoorModel model = reference_model(ModelKind::kSensory);
  PlaybackOptions options;
  options.loop = rotary_options();
  options.duration_s = 4.0;
  const std::filesystem::path path = dir.path / "played.h5";
  PlaybackSummary summary;
  bool started_in_run = false;
  {
    Playback playback(device, model, options, path, metadata(),
                      PlaybackSetup{"test:rotary", "reference door", ""});
    // The device starts with the run, just before its first tick, not when the playback is
    // built (the session file and the loop come first).
    CHECK_FALSE(device.started);
    bool changed = false;
    summary = playback.run_simulated(
        [&](double t) {
          started_in_run = started_in_run || device.started;
          device.advance_to(t);
        },
        [&](double t) {
          if (!changed && t >= 2.0) {
            const DoorModel lighter =
                perceptual::set(playback.current_model(), perceptual::Control::kSmoothness, 3.0);
            CHECK(playback.change_parameters(lighter, "smoother") == "");
            changed = true;
          }
        });
  }
  CHECK(started_in_run);
  CHECK(device.stopped);
  CHECK(summary.ticks >= 4000);
  CHECK(summary.parameter_changes == 1);
  CHECK(summary.records_dropped == 0);

  const SessionReader session(path);
  CHECK(session.sample_count("force") == summary.ticks);
  CHECK(session.sample_count("term_snap") == summary.ticks);
  // A value whose range nobody knows is stored as ±inf (session-format.md), not ±1e300.
  for (const ChannelInfo& channel : session.channels()) {
    INFO(channel.name);
    CHECK(channel.range_min == -std::numeric_limits<double>::infinity());
    CHECK(channel.range_max == std::numeric_limits<double>::infinity());
  }
  // The shortest text that reads back as the same double (core/number_format.h).
  CHECK(session.read_group_attribute("haptic", "handle_radius_m") == "0.58");
  CHECK(std::stod(session.read_group_attribute("haptic", "handle_radius_m")) == 0.58);
  CHECK_THAT(session.read_group_attribute("haptic/parameter_sets/set_2", "description"),
             Catch::Equals("smoother"));
  int parameter_events = 0;
  double change_time_s = 0.0;
  for (const SessionEvent& event : session.events()) {
    if (event.kind == "parameters") {
      ++parameter_events;
      if (event.detail == "set 2: smoother") change_time_s = event.time_s;
    }
  }
  CHECK(parameter_events == 2);
  CHECK(change_time_s == Approx(2.001).margin(1e-9));
  // The channel layout is the bench's: the export gives force, angle and rate columns.
  const Recording recording = session_to_recording(session);
  CHECK(recording.force_N.size() == summary.ticks);
  REQUIRE(recording.handle_radius_m);
  CHECK(*recording.handle_radius_m == Approx(0.58));
  REQUIRE(recording.angle_rad);
  CHECK(recording.angle_rad->size() == summary.ticks);
  REQUIRE(recording.rate_rad_s);
  CHECK(recording.rate_rad_s->size() == summary.ticks);
}
