// `doorbench campaign` as a command: runs of simulated participants on the simulated device,
// resume after SIGKILL in the middle of a trial (the final trials.csv equals an uninterrupted
// run's, times aside), the operator's output blind, a finished participant refused, a
// device fault that keeps the answers given, merge, and the HapticMaster emulator.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/session/session_file.h"
#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "study/campaign_file.h"
#include "study/campaign_plan.h"
#include "study/campaign_summary.h"
#include "study/quest_plus.h"
#include "study/trials_table.h"
#include "study/tuning_keys.h"
#include "tests/support/files.h"
#include "tests/support/hapticmaster_emulator_process.h"
#include "tests/support/run_on_terminal.h"
#include "tests/support/trials_rows.h"

using doorbench::testing::read_file;
using doorbench::testing::TempDir;
namespace fs = std::filesystem;

namespace {

struct Child {
  pid_t pid = -1;
  fs::path out, err;
};

Child start(const std::vector<std::string>& args, const fs::path& dir,
            const std::string& stdin_path = "/dev/null") {
  static int counter = 0;
  Child child;
  const std::string tag = std::to_string(counter++);
  child.out = dir / ("out_" + tag + ".txt");
  child.err = dir / ("err_" + tag + ".txt");
  std::vector<std::string> storage = {DOORBENCH_EXECUTABLE};
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& arg : storage) argv.push_back(arg.data());
  argv.push_back(nullptr);
  const std::string out = child.out.string(), err = child.err.string();
  child.pid = ::fork();
  REQUIRE(child.pid >= 0);
  if (child.pid == 0) {
    const int in_fd = ::open(stdin_path.c_str(), O_RDONLY);
    const int out_fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err_fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in_fd < 0 || out_fd < 0 || err_fd < 0) ::_exit(126);
    if (::dup2(in_fd, 0) < 0 || ::dup2(out_fd, 1) < 0 || ::dup2(err_fd, 2) < 0) ::_exit(126);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return child;
}

// The exit status, or -SIGNAL.
int wait_for(const Child& child) {
  int status = 0;
  ::waitpid(child.pid, &status, 0);
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? -WTERMSIG(status) : -1000;
}

struct Result {
  int status = 0;
  std::string out, err;
};

Result run(const std::vector<std::string>& args, const fs::path& dir,
           const std::string& stdin_path = "/dev/null") {
  const Child child = start(args, dir, stdin_path);
  Result result;
  result.status = wait_for(child);
  result.out = read_file(child.out);
  result.err = read_file(child.err);
  return result;
}

// 4 variants; tune, pair (2-AC), rating, jnd by constant stimuli and by a staircase.
// `extra`: more blocks appended.
std::string campaign_text(int participants, const std::string& extra = "") {
  return "[campaign]\nname = \"kill\"\nseed = 11\nsimulated_presentation_s = 0.2\n"
         "[variants]\nreference = \"base\"\nheavier = \"heaviness*1.2\"\n"
         "easier_unlatch = \"latch_effort*0.7\"\nlighter_smoother = \"J*0.85,smoothness*0.8\"\n"
         "[participants]\ncount = " +
         std::to_string(participants) +
         "\n"
         "[[blocks]]\nname = \"tune\"\ntype = \"tune\"\n"
         "[[blocks]]\nname = \"pair\"\ntype = \"pair\"\nquestion = \"preference-2ac\"\n"
         "[[blocks]]\nname = \"rating\"\ntype = \"rating\"\nattributes = [\"heavy-light\"]\nscale "
         "= 7\n"
         "[[blocks]]\nname = \"jnd-J\"\ntype = \"jnd\"\nparameter = \"J\"\nlevels = [1.1, "
         "1.3]\nrepetitions = 2\n"
         "[[blocks]]\nname = \"jnd-latch\"\ntype = \"jnd\"\nparameter = \"latch_effort\"\nmethod = "
         "\"staircase\"\ntrials = 6\n" +
         extra;
}

