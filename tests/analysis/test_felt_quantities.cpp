// Felt quantities of a model (virtual hand) and of recordings, and the check compare_feel.
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "analysis/design/felt_quantities.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/physical_model.h"
#include "analysis/simulation/fit_synthetic.h"
#include "analysis/simulation/run_summary.h"

using Catch::Matchers::Contains;
using Catch::Matchers::Equals;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::DoorModel;
using doorbench::FeltOptions;
using doorbench::FeltQuantities;
using doorbench::ModelKind;
using doorbench::PreparedData;

namespace {

DoorModel with_value(const DoorModel& model, const char* name, double factor) {
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  values.at(static_cast<std::size_t>(*model.find_parameter(name))) *= factor;
  return model.with_parameter_values(values);
}

const doorbench::FeltQuantityError& error_of(const doorbench::FeelCheck& check,
                                             const std::string& name) {
  for (const auto& e : check.errors) {
    if (e.name == name) return e;
  }
  throw std::runtime_error("no error for " + name);
}

}  // namespace

// The standard run ends at its last stroke sample (what follows is read by no quantity): the
// quantities are those of the whole run's strokes.
TEST_CASE("the standard run's quantities are the whole run's", "[felt]") {
  const DoorModel door = doorbench::reference_model(ModelKind::kPhysical);
  const FeltOptions options;
  const doorbench::VirtualHand hand(options.hand, door.geometry().handle_radius_m);
  std::vector<double> times;
  for (int i = 0; i <= 10000; ++i) times.push_back(i / 1000.0);
  const doorbench::Trajectory run = doorbench::simulate(door, hand, doorbench::DoorState{}, times);
  PreparedData whole;
  whole.handle_radius_m = door.geometry().handle_radius_m;
  for (const int marker : {1, 2}) {
    doorbench::Stroke stroke;
    stroke.id = marker;
    stroke.direction =
        marker == 1 ? doorbench::StrokeDirection::kOpening : doorbench::StrokeDirection::kClosing;
    for (std::size_t i = 0; i < times.size(); ++i) {
      if (hand.stroke_at(times[i]) != marker) continue;
      stroke.time_s.push_back(times[i]);
      stroke.force_N.push_back(run.force_N[i]);
      stroke.theta_rad.push_back(run.theta_rad[i]);
      stroke.omega_rad_s.push_back(run.omega_rad_s[i]);
    }
    whole.strokes.push_back(std::move(stroke));
  }
  const PreparedData standard = doorbench::virtual_hand_strokes(door, options);
  REQUIRE(standard.strokes.size() == 2);
  for (std::size_t s = 0; s < 2; ++s) {
    CHECK(standard.strokes[s].time_s == whole.strokes[s].time_s);
    CHECK(standard.strokes[s].force_N == whole.strokes[s].force_N);
    CHECK(standard.strokes[s].theta_rad == whole.strokes[s].theta_rad);
  }
}

TEST_CASE("Felt quantities of the reference physical door", "[felt]") {
  const DoorModel door = doorbench::reference_model(ModelKind::kPhysical);
  const FeltOptions options;
  const PreparedData strokes = doorbench::virtual_hand_strokes(door, options);
  REQUIRE(strokes.strokes.size() == 2);
  const FeltQuantities felt = doorbench::felt_quantities(door, options);
  INFO(felt.brief_report());

  // The mechanism's own peaks of the same run (run_summary: τ_m without the stops): the hand
  // force near closed differs by the door's inertia and the hand's tracking only.
  doorbench::Trajectory run;
  {
    const doorbench::VirtualHand hand(options.hand, door.geometry().handle_radius_m);
    std::vector<double> times;
    for (int i = 0; i <= 10000; ++i) times.push_back(i / 1000.0);
    run = doorbench::simulate(door, hand, doorbench::DoorState{}, times);
  }
  const doorbench::RunSummary summary = doorbench::summarize_run(door, run);
  WARN("felt: " << felt.brief_report() << "run summary:\n" << doorbench::format_summary(summary));
  CHECK_THAT(felt.peak_unlatch_force_N, WithinRel(summary.peak_unlatch_force_N, 0.10));
  CHECK_THAT(felt.peak_latch_force_N, WithinRel(summary.peak_latch_force_N, 0.25));
  CHECK(felt.unlatch_angle_rad > 0.0);
  CHECK(felt.unlatch_angle_rad < 0.1);
  // The demo's summary of this door (docs/simulator.md): unlatching takes tens of N.
  CHECK(felt.peak_unlatch_force_N > 10.0);
  CHECK(felt.peak_unlatch_force_N < 100.0);

  // Friction: hinge T_h plus the guide's, at the handle; the summary's median of the terms.
  CHECK_THAT(felt.free_movement_friction_N, WithinRel(summary.free_movement_friction_N, 0.25));
  CHECK(felt.friction_near_closed_N > 0.0);
  CHECK(felt.friction_open_N > 0.0);

  // Balance: the static holding force −τ_m(45°, 0) / r_h (friction is 0 at ω = 0).
  const double r_h = door.geometry().handle_radius_m;
  const double holding_N = -door.torque_Nm(options.balance_angle_rad, 0.0) / r_h;
  WARN("static holding force at 45 deg " << holding_N << " N, felt " << felt.balance_force_N);
  CHECK_THAT(felt.balance_force_N, WithinAbs(holding_N, 0.1 * std::abs(holding_N) + 0.5));
}

