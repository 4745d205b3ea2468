// The residual loop (docs/residual-loop.md) on recordings made by a different generator
// from the other loop tests': the tremor hand (fixtures/tremor_recording.h: 12 strokes, a
// softer grip that lets the push build up against the friction, 8–12 Hz tremor, rest kept
// before each stroke, the bench's noise). Breakaway friction, d_s − d1 = 1.5 N·m above the
// Coulomb level with w_s = 0.05 rad/s, must be named first with its parameters
// within 3 standard uncertainties on three seeds, and nothing added on the clean recordings
// of the same seeds. Every other catalogue effect is named first on seed 1 (the soft close,
// the end stop and the inertia error on seeds 2 and 3 too), and a physical door fitted with
// the sensory model ends with the structure check naming the physical model.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "analysis/loop/residual_loop.h"
#include "analysis/model/parameter_file.h"
#include "fixtures/reference_doors.h"
#include "fixtures/tremor_recording.h"
#include "tests/support/nested_refits.h"

namespace {

using doorbench::DoorModel;
using doorbench::LoopResult;
using doorbench::ModelKind;
namespace effects = doorbench::effects;

constexpr double kBreakaway_N_m = 1.5;  // d_s − d1
constexpr double kBreakawaySpeed_rad_s = 0.05;

using doorbench::testing::sensory_reference;

double reference_d1() {
  return doorbench::testing::sensory_reference_d1();
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

TEST_CASE(
    "residual loop: names breakaway friction first on tremor-hand recordings, and "
    "adds nothing to the clean recordings of the same seeds",
    "[residual_loop][tremor]") {
  const std::uint32_t seed = GENERATE(1u, 2u, 3u);
  INFO("seed " << seed);

  const LoopResult clean =
      doorbench::run_residual_loop(sensory_reference(), tremor_data(sensory_reference(), seed));
  {
    INFO(clean.full_report());
    doorbench::testing::check_nested_refits(clean);
    CHECK(clean.steps.empty());
    // The second look must not promote noise either: every screened candidate stays below z 4.
    for (const doorbench::CandidateEvidence& candidate : clean.last_candidates) {
      if (candidate.screened) CHECK(candidate.screen_score_z < clean.options.min_score_z);
    }
  }

  const doorbench::PreparedData data = tremor_data(
      doorbench::testing::sensory_reference_with_breakaway(kBreakaway_N_m, kBreakawaySpeed_rad_s),
      seed);
  REQUIRE(data.strokes.size() == 12);
  const LoopResult loop = doorbench::run_residual_loop(sensory_reference(), data);
  INFO(loop.full_report());
  CHECK(doorbench::testing::check_nested_refits(loop) >= 1);
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

namespace {

// No effect of a physical door fitted with the sensory model may stay once the loop has the
// physical model, and none with a free parameter at a bound or undetermined is ever added.
void check_ends_physical_without_spurious_effects(const LoopResult& loop) {
  CHECK(loop.model().kind() == ModelKind::kPhysical);
  CHECK(loop.model().effects().empty());
  for (const doorbench::LoopStep& step : loop.steps) {
    for (const doorbench::FittedParameter& p : step.parameters) {
      INFO("step " << step.number << ": " << p.name);
      if (p.free) CHECK_FALSE(p.at_bound);
      if (p.free) CHECK(p.determined);
    }
  }
}

}  // namespace

// The structure check, family before stacking: the physical reference
// door recorded by the tremor hand and fitted with the sensory model. No catalogue effect
// closes the gap the missing weight and spring leave (the best refit, a force offset, lowers
// the held-out RMSE by 13 %), so the loop must fit the physical model before it adds
// anything, name it the better structure, go on with it and end on it with no effect added
// (rather than the force offset, or on other doors an end stop at its bound);
// every refit on the way keeps the nested-refit inequality.
TEST_CASE(
    "residual loop: the structure check names the physical model on a physical door "
    "fitted with the sensory model",
    "[residual_loop][tremor][slow]") {
  const doorbench::PreparedData data =
      tremor_data(doorbench::reference_model(ModelKind::kPhysical), 1);
  const LoopResult loop = doorbench::run_residual_loop(sensory_reference(), data);
  INFO(loop.full_report());
  CHECK(doorbench::testing::check_nested_refits(loop) >= 1);
  const doorbench::StructureCheck& check = loop.structure;
  REQUIRE(check.ran);
  REQUIRE(check.other_fit.has_value());
  CHECK(check.current_kind == ModelKind::kSensory);
  CHECK(check.other_kind == ModelKind::kPhysical);
  // The physical fit from the reference door takes monotonic steps; the loop's own fits do not.
  CHECK_FALSE(check.other_fit->summary.options.nonmonotonic_steps);
  CHECK(loop.start_fit.summary.options.nonmonotonic_steps);
  CHECK(check.other_better);
  CHECK(check.other.held_out_rmse_rad_s < check.current.held_out_rmse_rad_s);
  CHECK(check.bic_change < 0);
  CHECK(check.current.held_out_rmse_rad_s >
        loop.options.structure_noise_ratio * check.noise_floor_rad_s);
  CHECK(check.best_explained_fraction < loop.options.structure_max_explained_fraction);
  CHECK(check.verdict.find("the physical model is the better structure") == 0);
  CHECK(loop.brief_report().find("Structure check: the physical model is the better structure") !=
        std::string::npos);
  // Family before stacking: checked before the first effect, and the loop goes on with it.
  CHECK(check.after_steps == 0);
  CHECK(check.switched);
  CHECK_FALSE(check.candidates.empty());  // the abandoned step's refits, with their verdicts
  CHECK(loop.steps.empty());
  check_ends_physical_without_spurious_effects(loop);
}

// After a family switch the effects added before it are refitted in the new family and kept
// only if they still help. The force offset is made to come first (it is the only candidate,
// and the check waits for a candidate explaining less than 10 % of the residual): the loop
// adds it to the sensory model, finds no candidate left, switches to the physical model,
// refits the offset there whatever its evidence, and drops it.
TEST_CASE(
    "residual loop: after a switch to the physical family an effect added before is "
    "re-examined and dropped",
    "[residual_loop][tremor][slow]") {
  const doorbench::PreparedData data =
      tremor_data(doorbench::reference_model(ModelKind::kPhysical), 1);
  doorbench::LoopOptions options;
  options.candidates = {effects::Kind::kForceOffset};
  options.structure_max_explained_fraction = 0.1;
  const LoopResult loop = doorbench::run_residual_loop(sensory_reference(), data, options);
  INFO(loop.full_report());
  CHECK(doorbench::testing::check_nested_refits(loop) >= 2);
  REQUIRE(loop.steps.size() == 1);
  CHECK(loop.steps.front().effect == effects::Kind::kForceOffset);
  CHECK(loop.steps.front().model_kind == ModelKind::kSensory);
  const doorbench::StructureCheck& check = loop.structure;
  CHECK(check.switched);
  CHECK(check.after_steps == 1);
  REQUIRE(check.reexamined.size() == 1);
  CHECK(check.reexamined.front().rfind("force_offset: dropped: rejected: ", 0) == 0);
  bool refitted_again = false;
  for (const doorbench::CandidateEvidence& candidate : loop.last_candidates) {
    if (candidate.kind != effects::Kind::kForceOffset) continue;
    refitted_again = candidate.reexamined && candidate.refitted && candidate.after.has_value();
  }
  CHECK(refitted_again);
  check_ends_physical_without_spurious_effects(loop);
}

// Nested refits never lose, on the case where a refit from the start model can: the sensory
// model stacking effects on a physical door with the structure check off, where a refit from
// the start model alone can end far above its parent (docs/residual-loop.md, "Nested refits
// never lose"); every refit must end at or below its parent (step 1 refits three candidates,
// Stribeck friction from the start model), and no step may add an effect with a free
// parameter at a bound or undetermined.
TEST_CASE(
    "residual loop: on a physical door fitted with the sensory model no refit ends above "
    "its parent",
    "[residual_loop][tremor][slow]") {
  const doorbench::PreparedData data =
      tremor_data(doorbench::reference_model(ModelKind::kPhysical), 1);
  doorbench::LoopOptions options;
  options.structure_check = false;
  options.max_steps = 2;
  const LoopResult loop = doorbench::run_residual_loop(sensory_reference(), data, options);
  INFO(loop.full_report());
  CHECK(doorbench::testing::check_nested_refits(loop) >= 3);
  for (const doorbench::LoopStep& step : loop.steps) {
    for (const doorbench::FittedParameter& p : step.parameters) {
      INFO("step " << step.number << ": " << p.name);
      if (p.free) CHECK_FALSE(p.at_bound);
      if (p.free) CHECK(p.determined);
    }
  }
}

TEST_CASE("residual loop: the structure check does not run at the noise floor",
          "[residual_loop][tremor]") {
  const LoopResult clean =
      doorbench::run_residual_loop(sensory_reference(), tremor_data(sensory_reference(), 1));
  INFO(clean.full_report());
  doorbench::testing::check_nested_refits(clean);
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

namespace {

// A catalogue effect of the size of tests/analysis/test_residual_loop.cpp's plain-hand case,
// added to the reference door, recorded by the tremor hand with the default options (every
// closing goes through the soft-close zone to closed, the last run opens past 1.2 rad into
// the end stop), and the loop run from the plain reference door: the effect must be named
// first, every free parameter of it within 3 standard uncertainties of the truth, nothing
// else added. An inertia error is J itself while J is free, so that case holds J (as the
// plain-hand test does).
struct CatalogueCase {
  effects::Kind kind;
  std::vector<double> values;  // the effect's parameters, in the catalogue's order
  bool hold_J = false;
};

LoopResult check_catalogue_case(const CatalogueCase& c, std::uint32_t seed) {
  const effects::EffectInfo& info = effects::info(c.kind);
  INFO(info.name << ", seed " << seed);
  doorbench::EffectSetting setting{c.kind, c.values, {}};
  for (const effects::EffectParameter& parameter : info.parameters) {
    setting.bounds.push_back(parameter.default_bounds);
  }
  doorbench::LoopOptions options;
  if (c.hold_J) options.fit.fixed_parameters = {"J"};
  LoopResult loop = doorbench::run_residual_loop(
      sensory_reference(), tremor_data(sensory_reference().with_effect(setting), seed), options);
  INFO(loop.full_report());
  CHECK(doorbench::testing::check_nested_refits(loop) >= 1);
  REQUIRE_FALSE(loop.steps.empty());
  const doorbench::LoopStep& step = loop.steps.front();
  CHECK(step.effect == c.kind);
  CHECK(step.after.held_out_rmse_rad_s < step.before.held_out_rmse_rad_s);
  CHECK(step.after.bic < step.before.bic);
  for (std::size_t k = 0; k < info.parameters.size(); ++k) {
    const std::string name =
        std::string(info.name) + "." + std::string(info.parameters[k].info.name);
    const doorbench::FittedParameter* p = find(step, name);
    REQUIRE(p != nullptr);
    if (k == 0 || p->free) check_within_3u(p, c.values[k]);  // the amplitude is always free
  }
  CHECK(loop.steps.size() == 1);
  // Where the structure check runs (its noise floor is an estimate), it keeps the sensory
  // model: the door is a sensory one.
  CHECK_FALSE(loop.structure.other_better);
  return loop;
}

}  // namespace

// Every catalogue effect on the tremor hand's seed-1 recording, at the plain-hand case's
// size. The soft close needs the second look (docs/residual-loop.md, "Recordings with the
// tremor hand": linear z 3.6; its second look's standard error from the residual the
// linearised step leaves, z 6.4). Here the check does not run at all: the held-out error
// after the effect is near the noise floor.
TEST_CASE("residual loop: names each catalogue effect first on a tremor-hand recording",
          "[residual_loop][tremor][slow]") {
  const CatalogueCase c = GENERATE(CatalogueCase{effects::Kind::kViscousDamping, {0.5}},
                                   CatalogueCase{effects::Kind::kGravityImbalance, {3.0}},
                                   CatalogueCase{effects::Kind::kForceOffset, {3.0}},
                                   CatalogueCase{effects::Kind::kDirectionFriction, {1.5}},
                                   CatalogueCase{effects::Kind::kSoftClose, {5.0, 0.15, 50.0}},
                                   CatalogueCase{effects::Kind::kEndStop, {200.0, 1.2, 3000.0}},
                                   CatalogueCase{effects::Kind::kInertiaError, {0.2}, true});
  const LoopResult loop = check_catalogue_case(c, 1);
  INFO(loop.brief_report());
  CHECK_FALSE(loop.structure.ran);
}

// Why the soft close needed the second look on seed 1, without the refits: the linear score
// stays below the refit threshold (5.4%, z 3.6, measured), and the second look's refinement,
// five steps from a start fit that bent the latch to mimic the damper, ends short of a
// least-squares point. Its z takes the standard error from the residual the linearised step
// leaves; from the refined point's own residual it was 1.6 and the damper was not refitted.
TEST_CASE(
    "residual loop: the second look sees the tremor hand's soft close that the linear "
    "score undersells",
    "[residual_loop][tremor]") {
  doorbench::EffectSetting setting{effects::Kind::kSoftClose, {5.0, 0.15, 50.0}, {}};
  for (const effects::EffectParameter& parameter : effects::info(setting.kind).parameters) {
    setting.bounds.push_back(parameter.default_bounds);
  }
  const doorbench::PreparedData data = tremor_data(sensory_reference().with_effect(setting), 1);
  const doorbench::LoopOptions options;
  const doorbench::FitResult fit = doorbench::fit_model(sensory_reference(), data, options.fit);
  const doorbench::ResidualExamination examination =
      doorbench::examine_residual(fit.model, data, options);
  REQUIRE_FALSE(examination.candidates.empty());
  const doorbench::CandidateEvidence& best = examination.candidates.front();
  INFO(best.name << ": " << best.explained_fraction << ", z " << best.score_z << "; second look "
                 << best.screen_explained_fraction << ", z " << best.screen_score_z);
  CHECK(best.kind == effects::Kind::kSoftClose);
  CHECK(best.score_z < options.min_score_z);  // the linear score alone would not refit it
  REQUIRE(best.screened);
  CHECK(best.screen_explained_fraction > 0.5);
  CHECK(best.screen_score_z >= options.min_score_z);
}

// The effects the tremor hand's strokes reach only in part (the soft-close zone at the end of
// each closing, the end stop in the last run's two strokes) and the inertia error, on two more
// seeds. On seed 2 the end stop's loop ends at 5.5 times the estimated noise floor and the
// structure check runs; it keeps the sensory model.
TEST_CASE(
    "residual loop: names a soft close, an end stop and an inertia error first on two "
    "more tremor-hand seeds",
    "[residual_loop][tremor][slow]") {
  const std::uint32_t seed = GENERATE(2u, 3u);
  const CatalogueCase c = GENERATE(CatalogueCase{effects::Kind::kSoftClose, {5.0, 0.15, 50.0}},
                                   CatalogueCase{effects::Kind::kEndStop, {200.0, 1.2, 3000.0}},
                                   CatalogueCase{effects::Kind::kInertiaError, {0.2}, true});
  check_catalogue_case(c, seed);
}

// Every refit obeys the nested-refit rule, those of a step the structure check abandons
// included. The force offset is the only candidate and the check runs after its refit (the
// refit explains less than structure_max_explained_fraction): the loop switches to the
// physical model and abandons the step, whose refit of the offset is kept in
// StructureCheck::candidates. It extends the sensory fit, so it ends at or below that fit's
// fitted sum of squares like any step's refit.
TEST_CASE(
    "residual loop: the refit of a step abandoned for a family switch ends at or below "
    "its parent",
    "[residual_loop][tremor][slow]") {
  const doorbench::PreparedData data =
      tremor_data(doorbench::reference_model(ModelKind::kPhysical), 1);
  doorbench::LoopOptions options;
  options.candidates = {effects::Kind::kForceOffset};
  const LoopResult loop = doorbench::run_residual_loop(sensory_reference(), data, options);
  INFO(loop.full_report());
  const doorbench::StructureCheck& check = loop.structure;
  REQUIRE(check.switched);
  CHECK(check.after_steps == 0);
  int abandoned = 0;
  for (const doorbench::CandidateEvidence& candidate : check.candidates) {
    if (candidate.kind != effects::Kind::kForceOffset) continue;
    REQUIRE(candidate.after.has_value());
    abandoned += doorbench::testing::check_nested_refit(candidate);
    CHECK(candidate.before.sum_of_squares == check.current.sum_of_squares);
  }
  CHECK(abandoned == 1);
  CHECK(doorbench::testing::check_nested_refits(loop) >= 1);
}
