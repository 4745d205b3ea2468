// Live tuning keys (study/tuning_keys.h): each key moves its perceptual control by one
// documented step and leaves the others alone; steps out of the parameter set's bounds or
// the model's constraints are refused naming the control and the limit; the tuner's ids,
// reset and log, and the log written into a real session file.
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <optional>
#include <string>

#include "acquisition/session/session_file.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "fixtures/temp_dir.h"
#include "study/tuning_keys.h"

using Catch::Matchers::Contains;
using Catch::Matchers::Equals;
using Catch::Matchers::StartsWith;
using Catch::Matchers::WithinRel;
using doorbench::DoorModel;
using doorbench::ModelKind;
using doorbench::perceptual::Control;
namespace study = doorbench::study;
namespace perceptual = doorbench::perceptual;

namespace {

const DoorModel& reference() {
  static const DoorModel door = doorbench::reference_model(ModelKind::kSensory);
  return door;
}

}  // namespace

TEST_CASE("Tuning keys: each key moves its control by the step, the others stay", "[ab][tuning]") {
  const std::map<char, std::pair<Control, double>> documented{
      {'+', {Control::kHeaviness, 1.1}},     {'-', {Control::kHeaviness, 1 / 1.1}},
      {'U', {Control::kLatchEffort, 1.1}},   {'u', {Control::kLatchEffort, 1 / 1.1}},
      {'C', {Control::kClosingEffort, 1.1}}, {'c', {Control::kClosingEffort, 1 / 1.1}},
      {'S', {Control::kSmoothness, 1.1}},    {'s', {Control::kSmoothness, 1 / 1.1}},
      {'N', {Control::kSnap, 1.1}},          {'n', {Control::kSnap, 1 / 1.1}},
  };
  CHECK(study::tuning_keys().size() == documented.size());
  for (const study::TuningKey& key : study::tuning_keys()) {
    INFO("key " << key.key);
    REQUIRE(documented.count(key.key) == 1);
    const auto [control, factor] = documented.at(key.key);
    CHECK(key.control == control);
    const study::KeyOutcome outcome = study::apply_key(reference(), key.key);
    REQUIRE(outcome.model);
    CHECK_THAT(perceptual::read(*outcome.model, control),
               WithinRel(perceptual::read(reference(), control) * factor, 1e-12));
    for (const perceptual::ControlInfo& other : perceptual::controls()) {
      if (other.control == control) continue;
      INFO("other control " << other.name);
      CHECK_THAT(perceptual::read(*outcome.model, other.control),
                 WithinRel(perceptual::read(reference(), other.control), 1e-12));
    }
    CHECK(outcome.control == perceptual::controls()[static_cast<int>(control)].name);
    CHECK_THAT(outcome.message, StartsWith(std::string(key.action) + ": " + outcome.control));
  }
  const study::KeyOutcome heavier = study::apply_key(reference(), '+');
  CHECK(heavier.message == "heavier: heaviness 0.95 -> 1.045 kg*m^2");
  // Another step factor.
  study::KeyOptions options;
  options.step_factor = 1.5;
  CHECK_THAT(study::apply_key(reference(), '-', options).new_value, WithinRel(0.95 / 1.5, 1e-12));
  options.step_factor = 1.0;
  CHECK_THAT(options.validate(), Equals("step factor must be above 1 and at most 2, got 1"));
  CHECK_THROWS_WITH(study::apply_key(reference(), '+', options),
                    StartsWith("tuning options: step factor"));
  CHECK_THAT(study::key_map_text(), Contains("  +  heavier: heaviness x step\n"));
  CHECK_THAT(study::key_map_text(), Contains("  r  reset"));
}

