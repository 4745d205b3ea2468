// The door snapshot the station reads (haptic/door_snapshot.h): events counted from each
// tick's angle, no allocation on the publishing side (alone and inside the render loop's
// tick), and whole snapshots only for a reader on another thread.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <thread>

#include "analysis/model/parameter_file.h"
#include "haptic/door_snapshot.h"
#include "haptic/render_loop.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/busy_processes.h"
#include "tests/support/haptic_test_device.h"

using namespace doorbench;
using namespace doorbench::haptic;

namespace {

// Opens from closed to `top_rad` and back, as a cosine over `period_s`.
double stroke_angle(double time_s, double top_rad, double period_s) {
  return 0.5 * top_rad * (1.0 - std::cos(2.0 * std::acos(-1.0) * time_s / period_s));
}

}  // namespace

TEST_CASE("door snapshot: latch crossings and stop hits are counted once each, without allocating",
          "[haptic][snapshot]") {
  DoorEventAngles angles;
  angles.latch_rad = 0.03;
  angles.open_stop_rad = 1.5;
  DoorSnapshotChannel channel(angles);
  const long long before = testing::allocations();
  // Three strokes from 10 mrad inside the closed stop to just past the open stop at 1 kHz:
  // each unlatches once, hits the open stop once, comes back, latches once and hits the
  // closed stop once (the first tick, at rest, is no hit).
  const double dt = 1e-3, period = 2.0;
  double previous = -0.01;  // at rest at the first tick
  for (int i = 0; i <= 6000; ++i) {
    const double t = i * dt;
    const double theta = stroke_angle(t, 1.52, period) - 0.01;
    channel.publish(t, theta, (theta - previous) / dt);
    previous = theta;
  }
  CHECK(testing::allocations() - before == 0);
  const DoorSnapshot s = channel.read();
  CHECK(s.ticks == 6001);
  CHECK(s.unlatches == 3);
  CHECK(s.latches == 3);
  CHECK(s.open_stop_hits == 3);
  CHECK(s.closed_stop_hits == 3);  // each stroke ends in the closed stop at ~0.45 rad/s
  CHECK(s.time_s == Approx(6.0));
  // The latest latching: where the cosine last fell through 0.03 + hysteresis.
  CHECK(s.last_latch_event_time_s > 5.8);
  CHECK(s.last_latch_event_time_s < 5.95);
}

TEST_CASE("door snapshot: the model's latch angle and stops", "[haptic][snapshot]") {
  const DoorModel sensory = reference_model(ModelKind::kSensory);
  const DoorEventAngles angles = DoorEventAngles::for_model(sensory);
  CHECK(angles.latch_rad == sensory.parameter_values()[*sensory.find_parameter("theta1")]);
  CHECK(angles.open_stop_rad == sensory.geometry().theta_max_rad);
  const DoorModel physical = reference_model(ModelKind::kPhysical);
  const auto v = physical.parameter_values();
  CHECK(DoorEventAngles::for_model(physical).latch_rad ==
        Approx(v[*physical.find_parameter("h")] / v[*physical.find_parameter("r_l")]));
  DoorEventAngles bad;
  bad.open_stop_rad = -1.0;
  CHECK_THROWS_WITH(DoorSnapshotChannel(bad),
                    "door snapshot: open_stop_rad must be finite and above closed_stop_rad");
}

TEST_CASE("door snapshot: a reader on another thread sees only whole snapshots, under load",
          "[haptic][snapshot]") {
  testing::BusyProcesses busy(2);
  DoorSnapshotChannel channel;
  std::atomic<bool> done{false};
  std::atomic<long> torn{0}, reads{0};
  std::thread reader([&] {
    while (!done.load(std::memory_order_acquire)) {
      const DoorSnapshot s = channel.read();
      // The writer keeps θ = t / 1000 and ω = t exactly: a mix of two publishes breaks it.
      if (s.ticks > 1 && (s.theta_rad != s.time_s / 1000.0 || s.omega_rad_s != s.time_s ||
                          s.time_s != double(s.ticks - 1))) {
        torn.fetch_add(1);
      }
      reads.fetch_add(1);
    }
  });
  // At least 2 million publishes, and on until the reader has read 1000 times: on a busy
  // machine the reader may not get a core before the first 2 million are done.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (long i = 0;
       i < 2000000 || (reads.load() < 1000 && std::chrono::steady_clock::now() < give_up); ++i) {
    channel.publish(i, static_cast<double>(i) / 1000.0, static_cast<double>(i));
  }
  done.store(true, std::memory_order_release);
  reader.join();
  CHECK(torn.load() == 0);
  CHECK(reads.load() >= 1000);
}

TEST_CASE("door snapshot: the render loop's tick publishes it and still allocates nothing",
          "[haptic][snapshot]") {
  testing::RotaryTestDevice device;
  device.reference_angle_rad = [](double t) { return stroke_angle(t, 0.6, 1.0); };
  const DoorModel model = reference_model(ModelKind::kSensory);
  const DoorMapping mapping(Kinematics::kRotary1, ArcGeometry{}, model.geometry().handle_radius_m);
  device.start(mapping.inertia_on_device(model.inertia_kg_m2()));
  RenderLoopOptions options;
  options.safety.velocity_trip = 6.0;
  RenderLoop loop(device, mapping, std::make_unique<PlaybackParameters>(model, mapping, "start"),
                  options);
  double time_s = 0.0;
  for (int i = 0; i < 600; ++i, time_s += 1e-3) {
    device.advance_to(time_s);
    loop.tick(time_s);
  }
  const long long before = testing::allocations();
  for (int i = 0; i < 2400; ++i, time_s += 1e-3) {
    device.advance_to(time_s);
    loop.tick(time_s);
  }
  CHECK(testing::allocations() - before == 0);
  const DoorSnapshot s = loop.snapshot().read();
  CHECK(s.ticks == 3000);
  CHECK(s.time_s == Approx(time_s - 1e-3));
  CHECK(s.theta_rad == loop.status().theta_rad);
  // The hand pulled the door open three times through the latch (after the start ramp).
  CHECK(s.unlatches >= 2);
  CHECK(s.latches >= 2);
}
