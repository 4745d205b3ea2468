// Upper bounds on work: a stiff door stops the simulator with the
// parameter that made it stiff instead of crawling for minutes; the CLI and session
// reader refuse sizes that would exhaust memory with a message, not std::bad_alloc. (The
// rig file's bounds are tested in test_rig_file.cpp.)
#include <catch2/catch.hpp>
#include <cstdlib>
#include <string>

#include "analysis/model/parameter_file.h"
#include "analysis/simulation/simulator.h"
#include "analysis/simulation/virtual_hand.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

namespace {

using doorbench::testing::DoorbenchRun;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

bool ends_with(const std::string& text, const std::string& tail) {
  return text.size() >= tail.size() &&
         text.compare(text.size() - tail.size(), tail.size(), tail) == 0;
}

// The sensory reference door with d1 (dry friction, bounds 0 to 20 N·m) at 1e6 N·m.
doorbench::DoorModel stiff_door() {
  const doorbench::DoorModel reference = doorbench::reference_model(doorbench::ModelKind::kSensory);
  std::vector<double> values(reference.parameter_values().begin(),
                             reference.parameter_values().end());
  for (int i = 0; i < static_cast<int>(values.size()); ++i) {
    if (reference.parameter_name(i) == "d1") values[static_cast<std::size_t>(i)] = 1e6;
  }
  return reference.with_parameter_values(values);
}

// The door opened and closed by the virtual hand (10 s), sampled at 1 kHz.
doorbench::Trajectory hand_run(const doorbench::DoorModel& door) {
  const doorbench::VirtualHand hand(doorbench::VirtualHandOptions{},
                                    door.geometry().handle_radius_m);
  std::vector<double> times;
  for (int i = 0; i <= 10000; ++i) times.push_back(0.001 * i);
  return doorbench::simulate(door, hand, doorbench::DoorState{}, times);
}

}  // namespace

TEST_CASE("Limits: a stiff door stops the simulator, naming the term and the parameter",
          "[limits][simulator]") {
  // Without the bound: 477 million steps and 344 s for 60 s of door (docs/simulator.md).
  const doorbench::DoorModel door = stiff_door();
  try {
    hand_run(door);
    FAIL("the run finished");
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    INFO(message);
    CHECK(message.rfind("simulation stopped at t = ", 0) == 0);
    CHECK(message.find(" steps (more than max_steps_per_s = 1e+05 per second of door): the "
                       "equation is too stiff; the stiffest term is friction (time constant ") !=
          std::string::npos);
    CHECK(ends_with(message, " s); parameters outside their bounds: d1 = 1e+06 (bounds 0 to 20)"));
  }
  // The reference door itself stays far inside the budget.
  const doorbench::Trajectory run =
      hand_run(doorbench::reference_model(doorbench::ModelKind::kSensory));
  CHECK(run.stats.accepted_steps + run.stats.rejected_steps < 2000 * 10);  // < 2 % of it
}

TEST_CASE("Limits: simulate refuses more than 10 million output samples", "[limits][cli]") {
  const TempDir dir("limits_simulate");
  const DoorbenchRun run = run_doorbench_shell(
      "simulate --model sensory --hand open-close --duration-s 3600 --rate-hz 100000 --out " +
          (dir / "r.csv").string(),
      dir);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --duration-s 3600 at --rate-hz 1e+05 gives 3.6e+08 samples; at most "
        "10000000 (see doorbench simulate --help)\n");
  CHECK(!std::filesystem::exists(dir / "r.csv"));
}

TEST_CASE("Limits: a session's 2e9-sample channel is refused by name, not by bad_alloc",
          "[limits][cli][session]") {
  const TempDir dir("limits_session");
  const auto session = dir / "s.h5";
  doorbench::testing::record_built_in_session(session, 1.0, 5, "sensory");
  // A sparse dataset (chunks never written take no space) of 2·10⁹ counts.
  const auto script = dir.write(
      "grow.py", "import h5py\nf = h5py.File('" + session.string() +
                     "', 'r+')\ndel f['channels/force/raw']\n"
                     "f.create_dataset('channels/force/raw', shape=(2000000000,), dtype='<i4', "
                     "chunks=(16384,), maxshape=(None,))\nf.close()\n");
  REQUIRE(std::system(("/usr/bin/python3 '" + script.string() + "'").c_str()) == 0);
  const DoorbenchRun exported =
      run_doorbench_shell("export " + session.string() + " --csv " + (dir / "s.csv").string(), dir);
  CHECK(exported.status == 1);
  CHECK(exported.err == "doorbench: " + session.string() +
                            ": /channels/force/raw: 2000000000 samples to read at once; at most "
                            "268435456 are (read a shorter time range)\n");
  const DoorbenchRun info = run_doorbench_shell("info " + session.string(), dir);
  INFO(info.err);
  CHECK(info.status == 0);
  CHECK(info.out.find("gaps: not checked: " + session.string() + ": /channels/force/raw: ") !=
        std::string::npos);
}
