// The haptic safety layer (haptic/safety.h, docs/haptic-safety.md): limits, ramps, trips,
// the passivity controller and the parameter-set check.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/sensory_model.h"
#include "haptic/door_mapping.h"
#include "haptic/safety.h"
#include "tests/support/allocation_counter.h"

using namespace doorbench;
using namespace doorbench::haptic;
using Catch::Matchers::Contains;

namespace {

constexpr double kTick = 0.001;

// A sample well inside the default workspace, at rest, with the given sequence number.
DeviceSample sample_at(std::uint64_t sequence, double time_s) {
  DeviceSample sample;
  sample.time_s = time_s;
  sample.sequence = sequence;
  return sample;
}

SafetyInput input_at(int tick, const Vec3& desired) {
  SafetyInput input;
  input.time_s = tick * kTick;
  input.sample = sample_at(static_cast<std::uint64_t>(tick) + 1, input.time_s);
  input.desired_force = desired;
  return input;
}

// Runs a layer at 1 kHz with `desired` until it is running (past the start-up ramp).
int run_until_running(SafetyLayer& layer, const Vec3& desired) {
  int tick = 0;
  while (layer.state() != SafetyState::kRunning) {
    layer.step(input_at(tick, desired));
    ++tick;
    REQUIRE(tick < 10000);
  }
  return tick;
}

struct RampDown {
  double zero_after_s = -1.0;  // time from the trip to the first zero force
  int stopped_events = 0;
  bool monotonic = true;
};

// Keeps ticking at 1 kHz from `first_tick` (time_offset added) and watches the force fall.
RampDown watch_ramp_down(SafetyLayer& layer, int first_tick, double trip_time_s,
                         double time_offset_s, const Vec3& desired, bool fresh_samples = true) {
  RampDown result;
  double previous = std::numeric_limits<double>::infinity();
  for (int tick = first_tick; tick < first_tick + 200; ++tick) {
    SafetyInput input = input_at(tick, desired);
    input.time_s += time_offset_s;
    if (!fresh_samples) input.sample.sequence = 7;
    const SafetyOutput output = layer.step(input);
    const double size = output.force.norm();
    if (size > previous + 1e-12) result.monotonic = false;
    previous = size;
    if (output.events & kEventStopped) ++result.stopped_events;
    if (size == 0.0 && result.zero_after_s < 0.0) {
      result.zero_after_s = input.time_s - trip_time_s;
      CHECK(output.state == SafetyState::kStopped);
    }
  }
  return result;
}

}  // namespace

TEST_CASE("Safety options are checked by name", "[haptic][safety]") {
  SafetyOptions options;
  CHECK(options.validate().empty());
  options.max_force = std::nan("");
  CHECK(options.validate() == "max_force = nan must be > 0");
  options = SafetyOptions{};
  options.max_stale_ticks = 0;
  CHECK(options.validate() == "max_stale_ticks = 0 must be >= 1");
  options = SafetyOptions{};
  options.shutdown_ramp_s = -1.0;
  CHECK_THROWS_WITH(SafetyLayer(options, DeviceLimits{}),
                    "safety options: shutdown_ramp_s = -1 must be > 0");
  // 60 N at 1000 N/s takes 60 ms, longer than the 20 ms the ramp down promises.
  options = SafetyOptions{};
  options.max_force_rate = 1000.0;
  CHECK_THROWS_WITH(SafetyLayer(options, DeviceLimits{}),
                    Contains("shutdown_ramp_s = 0.02 is shorter than the force limit over the "
                             "rate limit (60 / 1000 s)"));
  DeviceLimits limits;
  limits.max_force = 0.0;
  CHECK_THROWS_WITH(SafetyLayer(SafetyOptions{}, limits),
                    "device limits: max_force = 0 must be > 0");
  PassivityOptions passivity;
  passivity.max_damping_Nm_s_per_rad = 0.0;
  CHECK_THROWS_WITH(PassivityController(passivity),
                    "passivity options: max_damping_Nm_s_per_rad = 0 must be > 0");
}

TEST_CASE("Safety limits are the smaller of the device's and the options'", "[haptic][safety]") {
  DeviceLimits limits;
  limits.max_force = 40.0;
  limits.max_force_rate = 30000.0;
  const SafetyLayer layer(SafetyOptions{}, limits);
  CHECK(layer.force_limit() == 40.0);
  CHECK(layer.force_rate_limit() == 5000.0);
}

TEST_CASE("Every event bit has a name and a meaning", "[haptic][safety]") {
  for (std::uint32_t bit = 1; bit <= kEventLateTick; bit <<= 1) {
    CHECK_FALSE(event_name(bit).empty());
    CHECK_FALSE(event_meaning(bit).empty());
  }
  CHECK(event_name(kEventDeadlineMiss) == "deadline_miss");
  CHECK(event_name(kEventVelocityTrip | kEventDeadlineMiss).empty());
  CHECK(to_string(SafetyState::kRampingDown) == "ramping_down");
}

