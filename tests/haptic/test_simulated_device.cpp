// The simulated HapticMaster and the simulated rotary device (haptic/simulated_hapticmaster.h,
// haptic/rotary_device.h): their dynamics, delay, noise, walls, the virtual hand,
// determinism, misbehaviour, allocation-free real-time calls, and a closed loop with the
// reference door and the arc constraint under the hand's pushes.
#include <time.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "analysis/model/parameter_file.h"
#include "haptic/door_mapping.h"
#include "haptic/parameter_mailbox.h"
#include "haptic/rotary_device.h"
#include "haptic/simulated_hapticmaster.h"
#include "tests/support/allocation_counter.h"

using namespace doorbench;
using namespace doorbench::haptic;

namespace {

SimulatedHapticMasterOptions quiet_options() {
  SimulatedHapticMasterOptions options;
  options.device.force_noise_rms = 0.0;
  return options;
}

double distance_from_arc(const DoorMapping& mapping, const Vec3& position) {
  DeviceSample sample;
  sample.position = position;
  const DoorPoint point = mapping.to_door(sample);
  return std::hypot(point.radial_error_m, point.axial_error_m);
}

void sleep_s(double seconds) {
  timespec pause{0, static_cast<long>(seconds * 1e9)};
  nanosleep(&pause, nullptr);
}

const DoorMapping& reference_mapping() {
  static const DoorMapping mapping(Kinematics::kCartesian3, ArcGeometry{}, 0.58);
  return mapping;
}

}  // namespace

TEST_CASE("sim hapticmaster: a constant force accelerates the mass F/m after the control delay",
          "[haptic][sim]") {
  SimulatedHapticMasterOptions options = quiet_options();
  options.device.control_delay_s = GENERATE(0.001, 0.002);
  SimulatedHapticMaster device(options);
  const double mass_kg = 5.0;
  device.start(mass_kg);
  const Vec3 force(10.0, -4.0, 2.0);
  device.command_force(force);
  const double dt = 1.0 / options.device.servo_rate_hz;
  // Step by step: the end-effector does not move until the delay has passed, and moves
  // within two servo steps after it.
  double first_moving_s = -1.0;
  for (int i = 1; i <= 20; ++i) {
    device.advance_to(i * dt);
    const DeviceSample sample = device.read();
    REQUIRE(sample.time_s == Approx(i * dt));
    if (first_moving_s < 0.0 && sample.velocity.norm() > 0.0) first_moving_s = sample.time_s;
  }
  INFO("first moving sample at " << first_moving_s);
  CHECK(first_moving_s > options.device.control_delay_s);
  CHECK(first_moving_s <= options.device.control_delay_s + 2.0 * dt + 1e-9);

  device.advance_to(0.05);
  const DeviceSample early = device.read();
  device.advance_to(0.15);
  const DeviceSample late = device.read();
  const Vec3 acceleration = (late.velocity - early.velocity) / (late.time_s - early.time_s);
  CHECK((acceleration - force / mass_kg).norm() < 1e-9);
  CHECK(device.truth().applied_command.isApprox(force));
  CHECK(device.truth().inertia == mass_kg);
}

TEST_CASE("sim hapticmaster: command_inertia changes the mass after the delay and is clamped",
          "[haptic][sim]") {
  SimulatedHapticMaster device(quiet_options());
  device.start(4.0);
  device.command_force(Vec3(8.0, 0.0, 0.0));
  device.command_inertia(8.0);
  device.advance_to(0.1);
  const DeviceSample a = device.read();
  device.advance_to(0.2);
  const DeviceSample b = device.read();
  CHECK((b.velocity.x() - a.velocity.x()) / 0.1 == Approx(1.0).epsilon(1e-9));
  device.command_inertia(1000.0);  // above max_inertia: clamped
  device.advance_to(0.3);
  CHECK(device.truth().inertia == 50.0);
  device.command_inertia(0.001);
  device.advance_to(0.4);
  CHECK(device.truth().inertia == 2.0);
}

