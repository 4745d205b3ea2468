// The perceptual controls of door-models.md §2 (analysis/model/perceptual_controls.h): each
// control read on the reference sensory door against its hand-computed value, set and
// read back, the parameters it must keep, the settings it must refuse, and what a
// control change does to the felt door in a simulated run.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "analysis/model/sensory_model.h"
#include "analysis/simulation/run_summary.h"
#include "analysis/simulation/simulator.h"
#include "analysis/simulation/virtual_hand.h"

using Catch::Matchers::Contains;
using Catch::Matchers::Equals;
using Catch::Matchers::StartsWith;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::DoorModel;
using doorbench::ModelKind;
using doorbench::perceptual::Control;
namespace perceptual = doorbench::perceptual;
namespace sensory = doorbench::sensory;

namespace {

// reference-door.json, sensory section, written out.
constexpr double kJ = 0.95, kK = 40.0, kKInf = 1054.0, kKLock = 767.0, kTheta0 = 0.00698,
                 kTheta1 = 0.02793, kTheta2 = 0.0384, kTheta3 = 0.06109, kC = 3.0, kD1 = 2.6,
                 kD2 = 1.3, kTheta4 = 0.6109, kRh = 0.58;

const DoorModel& controls_reference() {
  static const DoorModel model = doorbench::reference_model(ModelKind::kSensory);
  return model;
}

double value_of(const DoorModel& model, int index) {
  return model.parameter_values()[index];
}

// Every parameter not in `changed` is exactly as in `before`.
void check_others_unchanged(const DoorModel& before, const DoorModel& after,
                            std::set<int> changed) {
  REQUIRE(before.parameter_count() == after.parameter_count());
  for (int i = 0; i < before.parameter_count(); ++i) {
    if (changed.count(i) != 0) continue;
    INFO("parameter " << before.parameter_name(i));
    CHECK(after.parameter_values()[i] == before.parameter_values()[i]);
  }
}

std::string throw_message(auto&& action) {
  try {
    action();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no std::invalid_argument thrown)";
}

doorbench::RunSummary hand_summary(const DoorModel& model) {
  const doorbench::VirtualHand hand(doorbench::VirtualHandOptions{},
                                    model.geometry().handle_radius_m);
  std::vector<double> times(10001);
  for (std::size_t i = 0; i < times.size(); ++i) times[i] = static_cast<double>(i) / 1000.0;
  const doorbench::Trajectory run = doorbench::simulate(model, hand, doorbench::DoorState{}, times);
  return doorbench::summarize_run(model, run);
}

}  // namespace

TEST_CASE("Perceptual controls: the catalogue", "[perceptual]") {
  const auto all = perceptual::controls();
  REQUIRE(all.size() == 7);
  const std::vector<std::string> names = {"heaviness",      "latch_effort", "closing_effort",
                                          "snap",           "smoothness",   "friction_balance",
                                          "friction_change"};
  for (std::size_t i = 0; i < all.size(); ++i) {
    CHECK(std::string(all[i].name) == names[i]);
    REQUIRE(perceptual::find(names[i]).has_value());
    CHECK(*perceptual::find(names[i]) == all[i].control);
    CHECK_FALSE(all[i].unit.empty());
    CHECK_FALSE(all[i].meaning.empty());
  }
  CHECK(std::string(all[1].unit) == "N");
  CHECK_FALSE(perceptual::find("latch").has_value());
  CHECK_FALSE(perceptual::find("").has_value());
}

