// The haptic path on a busy computer, through the command line and in real time: `play`, `ab`
// and `campaign run` on the HapticMaster protocol emulator (a process of its own), on the
// simulated HapticMaster and on the rotary device, while the test keeps every CPU busy with
// twice as many spinning processes as there are cores (tests/support/busy_processes.h); and
// each kind of stop named on stderr and in the session, word for word.
//
// The emulator runs at the normal priority beside the spinners, so its replies are slower and
// less regular than a real HapticMaster's (which has a processor of its own): that is the
// harder case for the driver's watchdog and the safety layer's stall checks.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "core/clock.h"
#include "core/number_format.h"
#include "fixtures/temp_dir.h"
#include "tests/support/busy_processes.h"
#include "tests/support/files.h"
#include "tests/support/hapticmaster_emulator_process.h"
#include "tests/support/pause_watch.h"
#include "tests/support/run_doorbench.h"

using Catch::Matchers::Contains;
using doorbench::SessionEvent;
using doorbench::SessionReader;
using doorbench::testing::BusyProcesses;
using doorbench::testing::DoorbenchRun;
using doorbench::testing::HapticMasterEmulator;
using doorbench::testing::PauseWatch;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;
namespace fs = std::filesystem;

namespace {

const std::string kReference = DOORBENCH_SOURCE_DIR "/analysis/data/reference-door.json";

// The detail of the session's "stop" event ("" without one).
std::string stop_event(const fs::path& session_path) {
  const SessionReader session(session_path);
  for (const SessionEvent& event : session.events()) {
    if (event.kind == "stop") return event.detail;
  }
  return "";
}

// The recorded time between a session's first and last tick.
double played_s(const fs::path& session_path) {
  const SessionReader session(session_path);
  const auto force = session.read("commanded_force_x");
  return force.time_s.empty() ? 0.0 : force.time_s.back() - force.time_s.front();
}

DoorbenchRun play(const std::string& device, double duration_s, const fs::path& session,
                  const TempDir& dir, const std::string& extra = "") {
  return run_doorbench_shell("play --device " + device + " --duration-s " +
                                 doorbench::format_number(duration_s) + " " + extra + " --out '" +
                                 session.string() + "'",
                             dir);
}

// A play that ran its whole time: exit 0, no early stop, the session's stop event saying so.
void check_played_through(const DoorbenchRun& run, const fs::path& session, double duration_s) {
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.out, !Contains("stopped early"));
  CHECK_THAT(run.out, Contains("\nstart-up: the device's checks "));
  CHECK(stop_event(session) == "end: the run's duration was played");
  CHECK(played_s(session) > duration_s - 0.05);
}

// A campaign of one participant: two variants compared in both orders (2 trials, 4
// presentations), each presentation `presentation_s` long.
fs::path plan_small_campaign(const TempDir& dir, const std::string& name) {
  const fs::path toml = dir / (name + ".toml");
  std::ofstream(toml) << "[campaign]\nname = \"load\"\nseed = 7\nmodel = \"sensory\"\n"
                         "presentation_s = 1.0\nsimulated_presentation_s = 1.0\n\n"
                         "[variants]\nreference = \"base\"\nheavier = \"heaviness*1.2\"\n\n"
                         "[participants]\ncount = 1\nprefix = \"P\"\n\n"
                         "[[blocks]]\nname = \"pair\"\ntype = \"pair\"\n"
                         "question = \"preference-2ac\"\npairs = \"all\"\nrepetitions = 1\n";
  const fs::path folder = dir / name;
  const DoorbenchRun planned = run_doorbench_shell(
      "campaign plan '" + toml.string() + "' --out '" + folder.string() + "'", dir);
  INFO(planned.err);
  REQUIRE(planned.status == 0);
  return folder;
}

// Runs stopped by a stall while a CPU was held that a load test plays again, in all: on the
// virtual machines the tests run on, a host holds one virtual CPU for 100 ms every 20 to 50 s
// under sustained load (measured: a pinned SCHED_FIFO watcher per CPU).
constexpr int kHeldRunsMax = 10;

// Whether a run that stopped with `stop` (its stop event, or its stderr) stopped for a stall
// while a CPU of the machine was held long enough to cause it: a stalled tick (0.1 s between
// two ticks) and a 90 ms hold, or a stalled device reading (50 ticks) and a 45 ms hold.
bool stalled_while_held(const std::string& stop, const PauseWatch& watch, double from_s,
                        double until_s) {
  if (stop.find(" between two ticks, above max_tick_stall_s") != std::string::npos) {
    return watch.held_during(from_s, until_s, 0.09);
  }
  if (stop.find("device_stalled: the device's reading did not change for ") != std::string::npos) {
    return watch.held_during(from_s, until_s, 0.045);
  }
  return false;
}