TEST_CASE("sim hapticmaster: the force sensor's noise has the rms set", "[haptic][sim]") {
  SimulatedHapticMasterOptions options;
  options.device.force_noise_rms = 0.3;
  options.device.seed = 7;
  SimulatedHapticMaster device(options);
  device.start(50.0);
  const double dt = 1.0 / options.device.servo_rate_hz;
  Vec3 sum = Vec3::Zero(), sum_squares = Vec3::Zero();
  const int n = 20000;
  for (int i = 1; i <= n; ++i) {
    device.advance_to(i * dt);
    const Vec3 f = device.read().measured_force;
    sum += f;
    sum_squares += f.cwiseProduct(f);
  }
  for (int axis = 0; axis < 3; ++axis) {
    CHECK(std::abs(sum[axis] / n) < 0.02);
    CHECK(std::sqrt(sum_squares[axis] / n) == Approx(0.3).epsilon(0.03));
  }
}

TEST_CASE("sim hapticmaster: the workspace wall stops the end-effector", "[haptic][sim]") {
  SimulatedHapticMasterOptions options = quiet_options();
  SimulatedHapticMaster device(options);
  device.start(5.0);
  device.command_force(Vec3(50.0, 0.0, -30.0));
  device.advance_to(3.0);
  const DeviceSample sample = device.read();
  // Held at the box's faces by the wall springs: 50 N / 20000 N/m = 2.5 mm in.
  CHECK(sample.position.x() == Approx(0.2 + 50.0 / 20000.0).margin(1e-4));
  CHECK(sample.position.z() == Approx(-0.2 - 30.0 / 20000.0).margin(1e-4));
  CHECK(sample.velocity.norm() < 1e-3);
  CHECK(device.truth().wall_force.isApprox(Vec3(-50.0, 0.0, 30.0), 1e-3));
}

TEST_CASE("sim hapticmaster: the device clamps the command to its max force", "[haptic][sim]") {
  SimulatedHapticMaster device(quiet_options());
  device.start(10.0);
  device.command_force(Vec3(300.0, 400.0, 0.0));
  device.advance_to(0.01);
  CHECK(device.truth().applied_command.norm() == Approx(100.0));
  CHECK(device.truth().applied_command.normalized().isApprox(Vec3(0.6, 0.8, 0.0)));
}

TEST_CASE("sim hapticmaster: start checks the inertia and options name the field",
          "[haptic][sim]") {
  SimulatedHapticMaster device;
  CHECK(device.name() == "sim:hapticmaster");
  CHECK_THROWS_WITH(
      device.start(0.5),
      Catch::Contains("sim:hapticmaster: inertia 0.5 outside what it renders [2, 50]"));
  SimulatedHapticMasterOptions options;
  options.device.control_delay_s = -1.0;
  CHECK_THROWS_WITH(SimulatedHapticMaster(options),
                    "sim:hapticmaster: control_delay_s must be in [0, 0.1]");
  options = {};
  options.initial_position = Vec3(0.5, 0.0, 0.0);
  CHECK_THROWS_WITH(SimulatedHapticMaster(options),
                    "sim:hapticmaster: initial_position must be inside the workspace");
  SimulatedHandOptions hand;
  hand.pushes.rate_hz = 1.0;
  hand.pushes.radial = hand.pushes.axial = hand.pushes.tangential = false;
  CHECK_THROWS_WITH(device.set_hand(hand, reference_mapping()),
                    "sim:hapticmaster hand: pushes need at least one of radial, axial, tangential");
}

TEST_CASE("sim hapticmaster: the default arc fits in the workspace with a margin",
          "[haptic][sim]") {
  SimulatedHapticMaster device;
  CHECK(reference_mapping().check_workspace(device.limits(), -0.05, 1.62, 0.05) == "");
  // The initial position is the arc's θ = 0.
  CHECK((device.truth().position - reference_mapping().point_at(0.0)).norm() < 1e-12);
}

