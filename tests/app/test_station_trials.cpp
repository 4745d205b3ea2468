// `campaign run --station` and `ab --station` under Xvfb: a participant's answers given on the
// station's window (pressed there from an answers file, or by a simulated participant, as
// key presses and clicks through the station's input) reach trials.csv and answers.csv row
// for row as the same answers typed on stdin do; the operator's terminal shows progress, not
// the question.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "fixtures/temp_dir.h"
#include "study/trials_table.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/trials_rows.h"

using doorbench::testing::DoorbenchRun;
using doorbench::testing::read_file;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;
namespace fs = std::filesystem;

namespace {

const std::string kStationXvfb = "xvfb-run -a -s '-screen 0 1280x1024x24 -noreset'";

// tune (a person's keys), pair (2-AC), rating on two attributes, jnd by constant stimuli and
// by a staircase (whose levels follow the answers).
constexpr const char* kStationCampaign = R"(
[campaign]
name = "station"
seed = 23
simulated_presentation_s = 0.2
[variants]
reference = "base"
heavier = "heaviness*1.2"
easier_unlatch = "latch_effort*0.7"
[participants]
count = 2
[[blocks]]
name = "tune"
type = "tune"
[[blocks]]
name = "pair"
type = "pair"
question = "preference-2ac"
[[blocks]]
name = "rating"
type = "rating"
attributes = ["heavy-light", "pleasant"]
scale = 5
pairs = [["reference", "heavier"]]
[[blocks]]
name = "jnd-J"
type = "jnd"
parameter = "J"
levels = [1.1, 1.3]
[[blocks]]
name = "jnd-latch"
type = "jnd"
parameter = "latch_effort"
method = "staircase"
trials = 4
)";

fs::path planned(const TempDir& dir, const std::string& name,
                 const std::string& text = kStationCampaign) {
  const fs::path campaign = dir.path / "station.toml";
  std::ofstream(campaign) << text;
  const DoorbenchRun run = run_doorbench_shell(
      "campaign plan '" + campaign.string() + "' --out '" + (dir.path / name).string() + "'", dir);
  REQUIRE(run.status == 0);
  return dir.path / name;
}

std::string run_participant(const fs::path& folder, const std::string& options) {
  return "campaign run '" + folder.string() + "' --participant P01 --device sim " + options;
}

// The answers a person would give: the simulated participant's, from its run, and for a
// tune trial the keys pressed (two: one each 0.1 s of a 0.2 s presentation).
std::string answers_from(const fs::path& folder) {
  const doorbench::study::TrialsTable table =
      doorbench::study::read_trials_table(folder / "trials.csv");
  std::string answers;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    answers += table.value(r, "question") == "tune" ? "+ U" : table.value(r, "answer");
    answers += "\n";
  }
  return answers;
}

}  // namespace

