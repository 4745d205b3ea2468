// `doorbench loop` stopped by SIGINT or SIGTERM after its first step ("Long verbs stop
// cleanly"): result.json and report.md are written with the finished steps, marked
// interrupted, and the exit status is 128 + the signal's number (app/stop_signals.h).
//
// The signal is sent when the loop's stderr says its first step was added (the stage line
// `step 1: added ...`), not after a fixed sleep: the loop on this recording has a second
// step left (seconds), so the signal always lands before its end.
#include <signal.h>

#include <catch2/catch.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/doorbench_process.h"
#include "tests/support/files.h"
#include "tests/support/loop_recording.h"
#include "tests/support/run_doorbench.h"

namespace {

using doorbench::testing::DoorbenchProcess;
using doorbench::testing::read_file;
using doorbench::testing::TempDir;

}  // namespace

TEST_CASE(
    "loop: SIGINT or SIGTERM after the first step leaves a readable result marked "
    "interrupted",
    "[cli][loop][signal]") {
  const TempDir dir("loop_interrupt");
  // The reference door with two effects its start model lacks: the loop adds the gravity
  // imbalance at step 1, the viscous damping at step 2, then runs the structure check.
  const std::string csv = doorbench::testing::simulate_loop_recording(dir);
  for (const int signal_number : {SIGINT, SIGTERM}) {
    const std::string name = signal_number == SIGINT ? "SIGINT" : "SIGTERM";
    DYNAMIC_SECTION(name) {
      const auto out = dir / ("out-" + name);
      DoorbenchProcess loop({"loop", csv, "--out", out.string()},
                            (dir / ("stdout-" + name + ".txt")).string());
      REQUIRE(loop.wait_for("\nstep 1: added gravity_imbalance", 600));
      loop.send_signal(signal_number);
      const int status = loop.wait_exit(600);
      INFO(loop.err());
      CHECK(status == 128 + signal_number);

      const nlohmann::json result = nlohmann::json::parse(read_file(out / "result.json"));
      CHECK(result.at("interrupted") == true);
      const std::string stop_reason = result.at("stop_reason");
      CHECK(stop_reason.rfind("interrupted ", 0) == 0);
      REQUIRE(result.at("steps").size() >= 1);
      CHECK(result.at("steps").at(0).at("effect") == "gravity_imbalance");
      // The structure check runs when a step's refits leave a gap (docs/residual-loop.md): on
      // this recording within step 1 (the start fit's global stage finds a basin whose refits
      // leave one), so it is kept; had it not run, it is marked as not run.
      const bool checked =
          loop.err().find("\nstructure check: ") < loop.err().find("\nstep 1: added");
      CHECK(result.at("structure_check").at("ran") == checked);
      if (!checked) {
        CHECK(result.at("structure_check").at("reason") == "not run: the loop was interrupted");
      }

      const std::size_t steps = result.at("steps").size();
      const std::string kept = steps == 1 ? "the 1 step finished before it is kept"
                                          : "the 2 steps finished before it are kept";
      const std::string line = name + " stopped the loop: " + stop_reason + "; " + kept +
                               (checked ? ", as is the structure check that ran before it"
                                        : ", the structure check was not run");
      // report.md: its title, then the line.
      const std::string report = read_file(out / "report.md");
      CHECK_THAT(report, Catch::StartsWith("# Residual loop: the sensory model on "));
      const std::size_t title_end = report.find("\n\n");
      REQUIRE(title_end != std::string::npos);
      CHECK(report.substr(title_end + 2, line.size() + 3) == line + ".\n\n");
      CHECK_THAT(loop.err(), Catch::EndsWith("\ndoorbench: loop: " + line + "; the results in " +
                                             out.string() + "/ are marked interrupted\n"));
      CHECK_THAT(read_file(dir / ("stdout-" + name + ".txt")),
                 Catch::StartsWith("Residual loop (interrupted: the steps finished before it): " +
                                   std::to_string(steps) + " effect"));
      // The fitted files are the last accepted model's, written beside it.
      CHECK(std::filesystem::exists(out / "fitted-params.json"));
      CHECK(std::filesystem::exists(out / "fitted-effects.json"));
    }
  }
}