TEST_CASE("sim hapticmaster: the virtual hand drives the end-effector along the arc to its target",
          "[haptic][sim]") {
  SimulatedHapticMaster device;
  SimulatedHandOptions hand;
  hand.lateral_grip_fraction = 1.0;  // no constraint here: the hand alone keeps to the arc
  device.set_hand(hand, reference_mapping());
  device.start(reference_mapping().inertia_on_device(0.95));
  double max_off_arc_m = 0.0;
  const double opening_end_s =
      (hand.hand.rest_fraction + hand.hand.opening_fraction) * hand.hand.duration_s;
  for (int tick = 1; tick * 0.001 <= opening_end_s + 0.5; ++tick) {
    device.advance_to(tick * 0.001);
    max_off_arc_m =
        std::max(max_off_arc_m, distance_from_arc(reference_mapping(), device.read().position));
  }
  const DoorPoint point = reference_mapping().to_door(device.read());
  CHECK(point.theta_rad == Approx(hand.hand.target_angle_rad).margin(0.01));
  CHECK(std::abs(point.omega_rad_s) < 0.02);
  CHECK(max_off_arc_m < 0.002);
  // The sensor measures the hand (the grip's force, noise aside).
  CHECK((device.read().measured_force - device.truth().user_force).norm() < 1.0);
  CHECK(device.truth().hand_grip == 1.0);
}

TEST_CASE("sim hapticmaster: a scripted external force is measured and moves the free device",
          "[haptic][sim]") {
  SimulatedHapticMaster device(quiet_options());
  device.set_external_force([](double t, const Vec3&, const Vec3&) {
    return t < 0.5 ? Vec3(0.0, 6.0, 0.0) : Vec3::Zero();
  });
  device.start(3.0);
  device.advance_to(0.2);
  const DeviceSample a = device.read();
  CHECK(a.measured_force.isApprox(Vec3(0.0, 6.0, 0.0)));
  device.advance_to(0.4);
  const DeviceSample b = device.read();
  CHECK((b.velocity.y() - a.velocity.y()) / 0.2 == Approx(2.0).epsilon(1e-9));
  device.advance_to(0.8);  // let go: it coasts (no friction by default)
  const DeviceSample c = device.read();
  CHECK(c.measured_force.isZero());
  device.advance_to(1.0);
  CHECK(device.read().velocity.y() == Approx(c.velocity.y()).epsilon(1e-12));
  CHECK(device.truth().hand_force.isZero());
}

TEST_CASE("sim hapticmaster: pushes go in the enabled directions", "[haptic][sim]") {
  const DoorMapping& mapping = reference_mapping();
  PushOptions pushes;
  pushes.rate_hz = 5.0;
  pushes.amplitude_N = 20.0;
  pushes.radial = GENERATE(true, false);
  pushes.axial = !pushes.radial;
  SimulatedHapticMasterOptions options = quiet_options();
  options.initial_position = mapping.point_at(0.7);
  SimulatedHapticMaster device(options);
  device.set_pushes(pushes, mapping);
  device.start(20.0);
  const Vec3 radial = (options.initial_position - mapping.geometry().hinge_point_m).normalized();
  const Vec3 axis = mapping.geometry().hinge_axis;
  double largest_push = 0.0;
  for (int tick = 1; tick <= 3000; ++tick) {
    device.advance_to(tick * 0.001);
    const Vec3 push = device.truth().push_force;
    largest_push = std::max(largest_push, push.norm());
    const Vec3 expected = pushes.radial ? radial : axis;
    REQUIRE((push - push.dot(expected) * expected).norm() < 1e-6 * (1.0 + push.norm()) + 0.02);
    device.command_force(Vec3::Zero());
  }
  CHECK(device.truth().pushes >= 5);
  CHECK(largest_push == Approx(20.0).margin(0.5));
  CHECK(device.truth().hand_force.isZero());
}