TEST_CASE("Perceptual controls: reading the reference door", "[perceptual]") {
  const DoorModel& door = controls_reference();
  CHECK(perceptual::read(door, Control::kHeaviness) == kJ);
  CHECK_THAT(perceptual::read(door, Control::kLatchEffort),
             WithinRel((40 * 0.02793 + 1054 * (0.02793 - 0.00698)) / 0.58, 1e-12));
  CHECK_THAT(perceptual::read(door, Control::kLatchEffort), WithinAbs(40.0, 0.1));
  CHECK_THAT(perceptual::read(door, Control::kClosingEffort),
             WithinRel(767 * (0.06109 - 0.0384) / 0.58, 1e-12));
  CHECK_THAT(perceptual::read(door, Control::kSnap), WithinRel(3.0 * (0.0384 - 0.02793), 1e-12));
  CHECK_THAT(perceptual::read(door, Control::kSmoothness), WithinRel(2.6 / 0.58, 1e-12));
  CHECK_THAT(perceptual::read(door, Control::kFrictionBalance), WithinRel(0.5, 1e-12));
  CHECK(perceptual::read(door, Control::kFrictionChange) == kTheta4);
  CHECK_THAT(perceptual::snap_width_rad(door), WithinRel(0.0384 - 0.02793, 1e-12));
  // The latch-effort control is the spec's approximate peak force to unlatch.
  std::array<double, sensory::kParameterCount> values{};
  std::copy(door.parameter_values().begin(), door.parameter_values().end(), values.begin());
  CHECK_THAT(perceptual::read(door, Control::kLatchEffort),
             WithinRel(sensory::peak_unlatch_force_N(values, door.geometry()), 1e-12));
  CHECK_THAT(perceptual::read(door, Control::kClosingEffort),
             WithinRel(sensory::peak_latch_force_N(values, door.geometry()), 1e-12));
}

