// The haptic path on a busy computer, through the command line and in real time: `play`, `ab`
// and `campaign run` on the HapticMaster protocol emulator (a process of its own), on the
// simulated HapticMaster and on the rotary device, while the test keeps every CPU busy with
// twice as many spinning processes as there are cores (tests/support/busy_processes.h); and
// each kind of stop named on stderr and in the session, word for word.
//
// The emulator runs at SCHED_FIFO 70 where the test may (below the play's tick at 80), else at
// the normal priority beside the spinners; either way it shares the test's CPUs, so its replies
// are less regular than a real HapticMaster's (which has a processor of its own): the harder
// case for the driver's watchdog and the safety layer's stall checks.
//
// A run that stops for a stall while the machine itself held a CPU (PauseWatch) is run again,
// at most kHeldRunsMax times per test case: that stop is the stall check doing its job. A stall
// without a hold fails the test.
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

// Whether a run that stopped with `stop` (its stderr) stopped for a stall while a CPU of the
// machine was held long enough to cause it: a stalled tick (0.1 s between two ticks) and a
// 90 ms hold, or a stalled device reading (50 ticks) and a 45 ms hold.
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

// Runs one attempt of a load test's command and runs it again while it stopped for a stall
// while a CPU was held, at most kHeldRunsMax times over the test case. `attempt(n)` runs the
// command for the n-th time in the test case (so that each writes its own files) and returns
// its DoorbenchRun; run() returns the last.
class ReplayWhenHeld {
 public:
  explicit ReplayWhenHeld(const PauseWatch& watch) : watch_(watch) {}

  template <class Attempt>
  DoorbenchRun run(const std::string& what, Attempt&& attempt) {
    for (;;) {
      const double started_s = doorbench::monotonic_now_s();
      DoorbenchRun result = attempt(attempts_++);
      if (result.status == 0 || held_ >= kHeldRunsMax ||
          !stalled_while_held(result.err, watch_, started_s, doorbench::monotonic_now_s())) {
        return result;
      }
      WARN(what << ": a CPU was held (longest gap so far " << watch_.longest_gap_s()
                << " s) and the run stalled with it; run again");
      ++held_;
    }
  }

 private:
  const PauseWatch& watch_;
  int attempts_ = 0;
  int held_ = 0;
};

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
  ReplayWhenHeld replay(watch);
  int played = 0;
  for (int run = 1; run <= 20; ++run) {
    fs::path session;
    const DoorbenchRun result = replay.run("run " + std::to_string(run), [&](int attempt) {
      session = dir / ("play-" + std::to_string(attempt) + ".h5");
      return play(emulator.name(), 3.0, session, dir);
    });
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
  const PauseWatch watch;
  ReplayWhenHeld replay(watch);
  for (const std::string device : {"sim", "sim:rotary"}) {
    for (int run = 1; run <= 3; ++run) {
      const std::string what = device + ", run " + std::to_string(run) + " of 3";
      fs::path session;
      const DoorbenchRun result = replay.run(what, [&](int attempt) {
        session = dir / ("play-" + device.substr(device.find(':') + 1) + "-" +
                         std::to_string(attempt) + ".h5");
        return play(device, 3.0, session, dir);
      });
      INFO(what << " with " << busy.count() << " busy processes");
      check_played_through(result, session, 3.0);
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
  ReplayWhenHeld replay(watch);
  for (const std::string& device :
       {emulator.name(), std::string("sim --real-time"), std::string("sim:rotary --real-time")}) {
    fs::path out;
    const DoorbenchRun run = replay.run(device, [&](int attempt) {
      out = dir / ("ab-" + std::to_string(attempt));
      return run_doorbench_shell("ab --a '" + kReference + "' --b '" + kReference +
                                     "' --trials 2 --seed 3 --presentation-s 1.5 --device " +
                                     device + " --answers '" + (dir / "answers.txt").string() +
                                     "' --out '" + out.string() + "'",
                                 dir);
    });
    INFO(device << " with " << busy.count() << " busy processes");
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
  ReplayWhenHeld replay(watch);
  const auto run_campaign = [&](const std::string& device, const std::string& what,
                                const std::string& extra) {
    fs::path folder;
    const DoorbenchRun result = replay.run(what, [&](int attempt) {
      folder = plan_small_campaign(dir, "campaign-" + std::to_string(attempt));
      return run_doorbench_shell("campaign run '" + folder.string() +
                                     "' --participant P01 --respondent sim --device " + device +
                                     extra,
                                 dir);
    });
    INFO(what << " with " << busy.count() << " busy processes: " << result.err);
    CHECK(result.status == 0);
    CHECK(answered_trials(folder) == 2);
    return result.status == 0 && answered_trials(folder) == 2;
  };
  int finished = 0;
  for (int run = 1; run <= 10; ++run) {
    if (run_campaign(emulator.name(), "run " + std::to_string(run) + " of 10", "")) ++finished;
  }
  CHECK(finished == 10);
  for (const std::string device : {"sim", "sim:rotary"}) {
    run_campaign(device, device, " --real-time");
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