TEST_CASE("Felt quantities: a heavier door falls open harder, a stiffer catch unlatches harder",
          "[felt]") {
  const DoorModel door = doorbench::reference_model(ModelKind::kPhysical);
  const FeltQuantities base = doorbench::felt_quantities(door);
  const FeltQuantities heavy = doorbench::felt_quantities(with_value(door, "m_d", 1.3));
  const FeltQuantities catchy = doorbench::felt_quantities(with_value(door, "F_l0", 1.5));
  const FeltQuantities rough = doorbench::felt_quantities(with_value(door, "T_h", 2.0));
  // Gravity opens the door (positive torque): more of it, a more negative holding force.
  CHECK(heavy.balance_force_N < base.balance_force_N - 1.0);
  CHECK(catchy.peak_unlatch_force_N > base.peak_unlatch_force_N * 1.05);
  CHECK(rough.free_movement_friction_N > base.free_movement_friction_N + 0.5 / 0.58);
}

TEST_CASE("compare_feel: a model against its own synthetic recording and a changed one", "[felt]") {
  const DoorModel door = doorbench::reference_model(ModelKind::kPhysical);
  doorbench::SyntheticStrokeOptions synthetic;
  synthetic.runs = {{1.0, 4.0}, {1.3, 5.0}};
  const std::vector<PreparedData> recordings = {doorbench::synthetic_strokes(door, synthetic)};

  const doorbench::FeelCheck same = doorbench::compare_feel(door, recordings);
  WARN("same model:\n" << same.brief_report());
  CHECK(same.bins_compared > 40);
  CHECK(same.curve_rms_error_N < 0.5);
  for (const auto& e : same.errors) {
    INFO(e.name);
    CHECK(std::abs(e.error) < 0.5);
  }

  // A latch catch preloaded 50 % more: the check sees it in the unlatching peak.
  const DoorModel changed = with_value(door, "F_l0", 1.5);
  const doorbench::FeelCheck other = doorbench::compare_feel(changed, recordings);
  WARN("changed model:\n" << other.brief_report());
  CHECK(error_of(other, "peak_unlatch_force_N").error_percent > 10.0);
  CHECK(other.curve_rms_error_N > 3.0 * same.curve_rms_error_N);
  // Doubled hinge friction: the friction errors, not the balance.
  const doorbench::FeelCheck rough =
      doorbench::compare_feel(with_value(door, "T_h", 2.0), recordings);
  CHECK_THAT(error_of(rough, "free_movement_friction_N").error, WithinRel(0.6 / 0.58, 0.2));
  CHECK(std::abs(error_of(rough, "balance_force_N").error) < 0.3);
}

TEST_CASE("Felt quantities: bad input is named", "[felt]") {
  const DoorModel door = doorbench::reference_model(ModelKind::kPhysical);
  FeltOptions bad;
  bad.near_closed_end_rad = 0.05;
  CHECK_THAT(bad.validate(), Equals("felt near_closed_end_rad must be > latch_zone_rad"));
  CHECK_THROWS_WITH(doorbench::felt_quantities(door, bad),
                    Equals("felt near_closed_end_rad must be > latch_zone_rad"));
  FeltOptions no_bins;
  no_bins.bin_width_rad = 0;
  CHECK_THAT(no_bins.validate(), Equals("felt bin_width_rad must be > 0"));
  CHECK_THROWS_WITH(doorbench::compare_feel(door, std::vector<PreparedData>{}),
                    Equals("compare_feel: no recordings"));
  PreparedData empty;
  empty.source = "empty.h5";
  CHECK_THROWS_WITH(doorbench::compare_feel(door, std::vector<PreparedData>{empty}),
                    Equals("compare_feel: no strokes in empty.h5"));
  CHECK_THROWS_WITH(doorbench::felt_from_strokes(std::vector<PreparedData>{empty}, 1.57),
                    Equals("felt quantities: no strokes"));
}