TEST_CASE("sim hapticmaster: stop() drops the commanded force", "[haptic][sim]") {
  SimulatedHapticMaster device(quiet_options());
  device.start(5.0);
  device.command_force(Vec3(5.0, 0.0, 0.0));
  device.advance_to(0.1);
  CHECK(device.truth().applied_command.x() == 5.0);
  device.stop();
  device.stop();                              // twice is fine
  device.command_force(Vec3(5.0, 0.0, 0.0));  // ignored when stopped
  device.advance_to(0.2);
  CHECK(device.truth().applied_command.isZero());
  const double rate = device.truth().velocity.x();
  device.advance_to(0.3);
  CHECK(device.truth().velocity.x() == rate);  // coasting, no force
}

TEST_CASE("sim hapticmaster: the same seed gives the same run, another seed another",
          "[haptic][sim]") {
  auto run = [](std::uint64_t seed) {
    SimulatedHapticMasterOptions options;
    options.device.seed = seed;
    SimulatedHapticMaster device(options);
    SimulatedHandOptions hand;
    hand.pushes.rate_hz = 5.0;
    device.set_hand(hand, reference_mapping());
    device.start(10.0);
    std::vector<double> trace;
    for (int tick = 1; tick <= 3000; ++tick) {
      device.advance_to(tick * 0.001);
      const DeviceSample sample = device.read();
      device.command_force(reference_mapping().constraint_force(sample));
      trace.push_back(sample.position.x());
      trace.push_back(sample.measured_force.y());
    }
    return std::make_pair(trace, device.truth().pushes);
  };
  const auto a = run(11), b = run(11), c = run(12);
  CHECK(a.first == b.first);
  CHECK(a.second == b.second);
  CHECK(a.second > 5);
  CHECK(a.first != c.first);
}

TEST_CASE("sim hapticmaster: a stall repeats the sample and drops commands", "[haptic][sim]") {
  SimulatedHapticMaster device(quiet_options());
  device.start(5.0);
  device.advance_to(0.01);
  const DeviceSample before = device.read();
  device.set_stalled(true);
  device.command_force(Vec3(10.0, 0.0, 0.0));
  device.advance_to(0.02);
  const DeviceSample stalled = device.read();
  CHECK(stalled.sequence == before.sequence);
  CHECK(stalled.time_s == before.time_s);
  CHECK(stalled.link_ok);
  CHECK(device.truth().dropped_commands == 1);
  CHECK(device.truth().applied_command.isZero());
  device.set_stalled(false);
  device.advance_to(0.03);
  CHECK(device.read().sequence > before.sequence);

  SECTION("for a time window") {
    device.stall_between(0.05, 0.08);
    device.advance_to(0.049);
    const std::uint64_t last = device.read().sequence;
    std::uint64_t in_window = 0;
    for (double t = 0.05; t < 0.0795; t += 0.001) {
      device.advance_to(t);
      const DeviceSample sample = device.read();
      if (in_window == 0) in_window = sample.sequence;
      CHECK(sample.sequence == in_window);
    }
    CHECK(in_window >= last);
    device.advance_to(0.081);
    CHECK(device.read().sequence > in_window);
  }
}

TEST_CASE("sim hapticmaster: a lost link says so and the device drops its force", "[haptic][sim]") {
  SimulatedHapticMaster device(quiet_options());
  device.start(5.0);
  device.command_force(Vec3(0.0, 5.0, 0.0));
  device.lose_link_at(0.02);
  device.advance_to(0.019);
  const DeviceSample before = device.read();
  CHECK(before.link_ok);
  CHECK(device.truth().applied_command.y() == 5.0);
  device.advance_to(0.03);
  const DeviceSample after = device.read();
  CHECK_FALSE(after.link_ok);
  CHECK(after.sequence == before.sequence);
  CHECK(device.truth().applied_command.isZero());
  device.start(5.0);  // a new run clears it
  CHECK(device.read().link_ok);
}