TEST_CASE("Each event is described with its figure against its limit, word for word",
          "[haptic][safety]") {
  DeviceLimits limits;  // a ±0.2 m box, 1 m/s
  SafetyOptions options;
  options.velocity_trip = 0.5;
  const SafetyLayer layer(options, limits);
  EventFacts facts;
  facts.sample.velocity = Vec3(0.3, 0.4, 0.12);  // 0.514 m/s
  facts.sample.position = Vec3(0.0, -0.1953, 0.0);
  facts.interval_s = 0.1314;
  facts.stale_ticks = 50;
  CHECK(layer.describe(kEventVelocityTrip, facts) ==
        "velocity_trip: the device moved at 0.514 m/s, above the trip speed of 0.5 m/s "
        "(velocity_trip, or the device's max_velocity)");
  CHECK(layer.describe(kEventWorkspaceTrip, facts) ==
        "workspace_trip: the device's y reached -0.1953 m, 0.3 mm beyond -0.195 m (its "
        "workspace less workspace_margin_m 0.005 m)");
  CHECK(layer.describe(kEventDeadlineMiss, facts) ==
        "deadline_miss: 0.131 s between two ticks, above max_tick_stall_s 0.1 s: the tick "
        "stalled");
  facts.interval_s = 0.0062;
  CHECK(layer.describe(kEventLateTick, facts) ==
        "late_tick: 6.2 ms between two ticks, above max_tick_interval_s 5 ms: the device held "
        "the last force meanwhile; counted, playback goes on");
  CHECK(layer.describe(kEventDeviceStalled, facts) ==
        "device_stalled: the device's reading did not change for 50 ticks (max_stale_ticks 50)");
  // Without a figure: the event's meaning.
  CHECK(layer.describe(kEventLinkLost, facts) ==
        "link_lost: trip: the device reported its link lost");
  facts.interval_s = kNaN;  // the first tick has no interval
  CHECK(layer.describe(kEventDeadlineMiss, facts) ==
        "deadline_miss: " + std::string(event_meaning(kEventDeadlineMiss)));
  // The rotary device's units.
  DeviceLimits rotary;
  rotary.kinematics = Kinematics::kRotary1;
  rotary.max_velocity = 6.0;
  rotary.workspace_min = Vec3(-0.3, 0, 0);
  rotary.workspace_max = Vec3(1.9, 0, 0);
  const SafetyLayer turning(SafetyOptions{}, rotary);
  facts.sample.velocity = Vec3(-2.5, 0, 0);
  facts.sample.position = Vec3(1.8999, 0, 0);
  CHECK(turning.describe(kEventVelocityTrip, facts) ==
        "velocity_trip: the device moved at 2.5 rad/s, above the trip speed of 1 rad/s "
        "(velocity_trip, or the device's max_velocity)");
  CHECK(turning.describe(kEventWorkspaceTrip, facts) ==
        "workspace_trip: the device's angle reached 1.9 rad, 4.9 mrad beyond 1.895 rad (its "
        "workspace less workspace_margin_m 0.005 m)");
}

TEST_CASE("The start-up ramp scales the force linearly from 0 to 1", "[haptic][safety]") {
  SafetyOptions options;
  options.startup_ramp_s = 0.5;
  SafetyLayer layer(options, DeviceLimits{});
  const Vec3 desired(10.0, 0.0, 0.0);  // 10 N over 0.5 s is 20 N/s: the rate limit never acts
  int done_events = 0;
  for (int tick = 0; tick <= 700; ++tick) {
    const SafetyOutput output = layer.step(input_at(tick, desired));
    const double t = tick * kTick;
    const double expected_scale = std::min(1.0, t / 0.5);
    REQUIRE(output.scale == Approx(expected_scale).margin(1e-12));
    REQUIRE(output.force.x() == Approx(10.0 * expected_scale).margin(1e-9));
    REQUIRE_FALSE(output.clipped);
    if (output.events & kEventStartRampDone) {
      ++done_events;
      CHECK(tick == 500);
    }
    CHECK(output.state == (tick < 500 ? SafetyState::kStarting : SafetyState::kRunning));
  }
  CHECK(done_events == 1);
}

TEST_CASE("The force limit clips the magnitude, keeps the direction, one event per episode",
          "[haptic][safety]") {
  SafetyOptions options;
  options.startup_ramp_s = 0.0;
  SafetyLayer layer(options, DeviceLimits{});
  int limited = 0;
  int rate_limited = 0;
  Vec3 last = Vec3::Zero();
  for (int tick = 0; tick < 300; ++tick) {
    const SafetyOutput output = layer.step(input_at(tick, Vec3(300.0, 400.0, 0.0)));
    if (output.events & kEventForceLimited) ++limited;
    if (output.events & kEventForceRateLimited) ++rate_limited;
    last = output.force;
  }
  CHECK(last.norm() == Approx(60.0));
  CHECK(last.x() / last.y() == Approx(0.75));
  CHECK(limited == 1);
  CHECK(rate_limited == 1);  // 60 N at 5000 N/s takes 12 ticks
}

TEST_CASE("The rate limit slows a step to max_force_rate", "[haptic][safety]") {
  SafetyOptions options;
  options.startup_ramp_s = 0.0;
  SafetyLayer layer(options, DeviceLimits{});
  std::vector<double> forces;
  for (int tick = 0; tick < 20; ++tick) {
    forces.push_back(layer.step(input_at(tick, Vec3(0.0, 0.0, -50.0))).force.z());
  }
  // First tick: no interval yet, so no change at all; then 5 N per 1 ms tick.
  CHECK(forces[0] == 0.0);
  for (int tick = 1; tick <= 10; ++tick) CHECK(forces[tick] == Approx(-5.0 * tick));
  CHECK(forces[15] == Approx(-50.0));
}

