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

fs::path planned(const TempDir& dir, const std::string& name) {
  const fs::path campaign = dir.path / "station.toml";
  std::ofstream(campaign) << kStationCampaign;
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
  CHECK(doorbench::testing::trials_rows_without_time(on_station / "trials.csv") == rows);
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
  CHECK(doorbench::testing::trials_rows_without_time(simulated_on_station / "trials.csv") ==
        doorbench::testing::trials_rows_without_time(simulated / "trials.csv"));
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