TEST_CASE("sim hapticmaster: the real-time clock follows CLOCK_MONOTONIC with a work cap",
          "[haptic][sim]") {
  SimulatedHapticMasterOptions options = quiet_options();
  options.device.clock = SimClock::kRealTime;
  SimulatedHapticMaster device(options);
  device.start(5.0);
  // The clock begins at the first read, however long after start() it comes: the virtual
  // user starts with the render loop.
  sleep_s(0.2);
  const DeviceSample first = device.read();
  CHECK(device.truth().steps == 0);
  CHECK(device.truth().skipped_steps == 0);
  CHECK(first.time_s > monotonic_now_s() - 0.05);
  sleep_s(0.02);
  const DeviceSample sample = device.read();
  CHECK(sample.time_s <= monotonic_now_s());
  CHECK(sample.time_s > monotonic_now_s() - 0.005);
  CHECK(device.truth().steps >= 40);
  CHECK(device.truth().skipped_steps == 0);

  options.device.max_steps_per_read = 10;
  SimulatedHapticMaster capped(options);
  capped.start(5.0);
  capped.read();
  sleep_s(0.02);
  capped.read();
  CHECK(capped.truth().steps == 10);
  CHECK(capped.truth().skipped_steps >= 35);
  CHECK(capped.read().time_s > monotonic_now_s() - 0.005);
}

TEST_CASE("sim devices: read, command_force, command_inertia and advance_to never allocate",
          "[haptic][sim][allocation]") {
  SimulatedHandOptions hand;
  hand.pushes.rate_hz = 20.0;
  SimulatedHapticMaster manual;
  manual.set_hand(hand, reference_mapping());
  manual.set_external_force(
      [](double t, const Vec3&, const Vec3&) { return Vec3(std::sin(t), 0, 0); });
  manual.start(10.0);
  SimulatedHapticMasterOptions realtime_options;
  realtime_options.device.clock = SimClock::kRealTime;
  SimulatedHapticMaster realtime(realtime_options);
  realtime.set_hand(hand, reference_mapping());
  realtime.start(10.0);
  SimulatedRotaryDevice rotary;
  RotaryHandOptions rotary_hand;
  rotary_hand.pushes.rate_hz = 20.0;
  rotary.set_hand(rotary_hand);
  rotary.start(0.95);

  const long long before = doorbench::testing::allocations();
  double sum = 0.0;
  for (int tick = 1; tick <= 2000; ++tick) {
    manual.advance_to(tick * 0.001);
    rotary.advance_to(tick * 0.001);
    const DeviceSample a = manual.read();
    const DeviceSample b = realtime.read();
    const DeviceSample c = rotary.read();
    manual.command_force(reference_mapping().to_device(1.0, a));
    realtime.command_force(reference_mapping().to_device(1.0, b));
    rotary.command_force(Vec3(-0.5, 0.0, 0.0));
    if (tick % 100 == 0) {
      manual.command_inertia(12.0);
      realtime.command_inertia(12.0);
      rotary.command_inertia(1.0);
    }
    sum += a.position.x() + b.position.x() + c.position.x() + manual.truth().hand_force.x();
  }
  CHECK(doorbench::testing::allocations() == before);
  CHECK(std::isfinite(sum));
  CHECK(manual.truth().pushes > 10);
}