TEST_CASE("Adversarial inputs never break the limits (property test)", "[haptic][safety]") {
  std::mt19937_64 random(20261121);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double specials[] = {nan, inf, -inf, 1e308, -1e308, 1e-320, 0.0, -0.0, 1e12, -1e12};
  auto wild = [&](double typical) {
    const double r = unit(random);
    if (r < 0.01) return specials[random() % std::size(specials)];
    if (r < 0.1) return -typical * normal(random) * 100.0;  // sign flips, big values
    return typical * normal(random);
  };
  long long ticks = 0;
  int runs = 0;
  int trips_seen = 0;
  while (ticks < 200000) {
    SafetyOptions options;
    options.startup_ramp_s = unit(random) * 0.2;
    DeviceLimits limits;
    limits.kinematics = unit(random) < 0.3 ? Kinematics::kRotary1 : Kinematics::kCartesian3;
    limits.max_force = 20.0 + 100.0 * unit(random);
    SafetyLayer layer(options, limits);
    ++runs;
    double time_s = unit(random);
    double previous_time_s = time_s;
    Vec3 previous_force = Vec3::Zero();
    std::uint64_t sequence = 0;
    // How often this run's ticks go wrong: never in a third of the runs (the limits alone,
    // under a desired force that jumps every tick), else from 1e-4 to 3e-2.
    const double adversity = unit(random) < 0.33 ? 0.0 : std::pow(10.0, -4.0 + 2.5 * unit(random));
    const int stop_at = unit(random) < 0.2 ? static_cast<int>(unit(random) * 5000) : -1;
    for (int tick = 0; tick < 5000; ++tick, ++ticks) {
      SafetyInput input;
      const double r = unit(random);
      if (r < adversity * 0.1) {
        time_s = specials[random() % std::size(specials)];
      } else if (r < adversity) {
        time_s = previous_time_s + (unit(random) - 0.3) * 0.05;  // gaps, steps back
      } else if (std::isfinite(previous_time_s)) {
        time_s = previous_time_s + kTick * (0.5 + unit(random));
      } else {
        time_s = 0.0;
      }
      input.time_s = time_s;
      if (unit(random) > adversity) ++sequence;
      input.sample.sequence = sequence;
      input.sample.link_ok = unit(random) > adversity * 0.05;
      const double gross = unit(random) < adversity ? 1.0 : 0.0;
      for (int axis = 0; axis < 3; ++axis) {
        input.sample.position[axis] = gross ? wild(0.1) : 0.02 * normal(random);
        input.sample.velocity[axis] = gross ? wild(0.5) : 0.1 * normal(random);
        input.sample.measured_force[axis] = gross ? wild(10.0) : 5.0 * normal(random);
        input.desired_force[axis] = unit(random) < adversity ? wild(50.0) : 40.0 * normal(random);
      }
      if (tick == stop_at) layer.request_stop();
      const SafetyOutput output = layer.step(input);
      REQUIRE(output.force.allFinite());
      REQUIRE(output.force.norm() <= layer.force_limit() * (1.0 + 1e-12));
      REQUIRE(output.scale >= 0.0);
      REQUIRE(output.scale <= 1.0);
      if (limits.kinematics == Kinematics::kRotary1) {
        REQUIRE(output.force.y() == 0.0);
        REQUIRE(output.force.z() == 0.0);
      }
      if (std::isfinite(time_s) && std::isfinite(previous_time_s)) {
        const double allowed = layer.force_rate_limit() * std::max(0.0, time_s - previous_time_s);
        REQUIRE((output.force - previous_force).norm() <= allowed * (1.0 + 1e-9) + 1e-9);
      } else {
        // A clock that is not finite: the one case where the force may drop to zero at once.
        REQUIRE(((output.force - previous_force).norm() == 0.0 || output.force.isZero(0.0)));
      }
      if (output.state == SafetyState::kStopped) {
        REQUIRE(output.force.isZero(0.0));
        ++trips_seen;
        break;
      }
      previous_force = output.force;
      previous_time_s = time_s;
    }
  }
  WARN("adversarial inputs: " << ticks << " ticks in " << runs << " runs, " << trips_seen
                              << " of them tripped and stopped");
  CHECK(runs > 40);
  CHECK(trips_seen > 20);  // the adversity did trip layers, so the ramp downs were exercised
}

TEST_CASE("A late tick is counted and played on, and the force after it ramps at the rate limit",
          "[haptic][safety]") {
  SafetyOptions options;
  SafetyLayer layer(options, DeviceLimits{});
  const Vec3 desired(0.0, 30.0, 40.0);
  const int running_at = run_until_running(layer, desired);
  // The next tick comes 8 ms late (late above 5 ms, a stall only above 100 ms) and asks for
  // the opposite force: the layer goes on, and the change is limited as over 5 ms, not 8.
  SafetyInput late = input_at(running_at, -desired);
  late.time_s += 0.008;
  const SafetyOutput output = layer.step(late);
  CHECK(output.events == (kEventLateTick | kEventForceRateLimited));
  CHECK(output.state == SafetyState::kRunning);
  const double allowed_change = layer.force_rate_limit() * options.max_tick_interval_s;
  CHECK((output.force - desired).norm() == Approx(allowed_change));
  // The ticks after it are on time: no more late events, and the force reaches the target.
  SafetyOutput next;
  for (int k = 1; k <= 40; ++k) {
    SafetyInput on_time = input_at(running_at + k, -desired);
    on_time.time_s += 0.008;
    next = layer.step(on_time);
    CHECK((next.events & (kEventLateTick | kEventDeadlineMiss)) == 0);
  }
  CHECK(next.state == SafetyState::kRunning);
  CHECK(next.force.isApprox(-desired));
}

TEST_CASE("A stalled tick ramps the force to zero within shutdown_ramp_s", "[haptic][safety]") {
  SafetyOptions options;
  SafetyLayer layer(options, DeviceLimits{});
  const Vec3 desired(0.0, 30.0, 40.0);
  const int running_at = run_until_running(layer, desired);
  // The next tick comes 120 ms late: past max_tick_stall_s (100 ms).
  SafetyInput late = input_at(running_at, desired);
  late.time_s += 0.120;
  const SafetyOutput trip = layer.step(late);
  CHECK(trip.events == kEventDeadlineMiss);
  CHECK(trip.state == SafetyState::kRampingDown);
  CHECK(trip.force.norm() == Approx(50.0));  // the trip tick itself holds the force
  const RampDown ramp = watch_ramp_down(layer, running_at + 1, late.time_s, 0.120, desired);
  CHECK(ramp.monotonic);
  CHECK(ramp.stopped_events == 1);
  CHECK(ramp.zero_after_s > 0.0);
  CHECK(ramp.zero_after_s <= options.shutdown_ramp_s + 1e-9);
  CHECK(layer.state() == SafetyState::kStopped);
  // Nothing restarts it: a fresh, valid tick still gives zero and no events.
  const SafetyOutput after = layer.step(input_at(running_at + 500, desired));
  CHECK(after.force.isZero(0.0));
  CHECK(after.events == 0);
}