TEST_CASE("Tuning keys: out of bounds refused naming the control and the limit", "[ab][tuning]") {
  // J = 0.95 with bounds [0.1, 5]: 0.95 * 1.1^17 = 4.80 is allowed, the 18th step is not.
  DoorModel door = reference();
  for (int press = 1; press <= 17; ++press) {
    study::KeyOutcome outcome = study::apply_key(door, '+');
    REQUIRE(outcome.model);
    door = *outcome.model;
  }
  const study::KeyOutcome refused = study::apply_key(door, '+');
  CHECK_FALSE(refused.model);
  CHECK_THAT(refused.message,
             Equals("heavier refused: heaviness 5.282 kg*m^2 is out of bounds: J would be "
                    "5.282, above its upper bound 5; the limit of heaviness is 5 kg*m^2"));

  // d1 = 2.6 N*m with upper bound 20: smoothness (d1 / r_h) is limited to 20 / 0.58 N.
  door = reference();
  study::KeyOutcome outcome;
  int presses = 0;
  while ((outcome = study::apply_key(door, 'S')).model) {
    door = *outcome.model;
    ++presses;
  }
  CHECK(presses == 21);
  CHECK_THAT(outcome.message, StartsWith("rougher refused: smoothness"));
  CHECK_THAT(outcome.message, Contains("d1 would be 21.16"));
  CHECK_THAT(outcome.message, Contains("above its upper bound 20; the limit of smoothness is "
                                       "34.48 N"));

  // A constraint of the model rather than a bound: the latch effort cannot fall below the
  // soft spring's share (k theta1 / r_h = 1.926 N); perceptual::set's reason is passed on.
  door = reference();
  while ((outcome = study::apply_key(door, 'u')).model) door = *outcome.model;
  CHECK_THAT(outcome.message, StartsWith("easier to unlatch refused: latch_effort "));
  CHECK_THAT(outcome.message, Contains("is below what the soft spring alone gives"));

  // Snap at 0 cannot be stepped by a factor.
  const DoorModel no_snap = perceptual::set(reference(), Control::kSnap, 0.0);
  CHECK_THAT(study::apply_key(no_snap, 'N').message,
             Equals("more snap refused: snap is 0 N*m*s, and a step multiplies it, so it cannot "
                    "move from 0"));
  CHECK_THAT(study::apply_key(reference(), 'x').message,
             Equals("key 'x' does nothing (keys: + - U u C c S s N n r)"));
  CHECK_THAT(study::apply_key(doorbench::reference_model(ModelKind::kPhysical), '+').message,
             Equals("heavier refused: the perceptual controls act on the sensory model only"));
}

TEST_CASE("Tuning: the tuner's parameter set ids, reset and log", "[ab][tuning]") {
  study::KeyTuner tuner(reference(), "ref");
  CHECK(tuner.parameter_set_id() == "ref");
  CHECK(tuner.press('+', 1.5).parameter_set_id == "ref-1");
  CHECK(tuner.press('s', 2.0).parameter_set_id == "ref-2");
  const study::TuningLogEntry& unknown = tuner.press('?', 2.5);
  CHECK_FALSE(unknown.applied);
  CHECK(unknown.parameter_set_id == "ref-2");
  CHECK_THAT(perceptual::read(tuner.model(), Control::kHeaviness), WithinRel(1.045, 1e-12));
  const study::TuningLogEntry& reset = tuner.press('r', 3.0);
  CHECK(reset.applied);
  CHECK(reset.parameter_set_id == "ref");
  CHECK(reset.message == "reset: back to parameter set ref");
  CHECK(perceptual::read(tuner.model(), Control::kHeaviness) == 0.95);
  CHECK(tuner.press('N', 4.0).parameter_set_id == "ref-3");

  const auto& entries = tuner.log().entries();
  REQUIRE(entries.size() == 5);
  CHECK(entries[0].time_s == 1.5);
  CHECK(entries[0].control == "heaviness");
  CHECK(entries[0].old_value == 0.95);
  CHECK_THAT(entries[0].new_value, WithinRel(1.045, 1e-12));
  const std::string csv = tuner.log().to_csv();
  CHECK_THAT(csv, StartsWith("time_s,key,action,control,old,new,unit,applied,parameter_set,"
                             "message\n1.5,+,heavier,heaviness,0.95,1.045"));
  CHECK_THAT(csv, Contains("\n2.5,?,unknown,,0,0,,0,ref-2,key '?' does nothing"));
  CHECK_THAT(csv, Contains("\n3,r,reset,,0,0,,1,ref,reset: back to parameter set ref\n"));

  CHECK_THROWS_WITH(study::KeyTuner(doorbench::reference_model(ModelKind::kPhysical), "p"),
                    Equals("tuning: the perceptual controls act on the sensory model only"));
}