// The lines of trials.csv after its header.
std::size_t answered_trials(const fs::path& folder) {
  std::ifstream in(folder / "trials.csv");
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') ++lines;
  }
  return lines == 0 ? 0 : lines - 1;
}

}  // namespace

TEST_CASE("play under load: 3 s on the HapticMaster emulator without a stop, 20 runs of 20",
          "[slow][hapticmaster][load][cli]") {
  TempDir dir("play_load_hm");
  HapticMasterEmulator emulator;
  const BusyProcesses busy;
  const PauseWatch watch;
  int played = 0, held = 0;
  for (int run = 1; run <= 20; ++run) {
    const fs::path session =
        dir / ("play-" + std::to_string(run) + "-" + std::to_string(held) + ".h5");
    const double started_s = doorbench::monotonic_now_s();
    const DoorbenchRun result = play(emulator.name(), 3.0, session, dir);
    // A stall while a CPU of the machine was held is the stall check doing its job, not a
    // defect of the play: that run is played again, at most kHeldRunsMax times in all.
    if (held < kHeldRunsMax &&
        stalled_while_held(stop_event(session), watch, started_s, doorbench::monotonic_now_s())) {
      WARN("run " << run << ": a CPU was held (longest gap so far " << watch.longest_gap_s()
                  << " s) and the play stalled with it; played again");
      ++held, --run;
      continue;
    }
    INFO("run " << run << " of 20 with " << busy.count() << " busy processes");
    check_played_through(result, session, 3.0);
    if (result.status == 0 && stop_event(session) == "end: the run's duration was played") {
      ++played;
    }
  }
  CHECK(played == 20);
}

TEST_CASE("play under load: the simulated HapticMaster and the rotary device in real time",
          "[slow][load][cli]") {
  TempDir dir("play_load_sim");
  const BusyProcesses busy;
  for (const std::string device : {"sim", "sim:rotary"}) {
    for (int run = 1; run <= 3; ++run) {
      INFO(device << ", run " << run << " of 3 with " << busy.count() << " busy processes");
      const fs::path session =
          dir / ("play-" + device.substr(device.find(':') + 1) + "-" + std::to_string(run) + ".h5");
      check_played_through(play(device, 3.0, session, dir), session, 3.0);
    }
  }
}

TEST_CASE("ab under load: blinded trials on the emulator, the simulated and the rotary device",
          "[slow][hapticmaster][load][cli]") {
  TempDir dir("ab_load");
  HapticMasterEmulator emulator;
  std::ofstream(dir / "answers.txt") << "1\n2\n";
  const BusyProcesses busy;
  const PauseWatch watch;
  int held = 0;
  for (const std::string& device :
       {emulator.name(), std::string("sim --real-time"), std::string("sim:rotary --real-time")}) {
    INFO(device << " with " << busy.count() << " busy processes");
    DoorbenchRun run;
    fs::path out;
    for (;;) {  // again while a stall came with a held CPU, at most kHeldRunsMax times in all
      out = dir / ("ab-" + std::to_string(device.size()) + "-" + std::to_string(held));
      const double started_s = doorbench::monotonic_now_s();
      run = run_doorbench_shell("ab --a '" + kReference + "' --b '" + kReference +
                                    "' --trials 2 --seed 3 " + "--presentation-s 1.5 --device " +
                                    device + " --answers '" + (dir / "answers.txt").string() +
                                    "' --out '" + out.string() + "'",
                                dir);
      if (run.status == 0 || held >= kHeldRunsMax ||
          !stalled_while_held(run.err, watch, started_s, doorbench::monotonic_now_s())) {
        break;
      }
      WARN(device << ": a CPU was held and the presentation stalled with it; run again");
      ++held;
    }
    INFO(run.out << run.err);
    REQUIRE(run.status == 0);
    for (const char* presentation :
         {"trial-01-1.h5", "trial-01-2.h5", "trial-02-1.h5", "trial-02-2.h5"}) {
      CHECK(stop_event(out / presentation) == "end: the run's duration was played");
    }
  }
}