TEST_CASE("A time that steps back is a missed deadline", "[haptic][safety]") {
  SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
  const int running_at = run_until_running(layer, Vec3(5.0, 0.0, 0.0));
  SafetyInput back = input_at(running_at, Vec3(5.0, 0.0, 0.0));
  back.time_s -= 0.01;
  CHECK((layer.step(back).events & kEventDeadlineMiss) != 0);
}

TEST_CASE("A stalled device trips after max_stale_ticks, and a lost link trips at once",
          "[haptic][safety]") {
  SECTION("stalled") {
    SafetyOptions options;
    options.max_stale_ticks = 50;
    SafetyLayer layer(options, DeviceLimits{});
    const Vec3 desired(20.0, 0.0, 0.0);
    const int running_at = run_until_running(layer, desired);
    int tripped_after = -1;
    for (int i = 1; i <= 100 && tripped_after < 0; ++i) {
      SafetyInput input = input_at(running_at + i, desired);
      input.sample.sequence = 424242;  // the same reading again and again
      const SafetyOutput output = layer.step(input);
      if (output.events & kEventDeviceStalled) {
        tripped_after = i;
        CHECK(output.state == SafetyState::kRampingDown);
      }
    }
    // The first repeat is tick 1 with a new number; ticks 2.. repeat it: 50 stale ticks.
    CHECK(tripped_after == 51);
    const double trip_time_s = (running_at + tripped_after) * kTick;
    const RampDown ramp =
        watch_ramp_down(layer, running_at + tripped_after + 1, trip_time_s, 0.0, desired, false);
    CHECK(ramp.zero_after_s <= options.shutdown_ramp_s + 1e-9);
    CHECK(ramp.stopped_events == 1);
  }
  SECTION("one stale tick short of the limit does not trip") {
    SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
    const int running_at = run_until_running(layer, Vec3::Zero());
    for (int round = 0; round < 20; ++round) {
      for (int i = 0; i < 50; ++i) {  // 49 repeats, then a new reading
        SafetyInput input = input_at(running_at + round * 50 + i, Vec3::Zero());
        input.sample.sequence = 1000 + static_cast<std::uint64_t>(round);
        REQUIRE(layer.step(input).events == 0);
      }
    }
    CHECK(layer.state() == SafetyState::kRunning);
  }
  SECTION("link lost") {
    SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
    const Vec3 desired(0.0, 0.0, 12.0);
    const int running_at = run_until_running(layer, desired);
    SafetyInput input = input_at(running_at, desired);
    input.sample.link_ok = false;
    const SafetyOutput output = layer.step(input);
    CHECK(output.events == kEventLinkLost);
    const RampDown ramp = watch_ramp_down(layer, running_at + 1, input.time_s, 0.0, desired);
    CHECK(ramp.zero_after_s <= 0.02 + 1e-9);
  }
}

TEST_CASE("Velocity and workspace trips", "[haptic][safety]") {
  const Vec3 desired(3.0, 0.0, 0.0);
  SECTION("Cartesian speed above velocity_trip") {
    SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
    const int running_at = run_until_running(layer, desired);
    SafetyInput input = input_at(running_at, desired);
    input.sample.velocity = Vec3(0.6, 0.6, 0.6);  // 1.04 m/s; no single axis is above 1
    CHECK(layer.step(input).events == kEventVelocityTrip);
  }
  SECTION("the device's own max_velocity when smaller") {
    DeviceLimits limits;
    limits.max_velocity = 0.5;
    SafetyLayer layer(SafetyOptions{}, limits);
    const int running_at = run_until_running(layer, desired);
    SafetyInput input = input_at(running_at, desired);
    input.sample.velocity = Vec3(0.0, -0.55, 0.0);
    CHECK(layer.step(input).events == kEventVelocityTrip);
  }
  SECTION("position within the margin of the workspace's edge") {
    SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
    const int running_at = run_until_running(layer, desired);
    SafetyInput inside = input_at(running_at, desired);
    inside.sample.position = Vec3(0.0, 0.194, 0.0);  // 6 mm from the edge, margin 5 mm
    CHECK(layer.step(inside).events == 0);
    SafetyInput outside = input_at(running_at + 1, desired);
    outside.sample.position = Vec3(0.0, 0.0, -0.196);
    const SafetyOutput output = layer.step(outside);
    CHECK(output.events == kEventWorkspaceTrip);
    CHECK(output.state == SafetyState::kRampingDown);
  }
  SECTION("rotary device: angle and rate in x only") {
    DeviceLimits limits;
    limits.kinematics = Kinematics::kRotary1;
    limits.workspace_min = Vec3(-0.05, 0.0, 0.0);
    limits.workspace_max = Vec3(1.6, 0.0, 0.0);
    SafetyOptions options;
    options.workspace_margin_m = 0.01;  // rad on a rotary device
    SafetyLayer layer(options, limits);
    const int running_at = run_until_running(layer, desired);
    SafetyInput input = input_at(running_at, desired);
    input.sample.position = Vec3(1.5, 0.0, 0.0);
    CHECK(layer.step(input).events == 0);
    input = input_at(running_at + 1, desired);
    input.sample.position = Vec3(1.595, 0.0, 0.0);
    CHECK(layer.step(input).events == kEventWorkspaceTrip);
  }
  SECTION("a NaN reading trips as non-finite input") {
    SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
    const int running_at = run_until_running(layer, desired);
    SafetyInput input = input_at(running_at, desired);
    input.sample.velocity.y() = std::nan("");
    const SafetyOutput output = layer.step(input);
    CHECK(output.events == kEventNonFiniteInput);
    CHECK(output.force.allFinite());
  }
  SECTION("a NaN clock drops the force to zero at once") {
    SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
    const int running_at = run_until_running(layer, desired);
    SafetyInput input = input_at(running_at, desired);
    input.time_s = std::nan("");
    const SafetyOutput output = layer.step(input);
    CHECK(output.events == (kEventNonFiniteInput | kEventStopped));
    CHECK(output.force.isZero(0.0));
    CHECK(output.state == SafetyState::kStopped);
  }
}