fs::path plan(const TempDir& dir, const std::string& name, int participants,
              const std::string& seed = "11", const std::string& extra = "") {
  const fs::path campaign = dir.write("c.toml", campaign_text(participants, extra));
  const Result result =
      run({"campaign", "plan", campaign.string(), "--out", (dir / name).string(), "--seed", seed},
          dir.path);
  REQUIRE(result.status == 0);
  return dir / name;
}

std::vector<std::string> run_args(const fs::path& folder, const std::string& participant) {
  return {"campaign", "run", folder.string(), "--participant", participant, "--respondent", "sim",
          "--device", "sim"};
}

std::size_t count_rows_of(const fs::path& trials, const std::string& participant) {
  std::ifstream in(trials);
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) n += line.rfind(participant + ",", 0) == 0;
  return n;
}

bool trial_started(const fs::path& sessions, int trial) {
  if (!fs::exists(sessions)) return false;
  char prefix[16];
  std::snprintf(prefix, sizeof prefix, "t%03d-", trial);
  for (const auto& entry : fs::directory_iterator(sessions)) {
    if (entry.path().filename().string().rfind(prefix, 0) == 0) return true;
  }
  return false;
}

// Runs `participant`, SIGKILLs it once its trial `kill_in` has begun (a presentation of it on
// disk, the answers before it written), and runs the same command again to the end.
void run_killed(const fs::path& folder, const std::string& participant, int kill_in,
                const fs::path& scratch) {
  const Child child = start(run_args(folder, participant), scratch);
  const fs::path sessions = folder / "sessions" / participant / "a1";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  bool reached = false;
  while (std::chrono::steady_clock::now() < deadline) {
    if (count_rows_of(folder / "trials.csv", participant) >=
            static_cast<std::size_t>(kill_in - 1) &&
        trial_started(sessions, kill_in)) {
      reached = true;
      break;
    }
    int status = 0;
    if (::waitpid(child.pid, &status, WNOHANG) == child.pid)
      FAIL("the run ended before trial " << kill_in);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  REQUIRE(reached);
  ::kill(child.pid, SIGKILL);
  REQUIRE(wait_for(child) == -SIGKILL);
  const std::size_t kept = count_rows_of(folder / "trials.csv", participant);
  CHECK(kept >= static_cast<std::size_t>(kill_in - 1));
  const Result again = run(run_args(folder, participant), scratch);
  INFO(again.err);
  REQUIRE(again.status == 0);
  if (kept > 0)
    CHECK_THAT(again.err,
               Catch::Matchers::Contains("resuming at trial " + std::to_string(kept + 1)));
}

void kill_and_compare(int participants, const std::vector<std::pair<int, int>>& kills,
                      const std::string& extra = "", int trials_each = 29) {
  TempDir dir("campaign_kill");
  const fs::path whole = plan(dir, "whole", participants, "11", extra);
  const fs::path killed = plan(dir, "killed", participants, "11", extra);
  for (int p = 1; p <= participants; ++p) {
    char id[8];
    std::snprintf(id, sizeof id, "P%02d", p);
    REQUIRE(run(run_args(whole, id), dir.path).status == 0);
    bool was_killed = false;
    for (const auto& [who, trial] : kills) {
      if (who == p) {
        run_killed(killed, id, trial, dir.path);
        was_killed = true;
      }
    }
    if (!was_killed) REQUIRE(run(run_args(killed, id), dir.path).status == 0);
  }
  const auto expected = doorbench::testing::trials_rows_without_time(whole / "trials.csv");
  const auto got = doorbench::testing::trials_rows_without_time(killed / "trials.csv");
  REQUIRE(expected.size() == static_cast<std::size_t>(participants * trials_each));
  REQUIRE(got.size() == expected.size());
  for (std::size_t r = 0; r < expected.size(); ++r) {
    INFO("row " << r + 1);
    CHECK(got[r] == expected[r]);
  }
  for (const auto& [who, trial] : kills) {
    char id[8];
    std::snprintf(id, sizeof id, "P%02d", who);
    CHECK(fs::exists(killed / "sessions" / id / "interrupted"));
  }
}

}  // namespace