TEST_CASE("campaign run --station: answers on the station equal the same answers on stdin",
          "[station][xvfb][campaign]") {
  TempDir dir("station_trials");
  // The simulated participant's answers, then typed on stdin...
  const fs::path simulated = planned(dir, "simulated");
  DoorbenchRun run = run_doorbench_shell(run_participant(simulated, "--respondent sim"), dir);
  REQUIRE(run.status == 0);
  std::ofstream(dir.path / "answers.txt") << answers_from(simulated);
  const fs::path typed = planned(dir, "typed");
  run = run_doorbench_shell(run_participant(typed, "--respondent person"), dir, "",
                            "cat '" + (dir.path / "answers.txt").string() + "'");
  INFO("stdin run: " << run.err);
  REQUIRE(run.status == 0);

  // ...and pressed on the station.
  const fs::path on_station = planned(dir, "on_station");
  run = run_doorbench_shell(
      run_participant(on_station, "--station --no-sound --answers '" +
                                      (dir.path / "answers.txt").string() + "'"),
      dir, kStationXvfb);
  INFO("station run: " << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.out, Catch::Matchers::Contains("station: "));
  const std::vector<std::vector<std::string>> rows =
      doorbench::testing::trials_rows_without_time(typed / "trials.csv");
  REQUIRE(rows.size() >= 8);
  CHECK(doorbench::testing::trials_rows_without_time_and_staging(on_station / "trials.csv") ==
        doorbench::testing::trials_rows_without_time_and_staging(typed / "trials.csv"));
  // The station's own scene was shown, silent (--no-sound); without the station nothing.
  for (const std::string& scene :
       doorbench::testing::trials_column(on_station / "trials.csv", "first_scene"))
    CHECK(scene == "built-in");
  for (const std::string& sounds :
       doorbench::testing::trials_column(on_station / "trials.csv", "second_sounds"))
    CHECK(sounds == "none");
  for (const std::string& scene :
       doorbench::testing::trials_column(typed / "trials.csv", "second_scene"))
    CHECK(scene == "none");
  // The tuned doors are the same files.
  CHECK(read_file(on_station / "sessions/P01/a1/t001-tuned.json") ==
        read_file(typed / "sessions/P01/a1/t001-tuned.json"));
  // The operator saw progress and no question.
  CHECK_THAT(run.err, Catch::Matchers::Contains("trial 11: asked on the station, "));
  CHECK_THAT(run.err, !Catch::Matchers::Contains("prefer"));
  CHECK_THAT(run.err, !Catch::Matchers::Contains("which felt"));
  CHECK_THAT(run.err, !Catch::Matchers::Contains("heavier"));

  // The simulated participant answering through the station's input equals its run without.
  const fs::path simulated_on_station = planned(dir, "simulated_on_station");
  run = run_doorbench_shell(
      run_participant(simulated_on_station, "--station --no-sound --respondent sim"), dir,
      kStationXvfb);
  INFO("simulated station run: " << run.err);
  REQUIRE(run.status == 0);
  CHECK(doorbench::testing::trials_rows_without_time_and_staging(simulated_on_station /
                                                                 "trials.csv") ==
        doorbench::testing::trials_rows_without_time_and_staging(simulated / "trials.csv"));
}

TEST_CASE("ab --station: answers on the station equal the same answers on stdin",
          "[station][xvfb][ab]") {
  TempDir dir("station_ab");
  const std::string reference = DOORBENCH_SOURCE_DIR "/analysis/data/reference-door.json";
  std::ofstream(dir.path / "answers.txt") << "4 1\n2 2\n1,3\n3 4\n5 2\n1 1\n";
  const std::string ab = "ab --a '" + reference + "' --b '" + reference +
                         "' --trials 6 --seed 8 --question rating:5 --presentation-s 0.2 " +
                         "--labels left right --out ";
  DoorbenchRun run = run_doorbench_shell(ab + "'" + (dir.path / "typed").string() + "'", dir, "",
                                         "cat '" + (dir.path / "answers.txt").string() + "'");
  INFO("stdin run: " << run.err);
  REQUIRE(run.status == 0);
  run = run_doorbench_shell(ab + "'" + (dir.path / "on_station").string() +
                                "' --station --no-sound --answers '" +
                                (dir.path / "answers.txt").string() + "'",
                            dir, kStationXvfb);
  INFO("station run: " << run.err);
  REQUIRE(run.status == 0);
  // answers.csv without its last column, the time of each answer.
  auto answers_of = [](const fs::path& csv) {
    std::ifstream in(csv);
    std::vector<std::string> rows;
    for (std::string line; std::getline(in, line);) rows.push_back(line.substr(0, line.rfind(',')));
    return rows;
  };
  const std::vector<std::string> typed = answers_of(dir.path / "typed" / "answers.csv");
  REQUIRE(typed.size() == 7);
  CHECK(answers_of(dir.path / "on_station" / "answers.csv") == typed);
  CHECK_THAT(run.err, Catch::Matchers::Contains("trial 6 of 6: asked on the station, "));
  CHECK_THAT(run.err, !Catch::Matchers::Contains("rate "));

  // A rating scale the station's keys cannot cover is refused before the device moves.
  run = run_doorbench_shell("ab --a '" + reference + "' --b '" + reference +
                                "' --question rating:12 --out '" + (dir.path / "wide").string() +
                                "' --station",
                            dir, kStationXvfb);
  CHECK(run.status == 2);
  CHECK_THAT(run.err, Catch::Matchers::Contains(
                          "doorbench: --station: the station asks ratings of 2 to 9 points (keys "
                          "1 to 9); this one has 12"));
  CHECK_FALSE(fs::exists(dir.path / "wide"));
}