TEST_CASE("request_stop ramps down once and stops", "[haptic][safety]") {
  SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
  const Vec3 desired(-45.0, 0.0, 0.0);
  const int running_at = run_until_running(layer, desired);
  layer.request_stop();
  layer.request_stop();
  const SafetyOutput output = layer.step(input_at(running_at, desired));
  CHECK(output.events == kEventStopRequested);
  const RampDown ramp = watch_ramp_down(layer, running_at + 1, running_at * kTick, 0.0, desired);
  CHECK(ramp.monotonic);
  CHECK(ramp.stopped_events == 1);
  CHECK(ramp.zero_after_s == Approx(0.02).margin(1e-9));
  layer.request_stop();
  CHECK(layer.step(input_at(running_at + 300, desired)).events == 0);
}

TEST_CASE("A stop during the start-up ramp ramps down from where it was", "[haptic][safety]") {
  SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
  const Vec3 desired(0.0, 50.0, 0.0);
  for (int tick = 0; tick < 100; ++tick) layer.step(input_at(tick, desired));
  layer.request_stop();
  const SafetyOutput first = layer.step(input_at(100, desired));
  // The stop holds the previous tick's force (99 ms of a 0.5 s ramp), then ramps it down.
  CHECK(first.force.y() == Approx(50.0 * 0.099 / 0.5));
  CHECK(first.scale == Approx(0.099 / 0.5));
  const SafetyOutput next = layer.step(input_at(110, desired));
  CHECK(next.force.y() == Approx(0.5 * 50.0 * 0.099 / 0.5));  // 10 ms of 20 ms
}

TEST_CASE("The safety layer's step and the passivity controller allocate nothing",
          "[haptic][safety]") {
  SafetyLayer layer(SafetyOptions{}, DeviceLimits{});
  PassivityController passivity(PassivityOptions{});
  std::uint32_t events = 0;
  double sink = 0.0;
  const long long before = doorbench::testing::allocations();
  for (int tick = 0; tick < 20000; ++tick) {
    SafetyInput input = input_at(tick, Vec3(std::sin(tick * 0.01) * 80.0, 1.0, 2.0));
    if (tick == 15000) input.sample.link_ok = false;  // the ramp down and the stop, too
    sink += layer.step(input).force.x();
    sink += passivity.step(5.0, std::sin(tick * 0.003), kTick, events);
  }
  const long long after = doorbench::testing::allocations();
  CHECK(after == before);
  CHECK(std::isfinite(sink));
  CHECK(layer.state() == SafetyState::kStopped);
}

namespace {

struct LoopResult {
  double injected_J = 0.0;         // ∫ (τ_snap + τ_passivity) ω dt, measured by the loop
  double max_injected_J = 0.0;     // its largest value during the run
  double max_tick_energy_J = 0.0;  // the largest |τ_snap ω dt| of a single tick
  double max_damping = 0.0;        // the largest τ_passivity / (−ω)
  int activations = 0;
  bool any_damping = false;
};

// A 1-DOF door driven by a stiff hand (PD on θ_ref(t)): J dω/dt = τ_m + τ_passivity + τ_hand,
// semi-implicit Euler at 1 kHz. The snap term is the model's active term.
LoopResult drive_door(const DoorModel& model, PassivityController& passivity, double duration_s,
                      double (*theta_ref)(double)) {
  LoopResult result;
  const double inertia = model.inertia_kg_m2();
  double theta = theta_ref(0.0);
  double omega = 0.0;
  std::vector<double> terms(static_cast<std::size_t>(model.term_count()));
  const double hand_stiffness = 3000.0;  // N*m/rad
  const double hand_damping = 40.0;      // N*m*s/rad
  const int steps = static_cast<int>(duration_s / kTick);
  for (int i = 0; i < steps; ++i) {
    const double t = i * kTick;
    const double reference = theta_ref(t);
    const double reference_rate = (theta_ref(t + kTick) - reference) / kTick;
    const double model_torque = model.torque_Nm(theta, omega, terms);
    const double active = terms[sensory::kSnap];
    std::uint32_t events = 0;
    const double damping_torque = passivity.step(active, omega, kTick, events);
    if (events & kEventPassivityActive) ++result.activations;
    if (damping_torque != 0.0) {
      result.any_damping = true;
      result.max_damping = std::max(result.max_damping, -damping_torque / omega);
    }
    const double hand =
        hand_stiffness * (reference - theta) + hand_damping * (reference_rate - omega);
    const double new_omega = omega + kTick * (model_torque + damping_torque + hand) / inertia;
    // The power over the tick with the torques held and ω moving from omega to new_omega.
    result.injected_J += (active + damping_torque) * 0.5 * (omega + new_omega) * kTick;
    result.max_injected_J = std::max(result.max_injected_J, result.injected_J);
    result.max_tick_energy_J = std::max(result.max_tick_energy_J, std::abs(active * omega * kTick));
    omega = new_omega;
    theta += kTick * omega;
  }
  return result;
}

DoorModel with_snap_damping(double c) {
  const DoorModel reference = reference_model(ModelKind::kSensory);
  std::vector<double> values(reference.parameter_values().begin(),
                             reference.parameter_values().end());
  values[sensory::kC] = c;
  return reference.with_parameter_values(values);
}

// Back and forth through the snap zone (θ1 = 0.028, θ2 = 0.038 rad) twice a second.
double through_the_snap_zone(double t) {
  return 0.045 - 0.04 * std::cos(2.0 * M_PI * 2.0 * t);
}

// One opening stroke from closed to 0.3 rad in 1 s, then held.
double one_opening(double t) {
  const double u = std::min(1.0, t);
  return 0.3 * (3.0 * u * u - 2.0 * u * u * u);
}

}  // namespace

