// doorbench ab run as a program: scripted answers from a file and from stdin, variant A vs B
// and the (simulated) real door vs a virtual one, the files it leaves and their counts
// (checked against the plan the same seed gives), and its refusals by their text.

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "fixtures/temp_dir.h"
#include "study/ab_trials.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/run_on_terminal.h"

using doorbench::testing::read_file;

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;
namespace study = doorbench::study;

namespace {

const std::string kReference = DOORBENCH_SOURCE_DIR "/analysis/data/reference-door.json";
const std::string kRig = DOORBENCH_SOURCE_DIR "/rigs/simulated-dishwasher.toml";

// Variant A: the reference door made heavier, so that A and B differ.
std::string write_heavier(const TempDir& dir) {
  std::string json = read_file(kReference);
  const std::string from = "\"value\": 0.95";
  REQUIRE(json.find(from) != std::string::npos);
  json.replace(json.find(from), from.size(), "\"value\": 1.4");
  const std::string path = (dir.path / "heavier.json").string();
  std::ofstream(path) << json;
  return path;
}

}  // namespace

TEST_CASE("doorbench ab: A vs B with scripted answers leaves sessions, answers and summary",
          "[ab][cli]") {
  TempDir dir("ab_cli");
  const std::string heavier = write_heavier(dir);
  study::AbOptions options;
  options.trials = 4;
  options.seed = 99;
  const auto plan = study::make_plan(options);
  // B chosen in trials 1-3, A in trial 4: 3 of 4 B preferred, p = 0.625.
  std::string answers;
  for (const auto& trial : plan) {
    const std::string want = trial.trial < 4 ? "B" : "A";
    answers += trial.variant[0] == want ? "1\n" : "2\n";
  }
  std::ofstream(dir.path / "answers.txt") << answers;
  const auto out = dir.path / "out";
  const auto run = run_doorbench_shell(
      "ab --a '" + heavier + "' --b '" + kReference + "' --trials 4 --seed 99 --presentation-s 2 " +
          "--out '" + out.string() + "' --answers '" + (dir.path / "answers.txt").string() + "'",
      dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.out, Contains("preferred: A 1, B 3"));
  CHECK_THAT(run.out, Contains("3 of 4 B preferred over A, p = 0.625"));
  CHECK_THAT(run.err, Contains("trial 4 of 4: presentation 2"));
  for (int trial = 1; trial <= 4; ++trial) {
    for (int position = 1; position <= 2; ++position) {
      const auto session_path =
          out / ("trial-0" + std::to_string(trial) + "-" + std::to_string(position) + ".h5");
      REQUIRE(std::filesystem::exists(session_path));
      const doorbench::SessionReader session(session_path);
      // The session says what was played (for the analysis, after unblinding).
      const std::string& variant = plan[trial - 1].variant[position - 1];
      CHECK_THAT(session.metadata().notes,
                 Contains("variant " + variant + " (" + (variant == "A" ? heavier : kReference)));
      // 2 s of ticks at 1 kHz, then the safety layer's 20 ms stop ramp.
      CHECK(session.sample_count("force") == 2021);
      CHECK(session.read_group_attribute("haptic", "device") == "sim:hapticmaster");
    }
  }
  const std::string csv = read_file(out / "answers.csv");
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 5);
  const auto summary = nlohmann::json::parse(read_file(out / "ab-summary.json"));
  CHECK(summary["counts"]["a_preferred"] == 1);
  CHECK(summary["counts"]["b_preferred"] == 3);
  CHECK(summary["seed"] == 99);
  CHECK(summary["binomial_test"]["p_value"].get<double>() == Approx(0.625));
  REQUIRE(summary["key"].size() == 4);
  CHECK(summary["key"][0]["first"] == plan[0].variant[0]);
  CHECK_THAT(read_file(out / "ab-summary.txt"), Contains("key (trial: first, second -> answer)"));
}

TEST_CASE("doorbench ab: the real door (simulated rig) vs the model, answers on stdin",
          "[ab][cli]") {
  TempDir dir("ab_cli_real");
  const auto out = dir.path / "out";
  study::AbOptions options;
  options.trials = 2;
  options.seed = 5;
  options.a_is_real = true;
  options.question = study::QuestionKind::kIdentifyReal;
  const auto plan = study::make_plan(options);
  // Right in both trials.
  std::string answers;
  for (const auto& trial : plan) answers += trial.variant[0] == "real" ? "L\\n" : "R\\n";
  const auto run =
      run_doorbench_shell("ab --real-rig '" + kRig + "' --b '" + kReference +
                              "' --question identify-real --trials 2 --seed 5 " +
                              "--presentation-s 1 --labels L R --out '" + out.string() + "'",
                          dir, "", "printf '" + answers + "'");
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.out, Contains("real door identified: 2 right, 0 wrong"));
  CHECK_THAT(run.out, Contains("2 of 2 the real door identified, p = 0.5"));
  CHECK_THAT(run.err, Contains("trial 2 of 2: presentation R\nwhich was the real door, L or R? "));
  for (int position = 1; position <= 2; ++position) {
    const doorbench::SessionReader session(out / ("trial-01-" + std::to_string(position) + ".h5"));
    const bool real = plan[0].variant[position - 1] == "real";
    CHECK(session.metadata().rig_name ==
          (real ? "simulated-dishwasher" : "haptic playback on sim:hapticmaster"));
  }
}