namespace {

// Variants staged in scenes and a sound set (docs/campaign.md, "Scenes and sound sets"), and
// a jnd block whose stimuli are no variant (the station's own scene).
constexpr const char* kStagedCampaign = R"(
[campaign]
name = "staged"
seed = 29
simulated_presentation_s = 0.3
[variants]
oak = { door = "base", scene = "scenes/oak.toml" }
steel = { door = "heaviness*1.2", scene = "scenes/steel.toml", sounds = "sounds/steel.toml" }
plain = "latch_effort*0.7"
[participants]
count = 1
[[blocks]]
name = "pair"
type = "pair"
[[blocks]]
name = "jnd"
type = "jnd"
parameter = "J"
levels = [1.2, 1.4]
)";

// What trials.csv must say for `stimulus` on a station with sound (`sound`) or without.
std::pair<std::string, std::string> staged_as(const std::string& stimulus, bool sound) {
  if (stimulus == "oak") return {"scenes/oak.toml", sound ? "scenes/oak.toml" : "none"};
  if (stimulus == "steel") return {"scenes/steel.toml", sound ? "sounds/steel.toml" : "none"};
  return {"built-in", sound ? "built-in" : "none"};
}

void check_staging(const fs::path& trials, bool station, bool sound) {
  const doorbench::study::TrialsTable table = doorbench::study::read_trials_table(trials);
  REQUIRE(table.rows.size() == 8);
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    for (const std::string position : {"first", "second"}) {
      INFO("row " << r + 1 << ", " << position << ": " << table.value(r, position));
      const auto [scene, sounds] = staged_as(table.value(r, position), sound);
      CHECK(table.value(r, position + "_scene") == (station ? scene : "none"));
      CHECK(table.value(r, position + "_sounds") == (station ? sounds : "none"));
    }
  }
}

}  // namespace

TEST_CASE("campaign run --station: each variant shown in its scene with its sounds, in trials.csv",
          "[station][xvfb][campaign]") {
  TempDir dir("station_staged");
  dir.write("scenes/oak.toml", "[colours]\ndoor_rgb = [0.6, 0.4, 0.2]\n");
  dir.write("scenes/steel.toml", "[colours]\ndoor_rgb = [0.8, 0.8, 0.85]\n");
  dir.write("sounds/steel.toml", "[sound]\nlatch_gain = 2.0\nhinge_gain = 0.2\n");
  // Without the station: the plan runs, nothing shown or heard.
  const fs::path unseen = planned(dir, "unseen", kStagedCampaign);
  DoorbenchRun run = run_doorbench_shell(run_participant(unseen, "--respondent sim"), dir);
  INFO("run without the station: " << run.err);
  REQUIRE(run.status == 0);
  check_staging(unseen / "trials.csv", false, false);

  // On the station, silent.
  const fs::path silent = planned(dir, "silent", kStagedCampaign);
  run = run_doorbench_shell(run_participant(silent, "--respondent sim --station --no-sound"), dir,
                            kStationXvfb);
  INFO("silent station run: " << run.err);
  REQUIRE(run.status == 0);
  check_staging(silent / "trials.csv", true, false);
  CHECK(doorbench::testing::trials_rows_without_time_and_staging(silent / "trials.csv") ==
        doorbench::testing::trials_rows_without_time_and_staging(unseen / "trials.csv"));

  // With sound, into OpenAL Soft's wave writer (no sound card needed).
  dir.write("alsoft.conf", "[general]\ndrivers = wave\n\n[wave]\nfile = " +
                               (dir.path / "output.wav").string() + "\n");
  const fs::path heard = planned(dir, "heard", kStagedCampaign);
  run = run_doorbench_shell(run_participant(heard, "--respondent sim --station"), dir,
                            "env ALSOFT_DRIVERS=wave ALSOFT_CONF='" +
                                (dir.path / "alsoft.conf").string() + "' " + kStationXvfb);
  INFO("station run with sound: " << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.out, Catch::Matchers::Contains("sound: "));
  check_staging(heard / "trials.csv", true, true);

  // A scene the campaign names that is gone by the run: refused before the device moves.
  fs::remove(dir.path / "scenes/oak.toml");
  const fs::path folder = dir.path / "silent";
  run = run_doorbench_shell(run_participant(folder, "--respondent sim --station --redo"), dir,
                            kStationXvfb);
  CHECK(run.status != 0);
  CHECK_THAT(run.err, Catch::Matchers::Contains(
                          "variants.oak.scene: no such file 'scenes/oak.toml' (looked for " +
                          (dir.path / "scenes/oak.toml").string() + ")"));
}