TEST_CASE("Passivity: a large snap driven through its zone stays within the energy budget",
          "[haptic][safety]") {
  const DoorModel model = with_snap_damping(45.0);
  PassivityOptions options;
  options.budget_recovery_W = 0.0;  // the budget alone: the injected energy must stay below it
  SECTION("without the controller the snap keeps injecting (the test can fail)") {
    options.enabled = false;
    PassivityController off(options);
    const LoopResult result = drive_door(model, off, 4.0, through_the_snap_zone);
    WARN("snap c = 45 through its zone for 4 s without control: injected " << result.injected_J
                                                                           << " J");
    CHECK(result.injected_J > 4.0 * options.energy_budget_J);
  }
  SECTION("with the controller") {
    PassivityController passivity(options);
    const LoopResult result = drive_door(model, passivity, 4.0, through_the_snap_zone);
    INFO("max injected " << result.max_injected_J << " J, one tick " << result.max_tick_energy_J
                         << " J, dissipated " << passivity.dissipated_energy_J() << " J");
    WARN("snap c = 45 through its zone for 4 s: injected at most "
         << result.max_injected_J << " J (budget " << options.energy_budget_J << " J, one tick "
         << result.max_tick_energy_J << " J), dissipated " << passivity.dissipated_energy_J()
         << " J, largest damping " << result.max_damping << " N*m*s/rad");
    CHECK(result.max_injected_J <= options.energy_budget_J + result.max_tick_energy_J + 1e-3);
    CHECK(passivity.observed_energy_J() <= options.energy_budget_J + 1e-12);
    CHECK(result.any_damping);
    CHECK(result.activations >= 1);
    CHECK(result.max_damping <= options.max_damping_Nm_s_per_rad);
    CHECK(passivity.dissipated_energy_J() > 1.0);
  }
  SECTION("with the budget recovering, the long-run injection is bounded by its rate") {
    options.budget_recovery_W = 0.5;
    PassivityController passivity(options);
    const LoopResult result = drive_door(model, passivity, 4.0, through_the_snap_zone);
    CHECK(result.max_injected_J <=
          options.energy_budget_J + 0.5 * 4.0 + result.max_tick_energy_J + 1e-3);
    CHECK(result.max_damping <= options.max_damping_Nm_s_per_rad);
  }
}

TEST_CASE("Passivity: one normal snap passes untouched", "[haptic][safety]") {
  const DoorModel model = reference_model(ModelKind::kSensory);  // c = 3 N*m*s/rad
  PassivityController passivity(PassivityOptions{});
  const LoopResult result = drive_door(model, passivity, 1.5, one_opening);
  WARN("one opening of the reference door: snap injected "
       << result.injected_J << " J, observed " << passivity.observed_energy_J() << " J at the end");
  CHECK(result.injected_J > 0.0);  // it did snap
  CHECK_FALSE(result.any_damping);
  CHECK(result.activations == 0);
  CHECK(passivity.dissipated_energy_J() == 0.0);
}

TEST_CASE("Passivity controller: damping capped, event once per episode", "[haptic][safety]") {
  PassivityOptions options;
  options.energy_budget_J = 0.1;
  options.budget_recovery_W = 0.0;
  options.max_damping_Nm_s_per_rad = 5.0;
  PassivityController passivity(options);
  std::uint32_t events = 0;
  double torque = 0.0;
  for (int i = 0; i < 1000; ++i) torque = passivity.step(100.0, 1.0, kTick, events);
  CHECK(events == kEventPassivityActive);
  CHECK(torque == Approx(-5.0));  // capped: 100 N*m of active torque cannot be cancelled by 5
  CHECK(passivity.step(std::nan(""), 1.0, kTick, events) == 0.0);
}

namespace {

DoorMapping hapticmaster_mapping() {
  return DoorMapping(Kinematics::kCartesian3, ArcGeometry{}, 0.58);
}

// The reference sensory door with one value replaced and every bound opened wide, so that
// the stiffness check (not the bounds) decides.
DoorModel widened(int index, double value) {
  const DoorModel reference = reference_model(ModelKind::kSensory);
  std::vector<double> values(reference.parameter_values().begin(),
                             reference.parameter_values().end());
  std::vector<Bounds> bounds(reference.parameter_bounds().begin(),
                             reference.parameter_bounds().end());
  values[static_cast<std::size_t>(index)] = value;
  for (Bounds& b : bounds) b = {-1e9, 1e9};
  return DoorModel(ModelKind::kSensory, reference.geometry(), values, bounds);
}

}  // namespace