TEST_CASE("campaign run under load: a simulated participant on the emulator, 10 runs of 10",
          "[slow][hapticmaster][load][cli]") {
  TempDir dir("campaign_load");
  HapticMasterEmulator emulator;
  const BusyProcesses busy;
  const PauseWatch watch;
  int finished = 0, held = 0;
  for (int run = 1; run <= 10; ++run) {
    const fs::path folder =
        plan_small_campaign(dir, "hm" + std::to_string(run) + "-" + std::to_string(held));
    const double started_s = doorbench::monotonic_now_s();
    const DoorbenchRun result =
        run_doorbench_shell("campaign run '" + folder.string() +
                                "' --participant P01 --respondent sim --device " + emulator.name(),
                            dir);
    if (result.status != 0 && held < kHeldRunsMax &&
        stalled_while_held(result.err, watch, started_s, doorbench::monotonic_now_s())) {
      WARN("run " << run << ": a CPU was held and a presentation stalled with it; run again");
      ++held, --run;
      continue;
    }
    INFO("run " << run << " of 10 with " << busy.count() << " busy processes: " << result.err);
    CHECK(result.status == 0);
    CHECK(answered_trials(folder) == 2);
    if (result.status == 0 && answered_trials(folder) == 2) ++finished;
  }
  CHECK(finished == 10);
  for (const std::string device : {"sim", "sim:rotary"}) {
    const fs::path folder = plan_small_campaign(dir, device.substr(device.find(':') + 1));
    const DoorbenchRun result = run_doorbench_shell(
        "campaign run '" + folder.string() + "' --participant P01 --respondent sim --device " +
            device + " --real-time",
        dir);
    INFO(device << ": " << result.err);
    CHECK(result.status == 0);
    CHECK(answered_trials(folder) == 2);
  }
}

TEST_CASE("play: each kind of stop is named on stderr and in the session, word for word",
          "[hapticmaster][cli]") {
  TempDir dir("play_stop_causes");
  const auto expect_stop = [&](const DoorbenchRun& run, const fs::path& session,
                               const std::string& cause) {
    INFO(run.out << run.err);
    CHECK(run.status == 1);
    REQUIRE(fs::exists(session));
    const std::string played = doorbench::format_significant(played_s(session), 3);
    // The first line says what is played; the last, why it stopped.
    const std::string last_line = run.err.substr(run.err.rfind('\n', run.err.size() - 2) + 1);
    CHECK(last_line == "doorbench: the playback stopped after " + played + " s of 5 s (session " +
                           session.string() + " kept): " + cause + "\n");
    CHECK_THAT(run.out, Contains("\nstopped early: " + cause + "\n"));
    CHECK(stop_event(session) == cause);
  };
  SECTION("a dropped connection") {
    HapticMasterEmulator emulator({"--drop-after", "3000"});
    const fs::path session = dir / "dropped.h5";
    expect_stop(play(emulator.name(), 5.0, session, dir), session,
                "link_lost: " + emulator.name() +
                    ": connection closed by the device; the device was stopped (zero force, "
                    "state stop)");
  }
  SECTION("a safety trip, with its figure") {
    // The virtual user opens and closes the door in 1 s: faster than the trip speed allows.
    // Simulated time: the same run every time.
    const fs::path session = dir / "trip.h5";
    const DoorbenchRun run = play("sim --simulated-time --hand-cycle-s 1", 5.0, session, dir);
    // The figure is the speed the session recorded at the trip's tick.
    const SessionReader reader(session);
    double trip_s = -1.0;
    for (const SessionEvent& event : reader.events()) {
      if (event.kind == "safety" && event.detail.rfind("velocity_trip:", 0) == 0) {
        trip_s = event.time_s;
      }
    }
    REQUIRE(trip_s >= 0.0);
    double speed = 0.0;
    const auto vx = reader.read("velocity_x"), vy = reader.read("velocity_y"),
               vz = reader.read("velocity_z");
    for (std::size_t i = 0; i < vx.raw.size(); ++i) {
      if (vx.time_s[i] == trip_s) speed = std::hypot(vx.raw[i], vy.raw[i], vz.raw[i]);
    }
    expect_stop(run, session,
                "velocity_trip: the device moved at " + doorbench::format_significant(speed, 3) +
                    " m/s, above the trip speed of 1 m/s (velocity_trip, or the device's "
                    "max_velocity)");
  }
  SECTION("an error reply") {
    HapticMasterEmulator emulator({"--fail-after", "3000=Amplifier overheated"});
    const fs::path session = dir / "refused.h5";
    const DoorbenchRun run = play(emulator.name(), 5.0, session, dir);
    // The refused command is whichever of the round trip's came 3001st.
    const std::string err = run.err;
    const std::size_t quote = err.find(": '");
    REQUIRE(quote != std::string::npos);
    const std::string command = err.substr(quote + 3, err.find("' failed", quote) - quote - 3);
    expect_stop(run, session,
                "link_lost: " + emulator.name() + ": '" + command +
                    "' failed: Amplifier overheated; the device was stopped (zero force, state "
                    "stop)");
  }
}
