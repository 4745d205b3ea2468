// doorbench play through the real executable.
#include <catch2/catch.hpp>
#include <fstream>
#include <regex>

#include "acquisition/session/session_file.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/run_on_terminal.h"

using namespace doorbench;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

// A rotary device's position is an angle and its force a torque: the session's device channels
// and the summary say so, where a HapticMaster's say m, m/s and N.
TEST_CASE("play: the device's channels and the summary carry the device's own units",
          "[haptic][cli]") {
  TempDir dir("play_cli_units");
  struct Case {
    std::string device, position, velocity, force, after_force;
  };
  // A rotary device's shaft is the hinge: there is no arc to leave, so no arc error is reported.
  for (const Case& c : {Case{"sim:rotary", "rad", "rad/s", "N*m", "; 0 parameter changes"},
                        Case{"sim", "m", "m/s", "N", ", arc error radial/axial max "}}) {
    INFO(c.device);
    const auto session = dir / (c.device == "sim" ? "sim.h5" : "rotary.h5");
    const auto run =
        run_doorbench_shell("play --device " + c.device +
                                " --simulated-time --duration-s 2 --out '" + session.string() + "'",
                            dir);
    INFO(run.err);
    REQUIRE(run.status == 0);
    CHECK(std::regex_search(
        run.out,
        std::regex("; max commanded force [0-9.e+-]+ " +
                   std::regex_replace(c.force, std::regex("\\*"), "\\*") + c.after_force)));
    const SessionReader reader(session);
    for (const char* axis : {"x", "y", "z"}) {
      CHECK(reader.channel(std::string("position_") + axis).unit == c.position);
      CHECK(reader.channel(std::string("velocity_") + axis).unit == c.velocity);
      CHECK(reader.channel(std::string("measured_force_") + axis).unit == c.force);
      CHECK(reader.channel(std::string("commanded_force_") + axis).unit == c.force);
    }
    CHECK(reader.channel("force").unit == "N");  // the hand's force along the arc, either way
    CHECK(reader.channel("model_torque").unit == "N*m");
  }
}