TEST_CASE("campaign run: a run SIGKILLed in the middle of a trial resumes to the same trials.csv",
          "[study][campaign][cli]") {
  // Killed in the tune trial, in a pair trial, and in the staircase's middle.
  kill_and_compare(3, {{1, 1}, {2, 9}, {3, 24}});
}

TEST_CASE(
    "campaign run: 20 simulated participants, three killed mid-trial, equal an uninterrupted run",
    "[study][campaign][cli][slow]") {
  kill_and_compare(20, {{2, 5}, {9, 17}, {20, 27}});
}

TEST_CASE(
    "campaign run: the operator's output names no variant, and a finished participant is refused",
    "[study][campaign][cli]") {
  TempDir dir("campaign_blind");
  const fs::path folder = plan(dir, "c", 2);
  const Result first = run(run_args(folder, "P01"), dir.path);
  INFO(first.err);
  REQUIRE(first.status == 0);
  CHECK_THAT(first.err, Catch::Matchers::Contains("trial 29 of 29: presentation 2"));
  for (const char* name : {"reference", "heavier", "easier_unlatch", "lighter_smoother",
                           "heaviness", "J*", "latch_effort*"}) {
    INFO(name);
    CHECK(first.err.find(name) == std::string::npos);
    CHECK(first.out.find(name) == std::string::npos);
  }
  const Result again = run(run_args(folder, "P01"), dir.path);
  CHECK(again.status == 1);
  CHECK(again.err ==
        "doorbench campaign run: participant P01 on sim\n"
        "doorbench: participant P01 has answered all 29 trials (attempt 1); give --redo to run "
        "them again (the earlier "
        "answers are kept, marked by attempt)\n");
  std::vector<std::string> redo = run_args(folder, "P01");
  redo.push_back("--redo");
  REQUIRE(run(redo, dir.path).status == 0);
  const auto table = doorbench::study::read_trials_table(folder / "trials.csv");
  REQUIRE(table.rows.size() == 58);
  CHECK(table.value(0, "attempt") == "1");
  CHECK(table.value(57, "attempt") == "2");
  CHECK(table.value(57, "sessions").rfind("sessions/P01/a2/", 0) == 0);

  const Result named =
      run({"campaign", "run", folder.string(), "--participant", "Anna Berg"}, dir.path);
  CHECK(named.status == 2);
  CHECK_THAT(named.err, Catch::Matchers::StartsWith(
                            "doorbench: participant id 'Anna Berg' looks like a name (it holds "
                            "a space); use a pseudonymous id such as P07"));
  // The spelling: the participant is the plan's, the simulated respondent is --respondent.
  const Result sim = run({"campaign", "run", folder.string(), "--participant", "sim:42"}, dir.path);
  CHECK(sim.status == 2);
  CHECK_THAT(sim.err, Catch::Matchers::StartsWith(
                          "doorbench: --participant names a participant of the plan (such as "
                          "P01), not sim:42; a simulated participant answers that participant's "
                          "trials with --participant P01 --respondent sim:42 (see doorbench "
                          "campaign run --help)\n"));
  const Result mail =
      run({"campaign", "run", folder.string(), "--participant", "a.b@example.org"}, dir.path);
  CHECK(mail.status == 2);
  CHECK_THAT(mail.err, Catch::Matchers::StartsWith(
                           "doorbench: participant id 'a.b@example.org' looks like an e-mail "
                           "address; use a pseudonymous id such as P07"));
}