TEST_CASE("Perceptual controls: setting each control and reading it back", "[perceptual]") {
  const DoorModel& door = controls_reference();

  SECTION("heaviness sets J only") {
    const DoorModel changed = perceptual::set(door, Control::kHeaviness, 1.4);
    CHECK(perceptual::read(changed, Control::kHeaviness) == 1.4);
    CHECK(changed.inertia_kg_m2() == 1.4);
    check_others_unchanged(door, changed, {sensory::kJ});
  }
  SECTION("latch effort sets k_inf, keeping theta0 and theta1 (and k)") {
    const DoorModel changed = perceptual::set(door, Control::kLatchEffort, 30.0);
    CHECK_THAT(perceptual::read(changed, Control::kLatchEffort), WithinRel(30.0, 1e-12));
    CHECK_THAT(value_of(changed, sensory::kKInf),
               WithinRel((30.0 * kRh - kK * kTheta1) / (kTheta1 - kTheta0), 1e-12));
    CHECK(value_of(changed, sensory::kTheta0) == kTheta0);
    CHECK(value_of(changed, sensory::kTheta1) == kTheta1);
    CHECK(value_of(changed, sensory::kK) == kK);
    check_others_unchanged(door, changed, {sensory::kKInf});
    // Exactly the soft spring's share is allowed: k_inf = 0.
    const double soft_share = kK * kTheta1 / kRh;
    const DoorModel soft = perceptual::set(door, Control::kLatchEffort, soft_share);
    CHECK_THAT(value_of(soft, sensory::kKInf), WithinAbs(0.0, 1e-9));
  }
  SECTION("closing effort sets k_lock only") {
    const DoorModel changed = perceptual::set(door, Control::kClosingEffort, 25.0);
    CHECK_THAT(perceptual::read(changed, Control::kClosingEffort), WithinRel(25.0, 1e-12));
    CHECK_THAT(value_of(changed, sensory::kKLock),
               WithinRel(25.0 * kRh / (kTheta3 - kTheta2), 1e-12));
    check_others_unchanged(door, changed, {sensory::kKLock});
  }
  SECTION("snap sets c, keeping the width; set_snap_width moves theta2, keeping c") {
    const DoorModel changed = perceptual::set(door, Control::kSnap, 0.05);
    CHECK_THAT(perceptual::read(changed, Control::kSnap), WithinRel(0.05, 1e-12));
    CHECK_THAT(value_of(changed, sensory::kC), WithinRel(0.05 / (kTheta2 - kTheta1), 1e-12));
    CHECK(perceptual::snap_width_rad(changed) == perceptual::snap_width_rad(door));
    check_others_unchanged(door, changed, {sensory::kC});

    const DoorModel wider = perceptual::set_snap_width(door, 0.015);
    CHECK_THAT(perceptual::snap_width_rad(wider), WithinAbs(0.015, 1e-15));
    CHECK_THAT(value_of(wider, sensory::kTheta2), WithinAbs(kTheta1 + 0.015, 1e-15));
    CHECK(value_of(wider, sensory::kC) == kC);
    CHECK_THAT(perceptual::read(wider, Control::kSnap), WithinRel(kC * 0.015, 1e-12));
    check_others_unchanged(door, wider, {sensory::kTheta2});
  }
  SECTION("smoothness sets d1 and d2, keeping d2/d1") {
    const DoorModel changed = perceptual::set(door, Control::kSmoothness, 6.0);
    CHECK_THAT(perceptual::read(changed, Control::kSmoothness), WithinRel(6.0, 1e-12));
    CHECK_THAT(value_of(changed, sensory::kD1), WithinRel(6.0 * kRh, 1e-12));
    CHECK_THAT(value_of(changed, sensory::kD2), WithinRel(6.0 * kRh * kD2 / kD1, 1e-12));
    CHECK_THAT(perceptual::read(changed, Control::kFrictionBalance), WithinRel(kD2 / kD1, 1e-12));
    check_others_unchanged(door, changed, {sensory::kD1, sensory::kD2});
    // No friction at all is a valid setting, and the balance then reads 0.
    const DoorModel frictionless = perceptual::set(door, Control::kSmoothness, 0.0);
    CHECK(value_of(frictionless, sensory::kD1) == 0.0);
    CHECK(value_of(frictionless, sensory::kD2) == 0.0);
    CHECK(perceptual::read(frictionless, Control::kFrictionBalance) == 0.0);
  }
  SECTION("friction balance sets d2, keeping d1") {
    const DoorModel changed = perceptual::set(door, Control::kFrictionBalance, 0.2);
    CHECK_THAT(perceptual::read(changed, Control::kFrictionBalance), WithinRel(0.2, 1e-12));
    CHECK_THAT(value_of(changed, sensory::kD2), WithinRel(0.2 * kD1, 1e-12));
    CHECK(value_of(changed, sensory::kD1) == kD1);
    CHECK_THAT(perceptual::read(changed, Control::kSmoothness), WithinRel(kD1 / kRh, 1e-12));
    check_others_unchanged(door, changed, {sensory::kD2});
    // Both ends of [0, 1] are allowed.
    CHECK(value_of(perceptual::set(door, Control::kFrictionBalance, 0.0), sensory::kD2) == 0.0);
    CHECK(value_of(perceptual::set(door, Control::kFrictionBalance, 1.0), sensory::kD2) == kD1);
  }
  SECTION("friction change sets theta4 only") {
    const DoorModel changed = perceptual::set(door, Control::kFrictionChange, 0.4);
    CHECK(perceptual::read(changed, Control::kFrictionChange) == 0.4);
    check_others_unchanged(door, changed, {sensory::kTheta4});
  }
  // Setting never changes the door's geometry or its bounds.
  const DoorModel changed = perceptual::set(door, Control::kHeaviness, 2.0);
  CHECK(changed.geometry().handle_radius_m == kRh);
  CHECK(changed.kind() == ModelKind::kSensory);
  CHECK(changed.parameter_bounds()[sensory::kJ].upper ==
        door.parameter_bounds()[sensory::kJ].upper);
}

