// The recording family (fixtures/recording_family.h): drawn conditions give well-formed
// recordings (strokes, rates, directions, a rate that agrees with the angle), the draws
// cover the family's variety, and a recording is deterministic for its conditions and seed.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "analysis/model/parameter_file.h"
#include "core/percentile.h"
#include "fixtures/recording_family.h"

namespace {

using doorbench::PreparedData;
using doorbench::Stroke;
using doorbench::StrokeDirection;
using doorbench::testing::RecordingConditions;

// The rate integrated over the stroke (trapezoid), to compare with its angle change.
double integrated_rate_rad(const Stroke& stroke) {
  double angle = 0.0;
  for (std::size_t i = 1; i < stroke.size(); ++i) {
    angle += 0.5 * (stroke.omega_rad_s[i] + stroke.omega_rad_s[i - 1]) *
             (stroke.time_s[i] - stroke.time_s[i - 1]);
  }
  return angle;
}

void check_well_formed(const PreparedData& data, const RecordingConditions& c) {
  INFO(c.describe());
  std::string excluded;
  for (const doorbench::ExcludedSegment& e : data.excluded) excluded.append(e.reason).append("; ");
  INFO("excluded: " << excluded);
  REQUIRE(static_cast<int>(data.strokes.size()) == c.strokes);
  CHECK(data.sample_rate_hz == Approx(c.sample_rate_hz).epsilon(0.02));
  CHECK(data.rate_noise_rad_s > 0);
  CHECK(data.angle_noise_rad > 0);
  for (std::size_t k = 0; k < data.strokes.size(); ++k) {
    const Stroke& s = data.strokes[k];
    INFO("stroke " << s.id);
    CHECK(s.id == static_cast<int>(k) + 1);
    CHECK(s.direction == (s.id % 2 == 1 ? StrokeDirection::kOpening : StrokeDirection::kClosing));
    REQUIRE(s.size() > 10);
    CHECK(doorbench::median_interval_s(s.time_s) == Approx(1.0 / c.sample_rate_hz).epsilon(0.05));
    bool finite = true, increasing = true;
    for (std::size_t i = 0; i < s.size(); ++i) {
      finite = finite && std::isfinite(s.force_N[i]) && std::isfinite(s.theta_rad[i]) &&
               std::isfinite(s.omega_rad_s[i]);
      if (i > 0) increasing = increasing && s.time_s[i] > s.time_s[i - 1];
    }
    CHECK(finite);
    CHECK(increasing);
    const double moved = s.theta_rad.back() - s.theta_rad.front();
    CHECK(std::abs(moved) > 1.0 * doorbench::kRadPerDeg);
    CHECK((moved > 0) == (s.direction == StrokeDirection::kOpening));
    // The rate agrees with the angle: the integrated rate is the angle change within 5 %
    // of it and 2 mrad (the gyroscope's bias removed, the derivative's filter, an encoder's
    // counts).
    CHECK(std::abs(integrated_rate_rad(s) - moved) < 0.05 * std::abs(moved) + 2e-3);
  }
}

}  // namespace

TEST_CASE("recording family: 30 drawn recordings are well-formed and cover the family",
          "[recording_family]") {
  const doorbench::DoorModel truth = doorbench::reference_model(doorbench::ModelKind::kSensory);
  std::set<std::string> hands, sensors, tremors;
  std::set<double> rates;
  std::set<bool> latches, pauses, jittered;
  for (std::uint32_t draw = 0; draw < 30; ++draw) {
    const RecordingConditions c = doorbench::testing::draw_conditions(100 + draw);
    const PreparedData data = doorbench::testing::family_recording(truth, c, 5000 + draw);
    check_well_formed(data, c);
    hands.insert(c.hand);
    sensors.insert(c.sensors);
    rates.insert(c.sample_rate_hz);
    tremors.insert(c.tremor_force_N > 0
                       ? std::to_string(c.tremor_low_hz) + "-" + std::to_string(c.tremor_high_hz)
                       : "none");
    if (c.hand != "impulse") latches.insert(c.latch);
    if (c.hand != "impulse") pauses.insert(c.pause_s > 0);
    jittered.insert(data.jittered);
  }
  CHECK(hands == std::set<std::string>{"impulse", "minimum-jerk", "pd", "robot"});
  CHECK(sensors == std::set<std::string>{"angle", "encoder", "inclinometer+gyro"});
  CHECK(rates == std::set<double>{50.0, 100.0, 200.0, 500.0, 1000.0});
  CHECK(tremors.size() == 3);  // none, 1-8 Hz, 8-12 Hz
  CHECK(latches.size() == 2);
  CHECK(pauses.size() == 2);
  CHECK(jittered.size() == 2);
}

TEST_CASE(
    "recording family: a recording is deterministic for its conditions and seed, and "
    "unknown conditions are refused",
    "[recording_family]") {
  const doorbench::DoorModel truth = doorbench::reference_model(doorbench::ModelKind::kSensory);
  doorbench::testing::FamilyOptions options;
  options.strokes = 5;
  const RecordingConditions c = doorbench::testing::draw_conditions(7, options);
  CHECK(doorbench::testing::draw_conditions(7, options).describe() == c.describe());
  const PreparedData a = doorbench::testing::family_recording(truth, c, 1);
  const PreparedData b = doorbench::testing::family_recording(truth, c, 1);
  const PreparedData other = doorbench::testing::family_recording(truth, c, 2);
  REQUIRE(a.strokes.size() == 5);
  REQUIRE(b.strokes.size() == 5);
  CHECK(a.strokes.back().direction == StrokeDirection::kOpening);
  CHECK(a.strokes[2].theta_rad == b.strokes[2].theta_rad);
  CHECK(a.strokes[2].omega_rad_s == b.strokes[2].omega_rad_s);
  CHECK(a.strokes[2].theta_rad != other.strokes[2].theta_rad);

  RecordingConditions bad = c;
  bad.hand = "foot";
  CHECK_THROWS_WITH(doorbench::testing::family_recording(truth, bad, 1),
                    "recording family: unknown hand 'foot'");
  bad = c;
  bad.sensors = "radar";
  CHECK_THROWS_WITH(doorbench::testing::family_recording(truth, bad, 1),
                    "recording family: unknown sensors 'radar'");
  bad = c;
  bad.sample_rate_hz = 10.0;
  CHECK_THROWS_WITH(doorbench::testing::family_recording(truth, bad, 1),
                    "recording family: needs strokes >= 2, sample_rate_hz >= 20 and "
                    "jitter_fraction in [0, 0.5]");
}