TEST_CASE(
    "campaign run: answers that end, a wrong answer and a device fault stop the run, and the "
    "answers given stay",
    "[study][campaign][cli]") {
  TempDir dir("campaign_fault");
  // A person's answers, without the tune block (a person's tuning is the next test's).
  std::string text = campaign_text(1);
  text.erase(text.find("[[blocks]]\nname = \"tune\""),
             std::string("[[blocks]]\nname = \"tune\"\ntype = \"tune\"\n").size());
  const fs::path campaign = dir.write("person.toml", text);
  REQUIRE(run({"campaign", "plan", campaign.string(), "--out", (dir / "p").string()}, dir.path)
              .status == 0);
  const fs::path folder = dir / "p";
  const auto plan_table = doorbench::study::read_trials_table(
      folder / "plan.csv", std::vector<std::string_view>{"question"});
  REQUIRE(plan_table.value(0, "question") == "preference-2ac");
  const fs::path answers = dir.write("answers.txt", "1\nsame\n2\n");
  const std::vector<std::string> person = {
      "campaign", "run", folder.string(), "--participant", "P01", "--answers", answers.string()};
  const Result ended = run(person, dir.path);
  CHECK(ended.status == 1);
  CHECK_THAT(ended.err,
             Catch::Matchers::EndsWith("doorbench: trial 4 of 28 stopped: " + answers.string() +
                                       ": the answers ended at trial 4 (the 3 "
                                       "answers before it are in " +
                                       (folder / "trials.csv").string() +
                                       "; run the same command again to resume)\n"));
  CHECK(count_rows_of(folder / "trials.csv", "P01") == 3);
  dir.write("answers.txt", "9\n");
  const Result wrong = run(person, dir.path);
  CHECK(wrong.status == 1);
  CHECK_THAT(wrong.err,
             Catch::Matchers::Contains(answers.string() +
                                       ":1: trial 4: expected \"1\", \"2\" or \"same\" "
                                       "(which felt better; same: no preference), got \"9\""));
  CHECK(count_rows_of(folder / "trials.csv", "P01") == 3);
  // The device is not there: trial 4 stops, the 3 answers stay; then the rest on the
  // simulated device, resumed at trial 4.
  dir.write("answers.txt", "1\n");
  std::vector<std::string> faulty = person;
  faulty.insert(faulty.end(), {"--device", "hapticmaster://127.0.0.1:1"});
  const Result fault = run(faulty, dir.path);
  CHECK(fault.status == 1);
  CHECK_THAT(fault.err, Catch::Matchers::Contains("doorbench: trial 4 of 28 stopped: "));
  CHECK(count_rows_of(folder / "trials.csv", "P01") == 3);
  const Result rest = run(run_args(folder, "P01"), dir.path);
  INFO(rest.err);
  REQUIRE(rest.status == 0);
  CHECK_THAT(rest.err, Catch::Matchers::Contains("resuming at trial 4 of 28"));
  const auto table = doorbench::study::read_trials_table(folder / "trials.csv");
  REQUIRE(table.rows.size() == 28);
  CHECK(table.value(0, "answer") == "1");
  CHECK(table.value(1, "answer") == "same");
  CHECK(table.value(2, "answer") == "2");
}

