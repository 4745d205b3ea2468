// `doorbench campaign analyze` on hand-written trials tables (the seven columns, no
// campaign folder), run as a process.
#include <signal.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "tests/study/simulated_panel.h"
#include "tests/support/doorbench_process.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"

using doorbench::testing::append_row;
using doorbench::testing::kTrialsHeader;
using doorbench::testing::read_file;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

namespace {

void write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

// A by hand: A vs B 10 times in both orders (A preferred 3 times, B 6, once same); an
// identify-real block of 8 trials, 6 correct.
std::string hand_table() {
  std::string text = kTrialsHeader;
  const char* answers[] = {"2", "2", "1", "same", "2", "1", "2", "1", "2", "2"};
  for (int t = 0; t < 10; ++t) {
    const bool a_first = t % 2 == 0;
    // Answers refer to positions: "2" in an A-first trial and "1" in a B-first one prefer B.
    append_row(text, {t < 5 ? "P1" : "P2", "pair", std::to_string(t + 1), "preference-2ac",
                      a_first ? "A" : "B", a_first ? "B" : "A", answers[t]});
  }
  const char* ir[] = {"1", "2", "1", "2", "1", "1", "2", "2"};  // real first on odd trials
  for (int t = 0; t < 8; ++t) {
    const bool real_first = t % 2 == 0;
    append_row(text, {"P1", "ir", std::to_string(t + 1), "identify-real", real_first ? "real" : "A",
                      real_first ? "A" : "real", ir[t]});
  }
  return text;
}

}  // namespace