TEST_CASE("doorbench ab: refusals by their text", "[ab][cli]") {
  TempDir dir("ab_cli_errors");
  const auto out = (dir.path / "out").string();
  auto ab = [&](const std::string& args, const std::string& stdin_from = "cat /dev/null") {
    return run_doorbench_shell("ab " + args, dir, "", stdin_from);
  };
  auto run = ab("--b '" + kReference + "' --out '" + out + "'");
  CHECK(run.status == 2);
  CHECK_THAT(run.err, Contains("ab needs exactly one of --a PARAMS.json and --real-rig RIG.toml"));
  run = ab("--a '" + kReference + "' --b '" + kReference + "' --question identify-real --out '" +
           out + "'");
  CHECK(run.status == 2);
  CHECK_THAT(run.err, Contains("question identify-real needs the real door"));
  run = ab("--a '" + kReference + "' --b '" + kReference + "' --question best --out '" + out + "'");
  CHECK(run.status == 2);
  CHECK_THAT(run.err, Contains("--question must be preference, identify-real, rating or "
                               "rating:K, not best"));
  run = ab("--a '" + kReference + "' --b '" + kReference + "' --question rating:1 --out '" + out +
           "'");
  CHECK(run.status == 2);
  CHECK_THAT(run.err, Contains("rating scale K must be 2 to 100, got 1"));
  // Nobody listens on loopback port 1: the first presentation fails naming the device.
  run = ab("--a '" + kReference + "' --b '" + kReference +
           "' --device hapticmaster://127.0.0.1:1 --out '" + out + "-hm'");
  CHECK(run.status == 1);
  CHECK_THAT(run.err, Contains("trial 1, presentation 1: hapticmaster://127.0.0.1:1: "));
  run = ab("--a '" + kReference + "' --b '" + kReference + "' --device telepathy --out '" + out +
           "-x'");
  CHECK(run.status == 2);
  CHECK_THAT(run.err, Contains("--device must be sim, sim:rotary or hapticmaster://HOST[:PORT], "
                               "not telepathy"));
  run = ab("--a '" + kReference + "' --b missing.json --out '" + out + "'");
  CHECK(run.status == 1);
  CHECK_THAT(run.err, Contains("missing.json"));
  // A wrong rating on stdin (not a terminal) stops the run at its line.
  run = ab("--a '" + kReference + "' --b '" + kReference +
               "' --question rating:5 --trials 2 --presentation-s 1 --seed 1 --out '" + out + "'",
           "printf '4 2\\n6 1\\n'");
  CHECK(run.status == 1);
  CHECK_THAT(run.err, Contains("doorbench: stdin:2: trial 2: rating 6 is outside 1..5"));
  CHECK_THAT(read_file(dir.path / "out" / "ab-summary.txt"), Contains("1 of 2 trials answered"));
  // The answers ended early: a failure too, with the results so far kept.
  run = ab("--a '" + kReference + "' --b '" + kReference +
               "' --trials 2 --presentation-s 1 --out '" + out + "-2'",
           "printf '1\\n'");
  CHECK(run.status == 1);
  CHECK_THAT(run.err, Contains("stdin: the answers ended after 1 of 2 trials"));
}

TEST_CASE("doorbench ab: on a terminal a wrong answer is asked again", "[ab][cli]") {
  // stdin is a real pseudo-terminal (openpty), so doorbench takes it as interactive.
  TempDir dir("ab_cli_tty");
  const auto out = dir.path / "out";
  const doorbench::testing::DoorbenchRun run = doorbench::testing::run_doorbench_on_terminal(
      {"ab", "--a", kReference, "--b", kReference, "--trials", "2", "--seed", "4",
       "--presentation-s", "1", "--out", out.string()},
      dir, "3\n1\n2\n");
  const std::string& err = run.err;
  INFO(err);
  CHECK(run.status == 0);
  CHECK_THAT(err, Contains("expected \"1\" or \"2\" (which felt better), got \"3\"; again please"));
  CHECK_THAT(run.out, Contains("2 of 2 trials answered"));
  const std::string csv = read_file(out / "answers.csv");
  CHECK_THAT(csv, Contains("\n1,1,trial-01-1.h5"));
  CHECK_THAT(csv, Contains("\n2,2,trial-02-1.h5"));
}