TEST_CASE(
    "campaign run: a person tunes in a tune trial with the keys, scripted in the answers file",
    "[study][campaign][cli]") {
  TempDir dir("campaign_person_tune");
  // Tune then pair (2 blocks: P01 takes them in this order).
  std::string text = campaign_text(1);
  const std::size_t rating = text.find("[[blocks]]\nname = \"rating\"");
  text.erase(rating);
  const fs::path campaign_path = dir.write("tune.toml", text);
  REQUIRE(run({"campaign", "plan", campaign_path.string(), "--out", (dir / "t").string()}, dir.path)
              .status == 0);
  const fs::path folder = dir / "t";
  const doorbench::study::CampaignFolder opened = doorbench::study::open_campaign_folder(folder);
  REQUIRE(opened.plan.rows.at(0).question == "tune");
  REQUIRE(opened.plan.rows.size() == 13);
  std::vector<std::string> person = {"campaign",
                                     "run",
                                     folder.string(),
                                     "--participant",
                                     "P01",
                                     "--answers",
                                     (dir / "answers.txt").string()};

  // An unknown key: the run stops naming the file, the line and the key; nothing answered.
  dir.write("answers.txt", "+x\n");
  const Result wrong = run(person, dir.path);
  CHECK(wrong.status == 1);
  CHECK_THAT(wrong.err,
             Catch::Matchers::EndsWith(
                 "doorbench: trial 1 of 13 stopped: " + (dir / "answers.txt").string() +
                 ":1: trial 1: a tune trial's line holds the keys pressed (+ - U u C c S s N n r; "
                 "empty: the "
                 "start kept), not 'x' (the 0 answers before it are in " +
                 (folder / "trials.csv").string() + "; run the same command again to resume)\n"));
  // More keys than the presentation (0.2 s: one press every 0.1 s) has room for.
  dir.write("answers.txt", "++u+\n");
  const Result short_run = run(person, dir.path);
  CHECK(short_run.status == 1);
  CHECK_THAT(short_run.err, Catch::Matchers::Contains("trial 1: the presentation ended after "));
  CHECK_THAT(short_run.err,
             Catch::Matchers::Contains(
                 " of the 4 keys (one is pressed every 0.1 s); give a longer --presentation-s"));
  CHECK_FALSE(
      (fs::exists(folder / "trials.csv") && count_rows_of(folder / "trials.csv", "P01") > 0));

  // Heavier twice, easier to unlatch, then the 12 pair answers.
  std::string answers = "+ + u\n";
  for (int i = 0; i < 12; ++i) answers += i % 3 == 0 ? "same\n" : "1\n";
  dir.write("answers.txt", answers);
  person.insert(person.end(), {"--presentation-s", "1"});
  const Result tuned_run = run(person, dir.path);
  INFO(tuned_run.err);
  REQUIRE(tuned_run.status == 0);
  CHECK_THAT(tuned_run.err, Catch::Matchers::Contains("trial 1: tuning with 3 keys from " +
                                                      (dir / "answers.txt").string() + ":1\n"));
  CHECK_THAT(tuned_run.err,
             Catch::Matchers::Contains("key +: played\nkey +: played\nkey u: played\n"));
  const auto table = doorbench::study::read_trials_table(folder / "trials.csv");
  REQUIRE(table.rows.size() == 13);
  CHECK(table.value(0, "question") == "tune");
  CHECK(table.value(0, "answer") == "sessions/P01/a1/t001-tuned.json");
  CHECK(table.value(1, "answer") == "same");
  // The tuned file is the start with the three keys applied, as a person's presses would.
  const doorbench::DoorModel start =
      doorbench::study::apply_steps(doorbench::study::base_model(opened.campaign),
                                    doorbench::study::parse_steps(opened.plan.rows[0].first));
  doorbench::DoorModel expected = start;
  for (char key : {'+', '+', 'u'}) expected = *doorbench::study::apply_key(expected, key).model;
  const doorbench::DoorModel tuned = doorbench::load_model(
      doorbench::ModelKind::kSensory, folder / "sessions" / "P01" / "a1" / "t001-tuned.json", "");
  REQUIRE(tuned.parameter_values().size() == expected.parameter_values().size());
  for (std::size_t i = 0; i < tuned.parameter_values().size(); ++i) {
    CHECK(tuned.parameter_values()[i] == Approx(expected.parameter_values()[i]).epsilon(1e-9));
  }
  const auto tuned_values = tuned.parameter_values(), start_values = start.parameter_values();
  CHECK_FALSE(std::equal(tuned_values.begin(), tuned_values.end(), start_values.begin()));
  // Each press is a tuning event of the tuning presentation's session, each change a
  // parameter set played.
  const doorbench::SessionReader reader(folder / "sessions" / "P01" / "a1" / "t001-1.h5");
  int tuning_events = 0, parameter_events = 0;
  for (const doorbench::SessionEvent& event : reader.events()) {
    tuning_events += event.kind == "tuning";
    parameter_events += event.kind == "parameters";
  }
  CHECK(tuning_events == 3);
  CHECK(parameter_events >= 3);
  // The operator's screen names no variant.
  for (const char* name : {"reference", "heavier", "easier_unlatch", "lighter_smoother"}) {
    CHECK(tuned_run.err.find(name) == std::string::npos);
  }
}