TEST_CASE("campaign analyze reads a hand-written trials table and writes every output", "[study]") {
  TempDir dir("campaign_analyze");
  write(dir / "trials.csv", hand_table());
  const auto run = run_doorbench_shell("campaign analyze '" + (dir / "trials.csv").string() +
                                           "' --out '" + (dir / "out").string() + "'",
                                       dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const auto analysis = nlohmann::json::parse(read_file(dir / "out" / "analysis.json"));
  // The estimates themselves are checked in test_preference_scale.cpp and
  // test_discrimination.cpp; here: the sections, the counts and the sign.
  REQUIRE(analysis["preference_scale"].size() == 2);
  CHECK(analysis["preference_scale"][0]["variant"] == "A");
  CHECK(analysis["preference_scale"][1]["variant"] == "B");
  CHECK(analysis["preference_scale"][1]["worth"].get<double>() > 0);
  CHECK(analysis.contains("ties"));
  CHECK(analysis.contains("order_effect"));
  const auto& two_ac = analysis["two_ac"];
  REQUIRE(two_ac.size() == 1);
  CHECK(two_ac[0]["prefer_first"] == 3);
  CHECK(two_ac[0]["no_preference"] == 1);
  CHECK(two_ac[0]["prefer_second"] == 6);
  const auto& panel = analysis["identify_real"]["panel"];
  CHECK(panel["n"] == 8);
  CHECK(panel["correct"] == 6);
  CHECK(panel["dprime"].get<double>() == Approx(std::sqrt(2.0) * 0.6744897501960817));
  CHECK(analysis["identify_real"]["verdict"].get<std::string>().rfind(
            "no evidence of a difference, but the data cannot exclude |d'| up to 2.62: d' 0.95 [",
            0) == 0);
  CHECK(analysis["identify_real"]["conclusion"] == "inconclusive");
  CHECK(analysis["identify_real"]["equivalence_margin"] == 1.0);
  for (const char* file :
       {"report.html", "preference-scale.svg", "identify-real.svg", "two-ac.svg"})
    CHECK(std::filesystem::exists(dir / "out" / file));
  CHECK(read_file(dir / "out" / "report.html").find("Preference scale") != std::string::npos);
  if (std::system("command -v weasyprint > /dev/null 2>&1") == 0)
    CHECK(read_file(dir / "out" / "report.pdf").rfind("%PDF", 0) == 0);
  CHECK(run.out.find("2-AC A vs B: no evidence of a preference, but the data cannot exclude "
                     "|d'| up to ") != std::string::npos);
}

TEST_CASE("campaign analyze takes a campaign folder and --quiet silences stderr", "[study]") {
  TempDir dir("campaign_analyze_folder");
  std::filesystem::create_directories(dir / "campaign");
  write(dir / "campaign" / "trials.csv", hand_table());
  const auto run = run_doorbench_shell("campaign analyze '" + (dir / "campaign").string() +
                                           "' --out '" + (dir / "out").string() + "' --no-pdf -q",
                                       dir);
  CHECK(run.status == 0);
  CHECK(run.err.empty());
  CHECK(std::filesystem::exists(dir / "out" / "analysis.json"));
  CHECK_FALSE(std::filesystem::exists(dir / "out" / "report.pdf"));
  // Again with --overwrite into a folder holding an earlier run's PDF and plots this campaign
  // does not draw: they do not stay beside a report.html that does not describe them; a file
  // of the user's stays.
  write(dir / "out" / "report.pdf", "%PDF of an earlier run\n");
  write(dir / "out" / "ratings-smooth.svg", "<svg/>\n");
  write(dir / "out" / "jnd-k_lock.svg", "<svg/>\n");
  write(dir / "out" / "my-notes.svg", "<svg/>\n");
  std::filesystem::create_directories(dir / "out" / "variants");
  write(dir / "out" / "variants" / "gone.json", "{}\n");
  const auto again =
      run_doorbench_shell("campaign analyze '" + (dir / "campaign").string() + "' --out '" +
                              (dir / "out").string() + "' --no-pdf -q --overwrite",
                          dir);
  CHECK(again.status == 0);
  CHECK_FALSE(std::filesystem::exists(dir / "out" / "report.pdf"));
  CHECK_FALSE(std::filesystem::exists(dir / "out" / "ratings-smooth.svg"));
  CHECK_FALSE(std::filesystem::exists(dir / "out" / "jnd-k_lock.svg"));
  CHECK(std::filesystem::exists(dir / "out" / "my-notes.svg"));
  CHECK_FALSE(std::filesystem::exists(dir / "out" / "variants" / "gone.json"));
  CHECK(std::filesystem::exists(dir / "out" / "report.html"));
}

TEST_CASE("campaign analyze's errors name the file and line, or the option", "[study]") {
  TempDir dir("campaign_analyze_errors");
  write(dir / "bad.csv", std::string(kTrialsHeader) + "P1,pair,1,preference,A,B,maybe\n");
  const std::string out = (dir / "out").string();
  auto run = run_doorbench_shell(
      "campaign analyze '" + (dir / "bad.csv").string() + "' --out '" + out + "' --no-pdf", dir);
  CHECK(run.status == 1);
  CHECK(run.err.find("doorbench: " + (dir / "bad.csv").string() +
                     ":2: answer 'maybe' to a preference question (expected 1 or 2)\n") !=
        std::string::npos);

  std::filesystem::create_directories(dir / "empty");
  run = run_doorbench_shell(
      "campaign analyze '" + (dir / "empty").string() + "' --out '" + out + "'", dir);
  CHECK(run.status == 2);
  CHECK(run.err == "doorbench: " + (dir / "empty").string() +
                       ": is a folder without trials.csv (give a campaign folder or a trials "
                       "table) (see doorbench campaign analyze --help)\n");

  write(dir / "good.csv", hand_table());
  std::filesystem::create_directories(dir / "full");
  write(dir / "full" / "x", "x");
  run = run_doorbench_shell("campaign analyze '" + (dir / "good.csv").string() + "' --out '" +
                                (dir / "full").string() + "'",
                            dir);
  CHECK(run.status == 2);
  CHECK(run.err == "doorbench: " + (dir / "full").string() +
                       ": exists and is not empty (give --overwrite to write into it)\n");

  run = run_doorbench_shell(
      "campaign analyze '" + (dir / "good.csv").string() + "' --out '" + out + "' --bootstrap 50",
      dir);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --bootstrap: must be 0 (none) or at least 100 resamples, got 50 "
        "(see doorbench campaign analyze --help)\n");
  run = run_doorbench_shell("campaign analyze '" + (dir / "good.csv").string() + "' --out '" + out +
                                "' --equivalence-dprime 0",
                            dir);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --equivalence-dprime: 0 is outside 0.05 to 5 (see doorbench campaign "
        "analyze --help)\n");

  std::filesystem::create_directories(dir / "campaign");
  write(dir / "campaign" / "trials.csv", hand_table());
  run = run_doorbench_shell("campaign analyze '" + (dir / "campaign").string() + "' --out '" +
                                (dir / "campaign").string() + "' --overwrite",
                            dir);
  CHECK(run.status == 2);
  CHECK(run.err == "doorbench: " + (dir / "campaign").string() +
                       ": holds an input of this command (" +
                       (dir / "campaign" / "trials.csv").string() +
                       ") (doorbench never writes onto its input)\n");
  CHECK_FALSE(std::filesystem::exists(dir / "campaign" / "analysis.json"));
}

