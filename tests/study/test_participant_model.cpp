// The simulated participant, the staircase, the answers' checks and the power's interval.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "study/campaign_file.h"
#include "study/campaign_run.h"
#include "study/participant_model.h"
#include "study/power.h"
#include "study/random_stream.h"
#include "study/staircase.h"

using namespace doorbench::study;
using doorbench::DoorModel;
using doorbench::uniform_open01;

namespace {
DoorModel with_steps(const DoorModel& base, const std::string& steps) {
  return apply_steps(base, parse_steps(steps));
}
}  // namespace

TEST_CASE("A simulated participant tells its Weber fraction apart 75 % of the time",
          "[study][participant]") {
  const DoorModel base = doorbench::reference_model(doorbench::ModelKind::kSensory);
  ParticipantModelOptions options;
  options.weber_spread = 0.0;
  options.lapse_rate = 0.0;
  options.position_bias_sd = 0.0;
  const SimulatedParticipant p = draw_participant(11, base, options);
  CHECK(p.weber[0] == Approx(0.10));
  // heaviness × 1.10 against the base: named stronger with probability 0.75.
  const DoorModel heavier = with_steps(base, "heaviness*1.1");
  std::mt19937_64 random(5);
  int right = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const bool comparison_first = i % 2 == 0;
    const std::string answer = answer_question(p, "stronger:J", comparison_first ? heavier : base,
                                               comparison_first ? base : heavier, random);
    right += answer == (comparison_first ? "1" : "2");
  }
  // 0.75 within 4.5 standard deviations of a binomial proportion of n.
  CHECK(std::abs(right / double(n) - 0.75) < 4.5 * std::sqrt(0.75 * 0.25 / n));
  // Four JNDs: nearly always right.
  const DoorModel much = with_steps(base, "latch_effort*1.8");
  right = 0;
  for (int i = 0; i < 2000; ++i)
    right += answer_question(p, "stronger:k_inf", base, much, random) == "2";
  CHECK(right > 1980);
}

TEST_CASE("A simulated participant prefers the door nearer its preference and tunes towards it",
          "[study][participant]") {
  const DoorModel base = doorbench::reference_model(doorbench::ModelKind::kSensory);
  ParticipantModelOptions options;
  options.preference_spread_jnd = 0.0;  // prefers the base door exactly
  options.lapse_rate = 0.0;
  const SimulatedParticipant p = draw_participant(3, base, options);
  const DoorModel far = with_steps(base, "heaviness*1.5,latch_effort*0.6");
  std::mt19937_64 random(9);
  int base_chosen = 0, same = 0, same_far = 0;
  for (int i = 0; i < 500; ++i) {
    base_chosen += answer_question(p, "preference", base, far, random) == "1";
    same += answer_question(p, "preference-2ac", base, with_steps(base, "heaviness*1.01"),
                            random) == "same";
    same_far += answer_question(p, "preference-2ac", base, far, random) == "same";
  }
  CHECK(base_chosen > 475);
  CHECK(same > 150);           // a difference far below a JND: often "same"
  CHECK(same_far * 3 < same);  // far apart: "same" much less often
  // Tuning from a start 30 % off brings every sensation within about one JND of the base.
  const TuneOutcome tuned = tune_door(p, with_steps(base, "heaviness*1.3,smoothness*0.75"), random);
  CHECK(!tuned.keys.empty());
  const auto felt = sensations(tuned.model), wanted = sensations(base);
  for (int s = 0; s < kSensations; ++s)
    CHECK(std::abs(felt[s] - wanted[s]) < 2.0 * std::log1p(p.weber[s]));
}