TEST_CASE("Perceptual controls: impossible settings are refused with a reason", "[perceptual]") {
  const DoorModel& door = controls_reference();
  // Below what the soft spring alone gives: k θ1 / r_h ≈ 1.926 N.
  const std::string latch =
      throw_message([&] { perceptual::set(door, Control::kLatchEffort, 1.0); });
  CHECK_THAT(latch, StartsWith("latch_effort 1 N is below what the soft spring alone gives, "
                               "k theta1 / r_h = 1.92"));
  CHECK_THAT(latch, Contains(" N"));
  CHECK_THROWS_AS(perceptual::set(door, Control::kLatchEffort, -5.0), std::invalid_argument);

  CHECK_THROWS_WITH(perceptual::set(door, Control::kFrictionBalance, 1.5),
                    Equals("friction_balance 1.5 is outside [0, 1] (d2 / d1 with d1 >= d2 >= 0)"));
  CHECK_THROWS_WITH(
      perceptual::set(door, Control::kFrictionBalance, -0.25),
      Equals("friction_balance -0.25 is outside [0, 1] (d2 / d1 with d1 >= d2 >= 0)"));

  // Values that break a constraint of the model: the model's own message.
  CHECK_THROWS_WITH(perceptual::set(door, Control::kHeaviness, 0.0),
                    Equals("sensory parameter J = 0 breaks J > 0"));
  CHECK_THROWS_WITH(perceptual::set(door, Control::kFrictionChange, 2.0),
                    Equals("sensory parameter theta4 = 2 breaks 0 < theta4 < theta_max "
                           "(theta_max = 1.5708)"));
  CHECK_THROWS_WITH(perceptual::set(door, Control::kFrictionChange, 0.0),
                    Equals("sensory parameter theta4 = 0 breaks 0 < theta4 < theta_max"));
  CHECK_THAT(throw_message([&] { perceptual::set(door, Control::kClosingEffort, -10.0); }),
             StartsWith("sensory parameter k_lock = -") && Contains("breaks k_lock >= 0"));
  CHECK_THAT(throw_message([&] { perceptual::set(door, Control::kSnap, -0.01); }),
             StartsWith("sensory parameter c = -") && Contains("breaks c >= 0"));
  CHECK_THAT(throw_message([&] { perceptual::set(door, Control::kSmoothness, -1.0); }),
             Contains("breaks d1 >= d2 >= 0"));
  CHECK_THAT(throw_message([&] { perceptual::set_snap_width(door, 0.05); }),
             StartsWith("sensory parameter theta2 = ") &&
                 Contains("breaks theta2 < theta3 (theta3 = 0.06109)"));
  CHECK_THAT(throw_message([&] { perceptual::set_snap_width(door, -0.001); }),
             StartsWith("sensory parameter theta1 = 0.02793 breaks theta1 < theta2"));
  CHECK_THROWS_WITH(perceptual::set(door, Control::kHeaviness, std::nan("")),
                    Equals("heaviness must be a finite number"));
  CHECK_THROWS_WITH(perceptual::set(door, Control::kSmoothness, INFINITY),
                    Equals("smoothness must be a finite number"));
}

TEST_CASE("Perceptual controls: the physical model is refused", "[perceptual]") {
  const DoorModel physical = doorbench::reference_model(ModelKind::kPhysical);
  const std::string message = "perceptual controls act on the sensory model only";
  for (const perceptual::ControlInfo& info : perceptual::controls()) {
    INFO(info.name);
    CHECK_THROWS_WITH(perceptual::read(physical, info.control), Equals(message));
    CHECK_THROWS_WITH(perceptual::set(physical, info.control, 1.0), Equals(message));
  }
  CHECK_THROWS_WITH(perceptual::snap_width_rad(physical), Equals(message));
  CHECK_THROWS_WITH(perceptual::set_snap_width(physical, 0.01), Equals(message));
}

TEST_CASE("Perceptual controls: 30% less latch effort is felt as about 30% less",
          "[perceptual][simulation]") {
  const DoorModel& door = controls_reference();
  const double effort = perceptual::read(door, Control::kLatchEffort);
  const DoorModel lighter = perceptual::set(door, Control::kLatchEffort, 0.7 * effort);
  const doorbench::RunSummary before = hand_summary(door);
  const doorbench::RunSummary after = hand_summary(lighter);
  const double drop = 1.0 - after.peak_unlatch_force_N / before.peak_unlatch_force_N;
  WARN("peak unlatch force " << before.peak_unlatch_force_N << " N -> "
                             << after.peak_unlatch_force_N << " N: a drop of " << 100 * drop
                             << "%");
  REQUIRE(before.peak_unlatch_force_N > 30.0);
  CHECK(drop > 0.20);
  CHECK(drop < 0.40);
  // Only the latch changed: closing effort and friction are felt as before.
  CHECK_THAT(after.peak_latch_force_N, WithinRel(before.peak_latch_force_N, 0.05));
  CHECK_THAT(after.free_movement_friction_N, WithinRel(before.free_movement_friction_N, 0.05));
}
