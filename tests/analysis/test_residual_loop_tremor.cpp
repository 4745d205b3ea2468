// The residual loop (docs/residual-loop.md) on recordings made by a different generator
// from the other loop tests': the tremor hand (tests/support/tremor_recording.h: 12 strokes, a
// softer grip that lets the push build up against the friction, 8–12 Hz tremor, rest kept
// before each stroke, the bench's noise). Breakaway friction, d_s − d1 = 1.5 N·m above the
// Coulomb level with w_s = 0.05 rad/s (issue 23), must be named first with its parameters
// within 3 standard uncertainties on three seeds, and nothing added on the clean recordings
// of the same seeds.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "analysis/parameter_file.h"
#include "analysis/residual_loop.h"
#include "tests/support/tremor_recording.h"

namespace {

using doorbench::DoorModel;
using doorbench::LoopResult;
using doorbench::ModelKind;
namespace effects = doorbench::effects;

constexpr double kBreakaway_N_m = 1.5;  // d_s − d1
constexpr double kBreakawaySpeed_rad_s = 0.05;

DoorModel sensory_reference() { return doorbench::reference_model(ModelKind::kSensory); }

double reference_d1() {
  const DoorModel model = sensory_reference();
  return model.parameter_values()[*model.find_parameter("d1")];
}

DoorModel with_breakaway() {
  doorbench::EffectSetting setting{effects::Kind::kStribeck,
                                   {reference_d1() + kBreakaway_N_m, kBreakawaySpeed_rad_s},
                                   {}};
  for (const effects::EffectParameter& parameter : effects::info(effects::Kind::kStribeck).parameters) {
    setting.bounds.push_back(parameter.default_bounds);
  }
  return sensory_reference().with_effect(std::move(setting));
}

doorbench::PreparedData tremor_data(const DoorModel& truth, std::uint32_t seed) {
  doorbench::testing::TremorRecordingOptions options;
  options.seed = seed;
  return doorbench::testing::tremor_recording(truth, options);
}

const doorbench::FittedParameter* find(const doorbench::LoopStep& step, const std::string& name) {
  for (const doorbench::FittedParameter& p : step.parameters) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

void check_within_3u(const doorbench::FittedParameter* p, double truth) {
  REQUIRE(p != nullptr);
  INFO(p->name << " = " << p->value << " +- " << p->uncertainty << ", truth " << truth);
  REQUIRE(p->free);
  REQUIRE(std::isfinite(p->uncertainty));
  REQUIRE(p->uncertainty > 0);
  CHECK(std::abs(p->value - truth) <= 3.0 * p->uncertainty);
}

}  // namespace

TEST_CASE("residual loop: names breakaway friction first on tremor-hand recordings, and "
          "adds nothing to the clean recordings of the same seeds",
          "[residual_loop][tremor]") {
  const std::uint32_t seed = GENERATE(1u, 2u, 3u);
  INFO("seed " << seed);

  const LoopResult clean =
      doorbench::run_residual_loop(sensory_reference(), tremor_data(sensory_reference(), seed));
  {
    INFO(clean.full_report());
    CHECK(clean.steps.empty());
    // The second look must not promote noise either: every screened candidate stays below z 4.
    for (const doorbench::CandidateEvidence& candidate : clean.last_candidates) {
      if (candidate.screened) CHECK(candidate.screen_score_z < clean.options.min_score_z);
    }
  }

  const doorbench::PreparedData data = tremor_data(with_breakaway(), seed);
  REQUIRE(data.strokes.size() == 12);
  const LoopResult loop = doorbench::run_residual_loop(sensory_reference(), data);
  INFO(loop.full_report());
  REQUIRE_FALSE(loop.steps.empty());
  const doorbench::LoopStep& step = loop.steps.front();
  CHECK(step.effect == effects::Kind::kStribeck);
  CHECK(step.rank == 1);
  CHECK(step.after.held_out_rmse_rad_s < step.before.held_out_rmse_rad_s);
  CHECK(step.after.bic < step.before.bic);
  check_within_3u(find(step, "stribeck.d_s"), reference_d1() + kBreakaway_N_m);
  check_within_3u(find(step, "stribeck.w_s"), kBreakawaySpeed_rad_s);
  CHECK(loop.steps.size() == 1);  // nothing else: the rest is noise

  // The speed-resolved residual shows where: between 0.01 and 0.05 rad/s the start fit's
  // residual is above the clean recording's (measured 2.7x, 2.0x and 1.47x on seeds 1-3).
  REQUIRE(step.speed_bands.size() == clean.last_speed_bands.size());
  REQUIRE(step.speed_bands.size() >= 2);
  const doorbench::SpeedBand& slow = step.speed_bands[1];
  const doorbench::SpeedBand& slow_clean = clean.last_speed_bands[1];
  INFO("0.01-0.05 rad/s: " << slow.rms_rad_s << " against " << slow_clean.rms_rad_s << " clean");
  CHECK(slow.low_rad_s == 0.01);
  CHECK(slow.samples > 500);
  CHECK(slow.rms_rad_s > 1.25 * slow_clean.rms_rad_s);
}

// Issue 23, the structure check: the physical reference door recorded by the tremor hand
// and fitted with the sensory model. No catalogue effect closes the gap the missing weight
// and spring leave, so the loop must end with the structure check naming the physical
// model the better structure, with both held-out errors; on the clean sensory recording the
// held-out error is at the noise floor and the check does not run.
TEST_CASE(
    "residual loop: the structure check names the physical model on a physical door "
    "fitted with the sensory model",
    "[residual_loop][tremor][slow]") {
  const doorbench::PreparedData data =
      tremor_data(doorbench::reference_model(ModelKind::kPhysical), 1);
  const LoopResult loop = doorbench::run_residual_loop(sensory_reference(), data);
  INFO(loop.full_report());
  const doorbench::StructureCheck& check = loop.structure;
  REQUIRE(check.ran);
  REQUIRE(check.other_fit.has_value());
  CHECK(check.current_kind == ModelKind::kSensory);
  CHECK(check.other_kind == ModelKind::kPhysical);
  CHECK(check.other_better);
  CHECK(check.other.held_out_rmse_rad_s < check.current.held_out_rmse_rad_s);
  CHECK(check.bic_change < 0);
  CHECK(check.current.held_out_rmse_rad_s >
        loop.options.structure_noise_ratio * check.noise_floor_rad_s);
  CHECK(check.best_explained_fraction < loop.options.structure_max_explained_fraction);
  CHECK(check.verdict.find("the physical model is the better structure") == 0);
  CHECK(loop.brief_report().find("Structure check: the physical model is the better structure") !=
        std::string::npos);
}

TEST_CASE("residual loop: the structure check does not run at the noise floor",
          "[residual_loop][tremor]") {
  const LoopResult clean =
      doorbench::run_residual_loop(sensory_reference(), tremor_data(sensory_reference(), 1));
  INFO(clean.full_report());
  CHECK_FALSE(clean.structure.ran);
  CHECK_FALSE(clean.structure.other_fit.has_value());
  CHECK(clean.structure.noise_floor_rad_s > 0);
  // The floor is what a right model leaves: the clean held-out RMSE is near it (2.1 times
  // on seed 1; the physical door's loop ends at 16.6 times).
  const double held_out = doorbench::model_figures(clean.final_fit.summary).held_out_rmse_rad_s;
  CHECK(held_out < 3.0 * clean.structure.noise_floor_rad_s);
  CHECK(held_out > 0.5 * clean.structure.noise_floor_rad_s);
  CHECK(clean.structure.reason.find("times the noise floor") != std::string::npos);
}

// The other catalogue effects on a tremor-hand recording (seed 1), each at the size of
// tests/test_residual_loop.cpp's plain-hand case: named first, its amplitude within 3
// standard uncertainties, nothing else added. Not here: the soft-close damper of the
// plain-hand case (b_sc = 5 N·m·s/rad from 0.15 rad) is not found on this recording (the
// start fit's held-out RMSE is 0.143 rad/s and no candidate is worth a refit; issue 23's
// follow-up), nor the end stop at 1.2 rad and the inertia error, which need the plain
// hand's strokes (tests/test_residual_loop.cpp).
TEST_CASE("residual loop: names each catalogue effect first on a tremor-hand recording",
          "[residual_loop][tremor][slow]") {
  struct Case {
    effects::Kind kind;
    std::vector<double> values;
    std::string amplitude;
  };
  const Case c = GENERATE(Case{effects::Kind::kViscousDamping, {0.5}, "viscous_damping.b"},
                          Case{effects::Kind::kGravityImbalance, {3.0}, "gravity_imbalance.g1"},
                          Case{effects::Kind::kForceOffset, {3.0}, "force_offset.F_off"},
                          Case{effects::Kind::kDirectionFriction, {1.5}, "direction_friction.d_dir"});
  INFO(c.amplitude);
  doorbench::EffectSetting setting{c.kind, c.values, {}};
  for (const effects::EffectParameter& parameter : effects::info(c.kind).parameters) {
    setting.bounds.push_back(parameter.default_bounds);
  }
  const LoopResult loop = doorbench::run_residual_loop(
      sensory_reference(), tremor_data(sensory_reference().with_effect(setting), 1));
  INFO(loop.full_report());
  REQUIRE_FALSE(loop.steps.empty());
  const doorbench::LoopStep& step = loop.steps.front();
  CHECK(step.effect == c.kind);
  CHECK(step.after.held_out_rmse_rad_s < step.before.held_out_rmse_rad_s);
  CHECK(step.after.bic < step.before.bic);
  check_within_3u(find(step, c.amplitude), c.values.front());
  CHECK(loop.steps.size() == 1);
  CHECK_FALSE(loop.structure.ran);
}