TEST_CASE("The reference door passes the parameter check at 1 kHz on the HapticMaster",
          "[haptic][safety]") {
  const DoorMapping mapping = hapticmaster_mapping();
  for (ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const DoorModel model = reference_model(kind);
    const double mass = mapping.inertia_on_device(model.inertia_kg_m2());
    CHECK(mass == Approx(0.95 / (0.58 * 0.15)));
    const double theta_max = model.geometry().theta_max_rad;
    const RestoringSlope slope = stiffest_restoring_slope(model, -0.02, theta_max + 0.02);
    const double on_device = mapping.stiffness_on_device(slope.slope_Nm_per_rad);
    const double bound = stiffness_bound(mass, 0.001);
    INFO(to_string(kind) << ": slope " << slope.slope_Nm_per_rad << " N*m/rad at "
                         << slope.theta_rad << " rad (" << slope.evaluations << " evaluations), "
                         << on_device << " N/m on the device, bound " << bound << " N/m, margin x"
                         << bound / on_device);
    CHECK(check_parameter_set(model, mapping, mass, 0.001, -0.02, theta_max + 0.02).empty());
    CHECK(on_device < bound);
    // The end stop (k_stop = 5000 N*m/rad) is the stiffest restoring slope of both doors.
    CHECK(slope.slope_Nm_per_rad >= 5000.0);
    // Inside the stops, the latch alone.
    const RestoringSlope latch = stiffest_restoring_slope(model, 0.001, theta_max - 0.001);
    WARN(to_string(kind) << " reference door inside the stops: stiffest slope "
                         << latch.slope_Nm_per_rad << " N*m/rad at " << latch.theta_rad
                         << " rad = " << mapping.stiffness_on_device(latch.slope_Nm_per_rad)
                         << " N/m on the device");
    WARN(to_string(kind) << " reference door: stiffest slope " << slope.slope_Nm_per_rad
                         << " N*m/rad at " << slope.theta_rad << " rad (" << slope.evaluations
                         << " evaluations) = " << on_device << " N/m on the device; bound " << bound
                         << " N/m at 1 kHz, m = " << mass << " kg: margin x" << bound / on_device);
  }
}

TEST_CASE("The stiffness check finds steep latch edges and refuses what the loop cannot render",
          "[haptic][safety]") {
  const DoorMapping mapping = hapticmaster_mapping();
  const double mass = mapping.inertia_on_device(0.95);
  SECTION("k_inf x1000") {
    const DoorModel model = widened(sensory::kKInf, 1054.0 * 1000.0);
    const std::string message = check_parameter_set(model, mapping, mass, 0.001, 0.0, 1.5708);
    WARN(message);
    CHECK_THAT(message, Contains("the stiffest restoring slope, -dtau/dtheta = 1.1"));
    CHECK_THAT(message, Contains("above the stability bound 1.94e+05 N/m for an inertia of 10.9 kg "
                                 "at a tick period of 0.001 s"));
  }
  SECTION("a latch edge between two grid points is still found") {
    // With β = 2e6 the switch at θ0 is 1e-6 rad wide, far narrower than the grid (4e-4 rad).
    // −∂τ/∂θ of −(k θ + k_inf (θ − θ0) S(θ; θ0)) peaks just above θ0 at about k + 1.1 k_inf;
    // the stops lie outside [0, θ_max] and the edge at θ1 is not restoring.
    const DoorModel model = widened(sensory::kBeta, 2e6);
    const RestoringSlope slope = stiffest_restoring_slope(model, 0.0, 1.5708);
    CHECK(slope.slope_Nm_per_rad > 1054.0);
    CHECK(slope.theta_rad == Approx(0.00698).margin(1e-4));
  }
  SECTION("the reference door at 100 Hz") {
    const DoorModel model = reference_model(ModelKind::kSensory);
    const std::string message = check_parameter_set(model, mapping, mass, 0.01, -0.02, 1.6);
    CHECK_THAT(message, Contains("-dtau/dtheta = 5.0"));
    CHECK_THAT(message, Contains("above the stability bound 1.94e+03 N/m"));
  }
  SECTION("a rotary device: stiffness in N*m/rad, inertia in kg*m^2") {
    const DoorMapping rotary(Kinematics::kRotary1, ArcGeometry{}, 0.58);
    const DoorModel model = reference_model(ModelKind::kSensory);
    CHECK(check_parameter_set(model, rotary, 0.95, 0.001, -0.02, 1.6).empty());
    CHECK_THAT(check_parameter_set(model, rotary, 0.95, 0.004, -0.02, 1.6),
               Contains("N*m/rad on the device, above the stability bound 1.06e+03 N*m/rad for "
                        "an inertia of 0.95 kg*m^2"));
  }
}

TEST_CASE("Parameter values are checked by name before a model is built", "[haptic][safety]") {
  const DoorMapping mapping = hapticmaster_mapping();
  const DoorModel model = reference_model(ModelKind::kSensory);
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  CHECK(check_parameter_values(model, values, mapping, 10.9, 0.001, -0.02, 1.6).empty());
  SECTION("NaN") {
    values[sensory::kKInf] = std::nan("");
    CHECK(check_parameter_values(model, values, mapping, 10.9, 0.001, -0.02, 1.6) ==
          "k_inf = nan is not finite");
  }
  SECTION("infinite") {
    values[sensory::kJ] = -std::numeric_limits<double>::infinity();
    CHECK(check_parameter_values(model, values, mapping, 10.9, 0.001, -0.02, 1.6) ==
          "J = -inf is not finite");
  }
  SECTION("outside its bounds") {
    values[sensory::kTheta1] = 0.2;
    CHECK(check_parameter_values(model, values, mapping, 10.9, 0.001, -0.02, 1.6) ==
          "theta1 = 0.2 is outside its bounds [0.002, 0.08]");
  }
  SECTION("a constraint between parameters") {
    values[sensory::kTheta0] = 0.03;  // within its bounds, above theta1
    CHECK_THAT(check_parameter_values(model, values, mapping, 10.9, 0.001, -0.02, 1.6),
               Contains("theta0 = 0.03 breaks 0 < theta0 < theta1"));
  }
  SECTION("the wrong count") {
    values.pop_back();
    CHECK(check_parameter_values(model, values, mapping, 10.9, 0.001, -0.02, 1.6) ==
          "expected 17 parameter values, got 16");
  }
  SECTION("a model whose value lies outside its own bounds") {
    const DoorModel outside = [&] {
      std::vector<Bounds> bounds(model.parameter_bounds().begin(), model.parameter_bounds().end());
      bounds[sensory::kK] = {0.0, 10.0};
      return DoorModel(ModelKind::kSensory, model.geometry(), values, bounds);
    }();
    CHECK(check_parameter_set(outside, mapping, 10.9, 0.001, -0.02, 1.6) ==
          "k = 40 is outside its bounds [0, 10]");
  }
  SECTION("unusable arguments throw") {
    CHECK_THROWS_WITH(check_parameter_set(model, mapping, 0.0, 0.001, -0.02, 1.6),
                      "check_parameter_set: device_inertia = 0 must be > 0");
    CHECK_THROWS_WITH(check_parameter_set(model, mapping, 10.9, std::nan(""), -0.02, 1.6),
                      "check_parameter_set: tick_period_s = nan must be > 0");
    CHECK_THROWS_WITH(check_parameter_set(model, mapping, 10.9, 0.001, 1.0, 1.0),
                      "check_parameter_set: the angle range [1, 1] rad must be finite and not "
                      "empty");
  }
}