TEST_CASE("campaign run: a person tunes on the terminal's keys until Enter, then answers there",
          "[study][campaign][cli]") {
  // stdin is a pseudo-terminal (openpty), as the participant's keypad and the operator's
  // keyboard would be: "+" and "u" while the start plays (in real time), Enter, then the 12
  // pair answers as lines.
  TempDir dir("campaign_terminal_tune");
  std::string text = campaign_text(1);
  text.erase(text.find("[[blocks]]\nname = \"rating\""));
  const fs::path campaign_path = dir.write("tune.toml", text);
  REQUIRE(run({"campaign", "plan", campaign_path.string(), "--out", (dir / "t").string()}, dir.path)
              .status == 0);
  const fs::path folder = dir / "t";
  std::string typed = "+u\n";
  for (int i = 0; i < 12; ++i) typed += "2\n";
  const doorbench::testing::DoorbenchRun result = doorbench::testing::run_doorbench_on_terminal(
      {"campaign", "run", folder.string(), "--participant", "P01"}, dir, typed, 300);
  INFO(result.err);
  REQUIRE(result.status == 0);
  CHECK_THAT(result.err,
             Catch::Matchers::Contains("trial 1: tune with the keys, Enter when done\n"));
  CHECK_THAT(result.err, Catch::Matchers::Contains("key +: played\nkey u: played\n"));
  const auto table = doorbench::study::read_trials_table(folder / "trials.csv");
  REQUIRE(table.rows.size() == 13);
  CHECK(table.value(0, "answer") == "sessions/P01/a1/t001-tuned.json");
  for (std::size_t r = 1; r < 13; ++r) CHECK(table.value(r, "answer") == "2");
  const doorbench::study::CampaignFolder opened = doorbench::study::open_campaign_folder(folder);
  doorbench::DoorModel expected =
      doorbench::study::apply_steps(doorbench::study::base_model(opened.campaign),
                                    doorbench::study::parse_steps(opened.plan.rows[0].first));
  for (char key : {'+', 'u'}) expected = *doorbench::study::apply_key(expected, key).model;
  const doorbench::DoorModel tuned = doorbench::load_model(
      doorbench::ModelKind::kSensory, folder / "sessions" / "P01" / "a1" / "t001-tuned.json", "");
  for (std::size_t i = 0; i < tuned.parameter_values().size(); ++i) {
    CHECK(tuned.parameter_values()[i] == Approx(expected.parameter_values()[i]).epsilon(1e-9));
  }
}

TEST_CASE("campaign merge joins folders of one plan and refuses another plan's",
          "[study][campaign][cli]") {
  TempDir dir("campaign_merge");
  const fs::path a = plan(dir, "a", 2);
  const fs::path b = plan(dir, "b", 2);
  const fs::path other = plan(dir, "other", 2, "12");
  REQUIRE(run(run_args(a, "P01"), dir.path).status == 0);
  REQUIRE(run(run_args(b, "P02"), dir.path).status == 0);
  const Result merged =
      run({"campaign", "merge", a.string(), b.string(), "--out", (dir / "m").string()}, dir.path);
  INFO(merged.err);
  REQUIRE(merged.status == 0);
  const auto table = doorbench::study::read_trials_table(dir / "m" / "trials.csv");
  CHECK(table.rows.size() == 58);
  CHECK(fs::exists(dir / "m" / "sessions" / "P02" / "a1" / "t029-2.h5"));
  CHECK(read_file(dir / "m" / "plan.csv") == read_file(a / "plan.csv"));

  const Result refused = run(
      {"campaign", "merge", a.string(), other.string(), "--out", (dir / "m2").string()}, dir.path);
  CHECK(refused.status == 1);
  CHECK_THAT(refused.err,
             Catch::Matchers::StartsWith("doorbench: " + other.string() + " and " + a.string() +
                                         " are not of the same plan (plan "));
  CHECK_THAT(refused.err, Catch::Matchers::Contains(" seed 12 vs plan "));
  const Result twice =
      run({"campaign", "merge", a.string(), a.string(), "--out", (dir / "m3").string()}, dir.path);
  CHECK(twice.status == 1);
}