// The local closed loop the issue asks for, without the render loop: read -> to_door ->
// model torque -> to_device -> command_force at 1 kHz in manual time.
namespace {

struct LoopResult {
  double max_off_arc_m = 0.0;
  double theta_at_opening_end_rad = 0.0;
  double max_theta_rad = -1.0;
  double min_theta_after_close_rad = 10.0;
  std::uint64_t pushes = 0;
};

LoopResult run_closed_loop(const ArcGeometry& geometry, double push_amplitude_N,
                           double push_rate_hz, std::uint64_t seed,
                           ModelKind kind = ModelKind::kSensory) {
  const DoorModel model = reference_model(kind);
  const DoorMapping mapping(Kinematics::kCartesian3, geometry, model.geometry().handle_radius_m);
  SimulatedHapticMasterOptions options;
  options.device.seed = seed;
  SimulatedHapticMaster device(options);
  SimulatedHandOptions hand;
  hand.handle_radius_m = model.geometry().handle_radius_m;
  hand.pushes.rate_hz = push_rate_hz;
  hand.pushes.amplitude_N = push_amplitude_N;
  device.set_hand(hand, mapping);
  device.start(mapping.inertia_on_device(model.inertia_kg_m2()));
  const double opening_end_s =
      (hand.hand.rest_fraction + hand.hand.opening_fraction + hand.hand.pause_fraction) *
      hand.hand.duration_s;
  LoopResult result;
  for (int tick = 1; tick <= static_cast<int>(hand.hand.duration_s * 1000.0); ++tick) {
    const double t = tick * 0.001;
    device.advance_to(t);
    const DeviceSample sample = device.read();
    const DoorPoint door = mapping.to_door(sample);
    const double torque = model.torque_Nm(door.theta_rad, door.omega_rad_s);
    device.command_force(mapping.to_device(torque, sample));
    result.max_off_arc_m =
        std::max(result.max_off_arc_m, distance_from_arc(mapping, device.truth().position));
    result.max_theta_rad = std::max(result.max_theta_rad, door.theta_rad);
    if (std::abs(t - opening_end_s) < 0.0005) result.theta_at_opening_end_rad = door.theta_rad;
    if (t > 0.95 * hand.hand.duration_s) {
      result.min_theta_after_close_rad = std::min(result.min_theta_after_close_rad, door.theta_rad);
    }
  }
  result.pushes = device.truth().pushes;
  return result;
}

}  // namespace

TEST_CASE("closed loop: the arc constraint holds the end-effector near the arc under pushes",
          "[haptic][sim][closed-loop]") {
  const std::uint64_t seed = GENERATE(1, 2, 3);
  const ModelKind kind = GENERATE(ModelKind::kSensory, ModelKind::kPhysical);
  const LoopResult result = run_closed_loop(ArcGeometry{}, 20.0, 2.0, seed, kind);
  INFO(to_string(kind) << " door, seed " << seed << ": max distance from the arc "
                       << result.max_off_arc_m * 1000.0 << " mm over " << result.pushes
                       << " pushes; θ at the opening's end " << result.theta_at_opening_end_rad
                       << " rad");
  CHECK(result.pushes >= 10);
  CHECK(result.max_off_arc_m < 0.003);  // the stated bound (docs/haptic-devices.md)
  // The hand opens the door to its target, and closes it again.
  CHECK(result.theta_at_opening_end_rad == Approx(1.3963).margin(0.05));
  CHECK(result.max_theta_rad < 1.5708);
  CHECK(result.min_theta_after_close_rad < 0.05);
}

TEST_CASE("closed loop: without the constraint the pushes carry the end-effector off the arc",
          "[haptic][sim][closed-loop]") {
  // The control case: the bound above is the constraint's doing, not the hand's.
  ArcGeometry loose;
  loose.radial_stiffness_N_per_m = loose.axial_stiffness_N_per_m = 0.0;
  loose.radial_damping_N_s_per_m = loose.axial_damping_N_s_per_m = 0.0;
  const LoopResult result = run_closed_loop(loose, 20.0, 2.0, 1);
  CHECK(result.max_off_arc_m > 0.02);
}