TEST_CASE("A 2-down-1-up staircase converges on the 70.7 % level", "[study][staircase]") {
  Block block;
  block.type = BlockType::kJnd;
  block.method = JndMethod::kStaircase;
  block.down = 2;
  block.start_level = 1.5;
  block.step_factor = 1.25;
  block.min_level = 1.001;
  block.max_level = 3.0;
  // An observer right with probability 0.5 + 0.5 (1 − exp(−(Δ/0.1)^2)): 70.7 % at
  // Δ = 0.1 · sqrt(−ln(1 − 0.414)) = 0.0731.
  const double target = 0.1 * std::sqrt(-std::log(1.0 - 0.41421356));
  std::mt19937_64 random(1);
  double log_sum = 0.0;
  const int runs = 400;
  for (int run = 0; run < runs; ++run) {
    std::vector<bool> correct;
    for (int trial = 0; trial < 80; ++trial) {
      const double delta = staircase_level(block, correct) - 1.0;
      const double p = 0.5 + 0.5 * (1.0 - std::exp(-(delta / 0.1) * (delta / 0.1)));
      correct.push_back(uniform_open01(random) < p);
    }
    log_sum += std::log(staircase_threshold(block, correct) - 1.0);
  }
  const double estimate = std::exp(log_sum / runs);
  CHECK(estimate == Approx(target).epsilon(0.15));
  // The track: two right answers make it smaller, one wrong larger.
  CHECK(staircase_level(block, {}) == Approx(1.5));
  CHECK(staircase_level(block, {true}) == Approx(1.5));
  CHECK(staircase_level(block, {true, true}) == Approx(1.4));
  CHECK(staircase_level(block, {true, true, false}) == Approx(1.5));
  CHECK(std::isnan(staircase_threshold(block, {true, true})));
}

TEST_CASE("Answers are checked against their question, word for word", "[study][campaign]") {
  CHECK(normalized_answer("preference-2ac", " same ") == "same");
  CHECK(normalized_answer("rating:heavy-light:7", "7,1") == "7 1");
  CHECK_THROWS_WITH(
      normalized_answer("preference-2ac", "3"),
      "expected \"1\", \"2\" or \"same\" (which felt better; same: no preference), got \"3\"");
  CHECK_THROWS_WITH(normalized_answer("preference", "same"),
                    "expected \"1\" or \"2\" (which felt better), got \"same\"");
  CHECK_THROWS_WITH(normalized_answer("stronger:J", "x"),
                    "expected \"1\" or \"2\" (which felt stronger), got \"x\"");
  CHECK_THROWS_WITH(
      normalized_answer("rating:pleasant:5", "6 1"),
      "rating 6 is outside 1..5: expected two ratings from 1 to 5, one per presentation "
      "(e.g. \"5 1\"), got \"6 1\"");
  CHECK_THROWS_WITH(normalized_answer("colour", "1"), "unknown question \"colour\"");
}

TEST_CASE("The power's Wilson interval covers the true rate about 95 % of the time",
          "[study][power]") {
  std::mt19937_64 random(2);
  for (double truth : {0.1, 0.5, 0.8}) {
    for (int n : {30, 100}) {
      int covered = 0;
      const int trials = 4000;
      for (int t = 0; t < trials; ++t) {
        int k = 0;
        for (int i = 0; i < n; ++i) k += uniform_open01(random) < truth;
        const auto [low, high] = wilson_interval(k, n);
        covered += low <= truth && truth <= high;
      }
      // Wilson's interval is close to nominal (a little above it for small n·p).
      CHECK(covered / double(trials) > 0.925);
      CHECK(covered / double(trials) < 0.985);
    }
  }
}

TEST_CASE(
    "Power: a large effect is detected more often than a small one, and more participants help",
    "[study][power]") {
  const std::string text =
      "[campaign]\nseed = 4\n[variants]\nreference = \"base\"\nslightly = \"heaviness*1.03\"\nmuch "
      "= \"heaviness*1.6\"\n"
      "[participants]\ncount = 12\n"
      "[[blocks]]\nname = \"pair\"\ntype = \"pair\"\npairs = [[\"reference\", \"slightly\"], "
      "[\"reference\", \"much\"]]\n"
      "[[blocks]]\nname = \"jnd\"\ntype = \"jnd\"\nparameter = \"J\"\nlevels = [1.02, "
      "1.3]\nrepetitions = 2\n";
  const Campaign campaign = parse_campaign(text, "c.toml", ".");
  PowerOptions options;
  options.panels = 60;
  const auto lines = simulate_power(campaign, 4, options);
  std::map<std::string, double> rate;
  for (const PowerLine& line : lines) rate[line.what] = line.rate;
  CHECK(rate.at("much vs reference") > 0.9);
  CHECK(rate.at("reference vs slightly") < 0.3);
  CHECK(rate.at("level J*1.3") > 0.9);
  CHECK(rate.at("level J*1.02") < 0.3);
}