TEST_CASE("campaign run: the same plan on the HapticMaster emulator",
          "[study][campaign][cli][hapticmaster]") {
  TempDir dir("campaign_hm");
  const fs::path folder = plan(dir, "c", 1);
  doorbench::testing::HapticMasterEmulator emulator;
  // The tune trial first in P01's order is played like any other; presentations short.
  const Result result =
      run({"campaign", "run", folder.string(), "--participant", "P01", "--respondent", "sim",
           "--device", emulator.name(), "--presentation-s", "0.2"},
          dir.path);
  INFO(result.err);
  REQUIRE(result.status == 0);
  CHECK(count_rows_of(folder / "trials.csv", "P01") == 29);
  CHECK(fs::exists(folder / "sessions" / "P01" / "a1" / "t029-2.h5"));
}

TEST_CASE(
    "campaign run: a quest+ jnd block runs with --respondent sim, its levels are QUEST+'s, and a "
    "kill resumes",
    "[study][campaign][cli][quest]") {
  const std::string quest =
      "[[blocks]]\nname = \"jnd-q\"\ntype = \"jnd\"\nparameter = \"J\"\nmethod = "
      "\"quest+\"\ntrials = 8\n";
  TempDir dir("campaign_quest");
  const fs::path folder = plan(dir, "c", 2, "11", quest);
  const doorbench::study::CampaignFolder opened = doorbench::study::open_campaign_folder(folder);
  const doorbench::study::Block& block = opened.campaign.blocks.back();
  REQUIRE(block.method == doorbench::study::JndMethod::kQuestPlus);
  // Each participant's trial number of the quest+ block's 5th slot: where the kills go.
  std::vector<std::pair<int, int>> kills;
  for (const doorbench::study::PlanRow& row : opened.plan.rows) {
    if (row.block == "jnd-q" && row.block_trial == 5)
      kills.emplace_back(std::stoi(row.participant.substr(1)), row.trial);
  }
  REQUIRE(kills.size() == 2);
  REQUIRE(run(run_args(folder, "P01"), dir.path).status == 0);
  REQUIRE(run(run_args(folder, "P02"), dir.path).status == 0);
  const doorbench::study::TrialsTable table =
      doorbench::study::read_trials_table(folder / "trials.csv");
  for (const std::string participant : {"P01", "P02"}) {
    std::vector<bool> answers;
    for (std::size_t r = 0; r < table.rows.size(); ++r) {
      if (table.value(r, "participant") != participant || table.value(r, "block") != "jnd-q")
        continue;
      const std::string& first = table.value(r, "first");
      const std::string& second = table.value(r, "second");
      const std::string comparison = first == "J*1" ? second : first;
      INFO(participant << " " << first << " " << second);
      CHECK(table.value(r, "question") == "stronger:J");
      CHECK(comparison == doorbench::study::jnd_stimulus_name(
                              "J", doorbench::study::quest_plus_level(block, answers)));
      answers.push_back(table.value(r, "answer") == (first == "J*1" ? "2" : "1"));
    }
    CHECK(answers.size() == 8);
  }
  const std::vector<std::string> lines = doorbench::study::block_summaries(opened.campaign, table);
  INFO(lines.back());
  CHECK_THAT(lines.back(), Catch::Matchers::Contains("16 answers; median threshold J*1."));
  CHECK_THAT(lines.back(), Catch::Matchers::Contains(
                               "over 2 participants; QUEST+ posterior mean Weber fraction [95 % "
                               "credible interval]: P01 0."));
  // Killed in the middle of the quest+ block: the resumed trials.csv equals an uninterrupted run's.
  kill_and_compare(2, kills, quest, 37);
}