TEST_CASE("play: the simulated HapticMaster in simulated time writes a session and a summary",
          "[haptic][cli]") {
  TempDir dir("play_cli");
  const auto session = dir / "played.h5";
  const auto run = run_doorbench_shell(
      "play --device sim --simulated-time --duration-s 12 --out '" + session.string() + "'", dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  // 12 s of ticks, then the safety layer's stop ramp (20 ms).
  CHECK_THAT(run.out, Catch::Contains("12022 ticks over 12.02 s into"));
  CHECK_THAT(run.out, Catch::Contains("0 records dropped"));
  CHECK_THAT(run.out, Catch::Contains("safety stopped (events: start_ramp_done"));
  const SessionReader reader(session);
  CHECK(reader.sample_count("force") == 12022);
  CHECK(reader.read_group_attribute("haptic", "device") == "sim:hapticmaster");

  // Explicit tick times (a late tick stays where it fell), the nominal rate in the group
  // haptic, and info shows both: the rate column says "times", a line the rate and the
  // intervals the ticks kept (exactly 1 ms in simulated time).
  CHECK(reader.channel("force").sample_rate_hz == 0.0);
  CHECK(reader.read_group_attribute("haptic", "rate_hz") == "1000");
  const auto info = run_doorbench_shell("info '" + session.string() + "'", dir);
  REQUIRE(info.status == 0);
  INFO(info.out);
  CHECK_THAT(info.out, Catch::Contains("\nplayback clock: nominal 1000 Hz (haptic/rate_hz); the "
                                       "channels keep each tick's own time (rate \"times\"): "
                                       "intervals median 1 ms, largest 1 ms over 12022 ticks\n"));
  CHECK(std::regex_search(info.out, std::regex("\n  force +haptic_force +12022 +times +N +N +"
                                               "\\(values are physical\\)\n")));

  // Sessions are never overwritten.
  const auto again = run_doorbench_shell(
      "play --device sim --simulated-time --duration-s 1 --out '" + session.string() + "'", dir);
  CHECK(again.status == 2);
  CHECK_THAT(again.err, Catch::Contains("exists (sessions are never overwritten)"));
}

TEST_CASE("play: bad devices and options are refused by name", "[haptic][cli]") {
  TempDir dir("play_cli_errors");
  const auto bogus = run_doorbench_shell(
      "play --device telepathy --duration-s 1 --out '" + (dir / "x.h5").string() + "'", dir);
  CHECK(bogus.status == 2);  // a usage error (tests/app/test_unknown_names.cpp)
  CHECK_THAT(bogus.err, Catch::Contains("--device 'telepathy': not a device (use sim, "
                                        "sim:hapticmaster, sim:rotary or "
                                        "hapticmaster://HOST[:PORT])"));
  const auto rate =
      run_doorbench_shell("play --rate-hz 8000 --out '" + (dir / "y.h5").string() + "'", dir);
  CHECK(rate.status != 0);
  CHECK_THAT(rate.err, Catch::Contains("--rate-hz"));
}

TEST_CASE("play --watch-params: a parameter file saved during a real-time run is played live",
          "[haptic][cli]") {
  TempDir dir("play_watch");
  const DoorModel reference = reference_model(ModelKind::kSensory);
  const DoorModel heavier = perceptual::set(reference, perceptual::Control::kHeaviness, 1.2);
  std::ofstream(dir / "heavier.json") << to_parameter_json(heavier);
  const auto watched = dir / "tuned.json";
  const auto session = dir / "live.h5";
  // The file appears about one second into a three-second run (as the viewer's "save" would):
  // when the first status line (written after one second of ticks when stderr is a file) is
  // there, so that a slow start on a loaded machine does not move it. A loaded machine may
  // delay a tick by tens of ms: that must not stop this run early.
  const std::string writer = "until grep -q 'safety' '" + (dir / "stderr.txt").string() +
                             "' 2> /dev/null; do sleep 0.02; done; cp '" +
                             (dir / "heavier.json").string() + "' '" + watched.string() +
                             "'; sleep 4";
  const auto run = run_doorbench_shell(
      "play --device sim --duration-s 3 --max-tick-interval-ms 200 --watch-params '" +
          watched.string() + "' --out '" + session.string() + "'",
      dir, "", writer);
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Catch::Contains("applied as parameter set 2"));
  const SessionReader reader(session);
  bool applied = false;
  for (const SessionEvent& event : reader.events()) {
    if (event.kind == "parameters" && event.detail.find("set 2: file ") == 0) {
      applied = true;
      CHECK(event.time_s > 0.8);
      CHECK(event.time_s < 2.5);
    }
  }
  CHECK(applied);
  CHECK_THAT(reader.read_group_attribute("haptic/parameter_sets/set_2", "parameters"),
             Catch::Contains("\"J\""));
}

TEST_CASE("play --keys: keypad presses on a terminal tune the door live, each one recorded",
          "[haptic][cli]") {
  // stdin is a real pseudo-terminal (openpty), as the operator's keypad would be.
  TempDir dir("play_keys");
  const auto session = dir / "keys.h5";
  // Heavier, then an unknown key, one second into the run.
  const testing::DoorbenchRun run = testing::run_doorbench_on_terminal(
      {"play", "--device", "sim", "--duration-s", "3", "--max-tick-interval-ms", "200", "--keys",
       "--out", session.string()},
      dir, "+x", 1000);
  const std::string& err = run.err;
  INFO(err);
  REQUIRE(run.status == 0);
  CHECK_THAT(err, Catch::Contains("key +: heavier: heaviness 0.95 -> 1.045 kg*m^2"));
  const SessionReader reader(session);
  int tuning_events = 0;
  bool heavier_played = false;
  for (const SessionEvent& event : reader.events()) {
    if (event.kind == "tuning") ++tuning_events;
    if (event.kind == "parameters" &&
        event.detail.rfind("set 2: key +: heavier: heaviness 0.95 -> 1.045", 0) == 0) {
      heavier_played = true;
    }
  }
  CHECK(tuning_events == 2);  // the refused key too
  CHECK(heavier_played);
  CHECK_THAT(reader.read_group_attribute("haptic/parameter_sets/set_2", "parameters"),
             Catch::Contains("1.045"));
}