TEST_CASE("Tuning: the log written into a session", "[ab][tuning]") {
  doorbench::testing::TempDir dir("tuning_log");
  study::KeyTuner tuner(reference(), "ref");
  tuner.press('+', 0.25);
  tuner.press('x', 0.5);
  const auto path = dir.path / "tuned.h5";
  {
    doorbench::SessionMetadata metadata;
    metadata.rig_name = "test";
    doorbench::SessionWriter writer(path, metadata);
    tuner.write_to_session(writer);
    writer.close();
  }
  const doorbench::SessionReader session(path);
  const auto events = session.events();
  REQUIRE(events.size() == 2);
  CHECK(events[0].kind == "tuning");
  CHECK(events[0].time_s == 0.25);
  CHECK(events[0].detail == "key +: heavier: heaviness 0.95 -> 1.045 kg*m^2 (set ref-1)");
  CHECK_THAT(events[1].detail, StartsWith("key x: key 'x' does nothing"));
  CHECK(session.read_group_attribute("tuning", "log_csv") == tuner.log().to_csv());
  CHECK(session.read_group_attribute("tuning", "final_parameter_set") == "ref-1");
  // The parameter file stored reads back as the tuned door.
  const doorbench::ParameterFile start = doorbench::parse_parameter_file(
      session.read_group_attribute("tuning", "start_parameters_json"), "start");
  const doorbench::ParameterFile final_set = doorbench::parse_parameter_file(
      session.read_group_attribute("tuning", "final_parameters_json"), "final");
  REQUIRE(start.sensory);
  REQUIRE(final_set.sensory);
  CHECK(start.sensory->values[doorbench::sensory::kJ] == 0.95);
  CHECK_THAT(final_set.sensory->values[doorbench::sensory::kJ], WithinRel(1.045, 1e-15));
  CHECK(final_set.sensory->values[doorbench::sensory::kK] ==
        start.sensory->values[doorbench::sensory::kK]);
}

TEST_CASE("Tuning: keys read one by one from a real pseudo-terminal, its mode restored",
          "[ab][tuning]") {
  int master = -1, slave = -1;
  REQUIRE(::openpty(&master, &slave, nullptr, nullptr, nullptr) == 0);
  termios before{};
  REQUIRE(::tcgetattr(slave, &before) == 0);
  REQUIRE((before.c_lflag & ICANON) != 0);
  {
    study::TerminalKeys keys(slave, "keypad");
    termios during{};
    REQUIRE(::tcgetattr(slave, &during) == 0);
    CHECK((during.c_lflag & ICANON) == 0);
    CHECK((during.c_lflag & ECHO) == 0);
    CHECK_FALSE(keys.poll());
    // No Enter: in canonical mode these would wait for a newline.
    REQUIRE(::write(master, "+u", 2) == 2);
    CHECK(keys.poll(1.0) == '+');
    CHECK(keys.poll(1.0) == 'u');
    CHECK_FALSE(keys.poll(0.05));
    // Through a tuner: the keys as the keypad sends them.
    study::KeyTuner tuner(reference(), "ref");
    REQUIRE(::write(master, "UUr-", 4) == 4);
    for (int i = 0; i < 4; ++i) {
      const std::optional<char> key = keys.poll(1.0);
      REQUIRE(key);
      tuner.press(*key, 0.1 * i);
    }
    CHECK(tuner.parameter_set_id() == "ref-3");
    CHECK_THAT(perceptual::read(tuner.model(), Control::kHeaviness), WithinRel(0.95 / 1.1, 1e-12));
  }
  termios after{};
  REQUIRE(::tcgetattr(slave, &after) == 0);
  CHECK(after.c_lflag == before.c_lflag);
  CHECK(after.c_cc[VMIN] == before.c_cc[VMIN]);
  ::close(master);
  ::close(slave);

  int pipe_fds[2];
  REQUIRE(::pipe(pipe_fds) == 0);
  CHECK_THROWS_WITH(study::TerminalKeys(pipe_fds[0]),
                    StartsWith("stdin is not a terminal: live tuning keys need one"));
  ::close(pipe_fds[0]);
  ::close(pipe_fds[1]);
}