TEST_CASE("campaign analyze shows the bootstrap's progress on stderr, and -q drops it", "[study]") {
  TempDir dir("campaign_analyze_progress");
  doorbench::testing::PairPanel panel;
  panel.participants = 8;
  panel.worths = {0.0, 0.3, -0.3, 1.5};  // D clearly the favourite
  std::ofstream(dir / "trials.csv")
      << kTrialsHeader << doorbench::testing::simulate_pairs(panel, 5);
  const std::string args =
      "campaign analyze '" + (dir / "trials.csv").string() + "' --no-pdf --bootstrap 200 --out ";
  auto run = run_doorbench_shell(args + "'" + (dir / "loud").string() + "'", dir);
  INFO(run.out);
  CHECK(run.status == 0);
  CHECK(run.err.find("preference bootstrap: 200 of 200 resamples, done in ") != std::string::npos);
  CHECK(run.out.find("favourite: D (probability ") != std::string::npos);
  run = run_doorbench_shell(args + "'" + (dir / "quiet").string() + "' -q", dir);
  CHECK(run.status == 0);
  CHECK(run.err.empty());
  CHECK(run.out.find("favourite: D (probability ") != std::string::npos);
}

// Ratings, thresholds and tuning (study/statistics/ratings.h, thresholds.h, tuning.h)
// through the verb: their sections, plots and the tune rows' files
// read beside the table.
TEST_CASE("campaign analyze writes the ratings, jnd and tuning sections and their plots",
          "[study]") {
  TempDir dir("campaign_analyze_others");
  std::string text = kTrialsHeader;
  doorbench::testing::PanelRandom random(8);
  auto door = nlohmann::json::parse(doorbench::reference_door_json());
  const double reference_j = door["sensory"]["J"]["value"].get<double>();
  for (int p = 1; p <= 6; ++p) {
    const std::string id = std::string("P0").append(std::to_string(p));
    for (int r = 0; r < 3; ++r) {  // B rated about two points heavier than A
      const int a = 2 + (p + r) % 3, b = std::min(7, a + 2 - (r == 2 ? 1 : 0));
      append_row(text, {id, "rating", std::to_string(r + 1), "rating:heavy:7", "A", "B",
                        std::to_string(a).append(" ").append(std::to_string(b))});
    }
    int trial = 0;
    for (int rep = 0; rep < 8; ++rep) {
      for (const char* level :
           {"J_d*0.80", "J_d*0.90", "J_d*0.95", "J_d*1.05", "J_d*1.10", "J_d*1.20"}) {
        const double factor = std::stod(std::string(level).substr(4));
        const double p_stronger = 0.5 * std::erfc(-std::log(factor) / 0.12 / std::sqrt(2.0));
        const bool stronger = random.uniform() < p_stronger;
        const bool comparison_first = ++trial % 2 == 1;
        append_row(text,
                   {id, "jnd", std::to_string(trial), "stronger:J_d",
                    comparison_first ? level : "J_d*1.00", comparison_first ? "J_d*1.00" : level,
                    stronger == comparison_first ? "1" : "2"});
      }
    }
    door["sensory"]["J"]["value"] = reference_j * (p > 3 ? 1.1 : 1.0) * (1.0 + 0.01 * p);
    dir.write("campaign/tuned/" + id + ".json", door.dump());
    append_row(text, {id, "tune", "1", "tune", "", "", "tuned/" + id + ".json"});
  }
  dir.write("campaign/trials.csv", text);
  const auto run = run_doorbench_shell("campaign analyze '" + (dir / "campaign").string() +
                                           "' --no-pdf --out '" + (dir / "out").string() + "'",
                                       dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const auto analysis = nlohmann::json::parse(read_file(dir / "out" / "analysis.json"));
  REQUIRE(analysis["ratings"].size() == 2);
  CHECK(analysis["ratings"][1]["variant"] == "B");
  CHECK(analysis["ratings"][1]["ci_low"].get<double>() > 0.0);
  REQUIRE(analysis["jnd"].size() >= 1);
  CHECK(analysis["jnd"][0]["participant"] == "panel");
  CHECK(analysis["jnd"][0]["trials"] == 288);
  CHECK(analysis["tuning"]["doors"].size() == 6);
  CHECK_FALSE(analysis.contains("preference_scale"));
  CHECK(std::filesystem::exists(dir / "out" / "jnd-J_d.svg"));
  CHECK(std::filesystem::exists(dir / "out" / "tuning.svg"));
  const std::string html = read_file(dir / "out" / "report.html");
  CHECK(html.find("<h2>Ratings</h2>") != std::string::npos);
  CHECK(html.find("<h2>Thresholds (jnd)</h2>") != std::string::npos);
}

TEST_CASE("campaign analyze stopped by SIGINT during the bootstrap ends within a second, marked",
          "[study][signal]") {
  TempDir dir("campaign_analyze_interrupt");
  doorbench::testing::PairPanel panel;
  panel.participants = 60;
  panel.worths = {0.0, 0.3, -0.3, 1.5};
  std::ofstream(dir / "trials.csv")
      << kTrialsHeader << doorbench::testing::simulate_pairs(panel, 9);
  // Enough resamples to last many seconds: the signal comes in the middle of them.
  doorbench::testing::DoorbenchProcess analyze(
      {"campaign", "analyze", (dir / "trials.csv").string(), "--bootstrap", "200000", "--out",
       (dir / "out").string()},
      (dir / "stdout.txt").string());
  REQUIRE(analyze.wait_for("preference bootstrap: 0 of 200000", 300));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto signalled = std::chrono::steady_clock::now();
  analyze.send_signal(SIGINT);
  const int status = analyze.wait_exit(60);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  INFO(analyze.err());
  CHECK(status == 130);
  CHECK(seconds <= 1.0);
  const auto analysis = nlohmann::json::parse(read_file(dir / "out" / "analysis.json"));
  const std::string where =
      "during the preference scale's bootstrap: it and the sections after it were not computed";
  CHECK(analysis["interrupted"] == where);
  CHECK_FALSE(analysis.contains("preference_scale"));
  CHECK_FALSE(std::filesystem::exists(dir / "out" / "report.pdf"));
  CHECK(std::filesystem::exists(dir / "out" / "report.html"));
  CHECK_THAT(analyze.err(), Catch::EndsWith("doorbench: campaign analyze: SIGINT stopped the "
                                            "analysis " +
                                            where + "; the results in " + (dir / "out").string() +
                                            "/ are marked interrupted\n"));
}

// The notes say why the intervals are Wald's: no bootstrap asked for, or too few people.
TEST_CASE("campaign analyze's notes say why the intervals are Wald intervals", "[study]") {
  TempDir dir("campaign_analyze_notes");
  doorbench::testing::PairPanel panel;
  panel.participants = 8;
  std::ofstream(dir / "trials.csv")
      << kTrialsHeader << doorbench::testing::simulate_pairs(panel, 6);
  auto run =
      run_doorbench_shell("campaign analyze '" + (dir / "trials.csv").string() +
                              "' --no-pdf --bootstrap 0 --out '" + (dir / "a").string() + "'",
                          dir);
  REQUIRE(run.status == 0);
  CHECK(run.out.find("note: Wald intervals: no participant bootstrap was asked for (--bootstrap "
                     "0), so the intervals assume the participants agree\n") != std::string::npos);
  panel.participants = 4;
  std::ofstream(dir / "few.csv") << kTrialsHeader << doorbench::testing::simulate_pairs(panel, 6);
  run = run_doorbench_shell("campaign analyze '" + (dir / "few.csv").string() +
                                "' --no-pdf --out '" + (dir / "b").string() + "'",
                            dir);
  REQUIRE(run.status == 0);
  CHECK(run.out.find("note: Wald intervals: 4 participants, fewer than the 6 a participant "
                     "bootstrap needs; they assume the participants agree\n") != std::string::npos);
}