TEST_CASE(
    "closed loop: the constraint's defaults are stable from the lightest to the heaviest mass",
    "[haptic][sim][closed-loop]") {
  // Let go 1 cm off the arc radially and 1 cm axially; the constraint alone pulls it back.
  const double mass_kg = GENERATE(2.0, 10.9, 50.0);
  const DoorMapping& mapping = reference_mapping();
  const Vec3 on_arc = mapping.point_at(0.5);
  const Vec3 outward = (on_arc - mapping.geometry().hinge_point_m).normalized();
  SimulatedHapticMasterOptions options;
  options.initial_position = on_arc + 0.01 * outward + Vec3(0.0, 0.01, 0.0);
  SimulatedHapticMaster device(options);
  device.start(mass_kg);
  double worst_after_2s = 0.0;
  for (int tick = 1; tick <= 4000; ++tick) {
    device.advance_to(tick * 0.001);
    const DeviceSample sample = device.read();
    device.command_force(mapping.constraint_force(sample));
    if (tick > 2000) {
      worst_after_2s =
          std::max(worst_after_2s, distance_from_arc(mapping, device.truth().position));
    }
  }
  INFO("mass " << mass_kg << " kg: worst distance after 2 s " << worst_after_2s * 1000.0 << " mm");
  CHECK(worst_after_2s < 0.0001);
}

// ---------------------------------------------------------------- rotary

TEST_CASE("sim rotary: a constant torque gives α = τ/J after the delay", "[haptic][sim][rotary]") {
  SimulatedRotaryOptions options;
  options.device.force_noise_rms = 0.0;
  options.encoder_counts_per_rev = 0.0;
  SimulatedRotaryDevice device(options);
  CHECK(device.name() == "sim:rotary");
  CHECK(device.limits().kinematics == Kinematics::kRotary1);
  CHECK(device.limits().max_force == 30.0);
  device.start(0.95);
  device.command_force(Vec3(1.9, 0.0, 0.0));
  const double dt = 1.0 / options.device.servo_rate_hz;
  device.advance_to(0.001);
  CHECK(device.truth().velocity.x() == 0.0);
  device.advance_to(0.001 + 2.0 * dt);
  CHECK(device.truth().velocity.x() > 0.0);
  device.advance_to(0.1);
  const double rate_a = device.truth().velocity.x();
  device.advance_to(0.3);
  CHECK((device.truth().velocity.x() - rate_a) / 0.2 == Approx(2.0).epsilon(1e-9));
  // The drive's rate estimate follows the true rate (ramp lag of the 300 Hz filter aside).
  CHECK(device.read().velocity.x() == Approx(device.truth().velocity.x()).epsilon(0.01));
}

TEST_CASE("sim rotary: the encoder quantizes and the torque sensor is noisy",
          "[haptic][sim][rotary]") {
  SimulatedRotaryOptions options;
  options.device.force_noise_rms = 0.05;
  SimulatedRotaryDevice device(options);
  device.start(5.0);
  device.command_force(Vec3(0.7, 0.0, 0.0));
  const double count_rad = 2.0 * std::numbers::pi / options.encoder_counts_per_rev;
  double sum_squares = 0.0;
  const int n = 10000;
  for (int i = 1; i <= n; ++i) {
    device.advance_to(i * 0.0004);
    const DeviceSample sample = device.read();
    const double counts = sample.position.x() / count_rad;
    REQUIRE(std::abs(counts - std::round(counts)) < 1e-6);
    REQUIRE(std::abs(sample.position.x() - device.truth().position.x()) <= count_rad);
    sum_squares += sample.measured_force.x() * sample.measured_force.x();
  }
  CHECK(std::sqrt(sum_squares / n) == Approx(0.05).epsilon(0.04));
}