namespace {

// The loop the bound is derived for (docs/haptic-safety.md): an admittance device renders a
// mass m with damping b (its own and the hand's) far faster than the tick; the tick reads
// the position and its spring force reaches the device one period later and is held for a
// period. Returns the oscillation's amplitude after `duration_s` relative to its start.
double delayed_spring_growth(double mass, double damping, double stiffness, double period_s,
                             double duration_s) {
  constexpr int kSubsteps = 50;
  const double h = period_s / kSubsteps;
  double x = 0.001;
  double v = 0.0;
  double read_now = x;
  double force = 0.0;  // computed from the previous tick's reading
  double early_peak = 0.0;
  double late_peak = 0.0;
  const int ticks = static_cast<int>(duration_s / period_s);
  for (int tick = 0; tick < ticks; ++tick) {
    const double read_previous = read_now;
    read_now = x;
    force = -stiffness * read_previous;
    for (int i = 0; i < kSubsteps; ++i) {
      v += h * (force - damping * v) / mass;
      x += h * v;
    }
    if (tick < ticks / 10) early_peak = std::max(early_peak, std::abs(x));
    if (tick > ticks * 9 / 10) late_peak = std::max(late_peak, std::abs(x));
  }
  return late_peak / early_peak;
}

}  // namespace

TEST_CASE(
    "The stiffness bound is where the delayed sampled spring turns unstable with the "
    "assumed damping",
    "[haptic][safety]") {
  const double mass = 0.95 / (0.58 * 0.15);
  const double period_s = 0.001;
  const double bound = stiffness_bound(mass, period_s);
  CHECK(bound == Approx(0.01778 * mass / (period_s * period_s)).epsilon(1e-3));
  // The damping the bound assumes: ζ_max of critical at K_max.
  const double damping = 2.0 * kMaxRequiredDampingRatio * std::sqrt(bound * mass);
  const double below = delayed_spring_growth(mass, damping, 0.8 * bound, period_s, 3.0);
  const double above = delayed_spring_growth(mass, damping, 1.25 * bound, period_s, 3.0);
  WARN("m = " << mass << " kg, T = 1 ms, K_max = " << bound << " N/m, b = " << damping
              << " N*s/m: amplitude after 3 s x" << below << " at 0.8 K_max, x" << above
              << " at 1.25 K_max");
  CHECK(below < 0.1);
  CHECK(above > 10.0);
  // With less damping than the bound assumes, even 0.8 K_max grows: the bound rests on it.
  CHECK(delayed_spring_growth(mass, 0.3 * damping, 0.8 * bound, period_s, 3.0) > 1.0);
}

TEST_CASE("Sets within their fit bounds that the loop cannot render are refused",
          "[haptic][safety]") {
  // The fit bounds are wider than what a 1 kHz loop on the HapticMaster can render: one value
  // at its bound is enough. (Measured one parameter at a time: docs/haptic-safety.md.)
  const DoorMapping mapping = hapticmaster_mapping();
  const double mass = mapping.inertia_on_device(0.95);
  struct Case {
    ModelKind kind;
    const char* name;
    double value;
    const char* slope;
  };
  const Case cases[] = {
      {ModelKind::kSensory, "k_inf", 20000.0, "-dtau/dtheta = 2.19e+04 N*m/rad"},
      {ModelKind::kSensory, "k_lock", 20000.0, "-dtau/dtheta = 2.2e+04 N*m/rad"},
      {ModelKind::kSensory, "k_stop", 100000.0, "-dtau/dtheta = 1e+05 N*m/rad"},
      {ModelKind::kPhysical, "e", 5e-05, "is 2.94e+05 N/m on the device"},
      {ModelKind::kPhysical, "alpha_c", 1.2, "is 4.7e+05 N/m on the device"},
  };
  for (const Case& c : cases) {
    const DoorModel reference = reference_model(c.kind);
    std::vector<double> values(reference.parameter_values().begin(),
                               reference.parameter_values().end());
    values[static_cast<std::size_t>(*reference.find_parameter(c.name))] = c.value;
    INFO(to_string(c.kind) << " " << c.name << " = " << c.value);
    const std::string message =
        check_parameter_values(reference, values, mapping, mass, 0.001, -0.02, 1.5908);
    CHECK_THAT(message, Contains(c.slope));
    CHECK_THAT(message, Contains("above the stability bound 1.94e+05 N/m"));
  }
  // β at its upper bound (20000 1/rad) only sharpens the edge at θ0; its peak restoring slope
  // stays near k + 1.1 k_inf, so β alone cannot make the sensory door too stiff.
  const DoorModel sensory_door = reference_model(ModelKind::kSensory);
  std::vector<double> values(sensory_door.parameter_values().begin(),
                             sensory_door.parameter_values().end());
  values[sensory::kBeta] = 20000.0;
  CHECK(check_parameter_values(sensory_door, values, mapping, mass, 0.001, -0.02, 1.5908).empty());
}