TEST_CASE("sim rotary: impedance mode renders only the rotor's inertia", "[haptic][sim][rotary]") {
  SimulatedRotaryOptions options;
  options.device.force_noise_rms = 0.0;
  options.render_inertia_by_admittance = false;
  SimulatedRotaryDevice device(options);
  CHECK(device.limits().max_inertia == 0.0);
  device.start(0.0);
  device.command_force(Vec3(0.02, 0.0, 0.0));
  device.advance_to(0.1);
  const double rate_a = device.truth().velocity.x();
  device.advance_to(0.2);
  CHECK((device.truth().velocity.x() - rate_a) / 0.1 == Approx(1.0).epsilon(1e-9));
}

TEST_CASE("sim rotary: the end stop, misbehaviour and the inertia check", "[haptic][sim][rotary]") {
  SimulatedRotaryDevice device;
  CHECK_THROWS_WITH(device.start(10.0), Catch::Contains("sim:rotary: inertia 10 outside"));
  device.start(0.5);
  device.command_force(Vec3(10.0, 0.0, 0.0));
  device.advance_to(4.0);
  CHECK(device.truth().position.x() == Approx(1.9 + 10.0 / 2000.0).margin(2e-3));
  device.set_stalled(true);
  const std::uint64_t sequence = device.read().sequence;
  device.advance_to(4.1);
  CHECK(device.read().sequence == sequence);
  device.lose_link();
  CHECK_FALSE(device.read().link_ok);
}

TEST_CASE("sim rotary: deterministic with a seed, and the real-time clock",
          "[haptic][sim][rotary]") {
  auto run = [](std::uint64_t seed) {
    SimulatedRotaryOptions options;
    options.device.seed = seed;
    SimulatedRotaryDevice device(options);
    RotaryHandOptions hand;
    hand.pushes.rate_hz = 5.0;
    device.set_hand(hand);
    device.start(0.95);
    std::vector<double> trace;
    for (int tick = 1; tick <= 2000; ++tick) {
      device.advance_to(tick * 0.001);
      const DeviceSample sample = device.read();
      trace.push_back(sample.position.x());
      trace.push_back(sample.measured_force.x());
    }
    return trace;
  };
  CHECK(run(5) == run(5));
  CHECK(run(5) != run(6));

  SimulatedRotaryOptions options;
  options.device.clock = SimClock::kRealTime;
  SimulatedRotaryDevice device(options);
  device.start(0.95);
  sleep_s(0.1);
  device.read();  // the clock begins here
  CHECK(device.truth().steps == 0);
  sleep_s(0.02);
  CHECK(device.read().time_s > monotonic_now_s() - 0.005);
  CHECK(device.truth().steps >= 40);
}

TEST_CASE("sim rotary: the hand opens the reference door in a closed loop",
          "[haptic][sim][rotary]") {
  const DoorModel model = reference_model(ModelKind::kSensory);
  const DoorMapping mapping(Kinematics::kRotary1, ArcGeometry{}, model.geometry().handle_radius_m);
  SimulatedRotaryDevice device;
  RotaryHandOptions hand;
  hand.pushes.rate_hz = 2.0;
  hand.pushes.amplitude_N = 20.0;
  hand.pushes.tangential = true;
  device.set_hand(hand);
  device.start(mapping.inertia_on_device(model.inertia_kg_m2()));
  double theta_at_opening_end = 0.0, max_theta = -1.0;
  const double opening_end_s = 0.55 * hand.hand.duration_s;
  for (int tick = 1; tick <= 10000; ++tick) {
    device.advance_to(tick * 0.001);
    const DeviceSample sample = device.read();
    const DoorPoint door = mapping.to_door(sample);
    device.command_force(
        mapping.to_device(model.torque_Nm(door.theta_rad, door.omega_rad_s), sample));
    if (tick == static_cast<int>(opening_end_s * 1000.0)) theta_at_opening_end = door.theta_rad;
    max_theta = std::max(max_theta, door.theta_rad);
  }
  CHECK(theta_at_opening_end == Approx(1.3963).margin(0.05));
  CHECK(max_theta < 1.5708);
  CHECK(device.truth().position.x() < 0.05);  // closed again
  CHECK(device.truth().pushes > 5);
}
