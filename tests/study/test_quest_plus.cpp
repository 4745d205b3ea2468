// QUEST+ for jnd blocks (study/quest_plus.h): the stimulus choice on a case computed by hand,
// convergence and the credible interval's coverage on simulated observers of known threshold.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "study/campaign_file.h"
#include "study/campaign_run.h"
#include "study/power.h"
#include "study/quest_plus.h"
#include "threshold_simulation.h"

using namespace doorbench::study;

namespace {

// Entropy (nats) of the normalised weights.
double entropy_by_hand(double a, double b) {
  const double pa = a / (a + b), pb = b / (a + b);
  return -pa * std::log(pa) - pb * std::log(pb);
}

}  // namespace

TEST_CASE("QUEST+ presents the level of least expected entropy, computed by hand on 2 x 2 points",
          "[study][quest]") {
  // Two levels, two thresholds, the slope k = 1 only (a curve through 50 % at the reference),
  // lapse 0.1, prior 1/2 each.
  QuestPlus quest(QuestPlusGrid{{1.1, 1.3}, {0.1, 0.3}, {1.0}, 0.1});
  // At its own threshold level (c = 1 + w) an observer says "stronger" with
  // 0.1/2 + 0.9 × 0.75 = 0.725; the other two from Φ(z75 · ln c / ln(1 + w)):
  // Φ(0.6745 · ln 1.1 / ln 1.3) = Φ(0.24459) = 0.59661 → 0.05 + 0.9 × 0.59661 = 0.58710;
  // Φ(0.6745 · ln 1.3 / ln 1.1) = Φ(1.85546) = 0.96832 → 0.05 + 0.9 × 0.96832 = 0.92149.
  const double p[2][2] = {{0.725, 0.58710}, {0.92149, 0.725}};  // [level][threshold]
  for (int l = 0; l < 2; ++l) {
    for (int t = 0; t < 2; ++t) CHECK(quest.probability(l, t, 0) == Approx(p[l][t]).epsilon(1e-4));
  }
  // Expected entropy of level l: Σ over the answer of P(answer) · H(posterior | answer).
  std::vector<double> by_hand;
  for (int l = 0; l < 2; ++l) {
    const double yes = 0.5 * p[l][0] + 0.5 * p[l][1], no = 1.0 - yes;
    by_hand.push_back(yes * entropy_by_hand(p[l][0], p[l][1]) +
                      no * entropy_by_hand(1.0 - p[l][0], 1.0 - p[l][1]));
  }
  // 0.68256 and 0.65835 nats: 1.3 separates the two thresholds better.
  CHECK(by_hand[0] == Approx(0.68256).epsilon(1e-4));
  CHECK(by_hand[1] == Approx(0.65835).epsilon(1e-4));
  const std::vector<double> entropies = quest.expected_entropies();
  REQUIRE(entropies.size() == 2);
  CHECK(entropies[0] == Approx(by_hand[0]).epsilon(1e-4));
  CHECK(entropies[1] == Approx(by_hand[1]).epsilon(1e-4));
  CHECK(quest.next_level() == 1);

  // "Not stronger" at 1.3: posterior ∝ (1 − 0.92149, 1 − 0.725) = (0.2221, 0.7779).
  quest.update(1, false);
  CHECK(quest.posterior()[0] == Approx(0.07851 / (0.07851 + 0.275)).epsilon(1e-3));
  CHECK(quest.posterior()[1] == Approx(0.275 / (0.07851 + 0.275)).epsilon(1e-3));
  // Posterior mean of ln w: 0.2221 ln 0.1 + 0.7779 ln 0.3 → w = 0.2351.
  CHECK(quest.estimate().weber_fraction ==
        Approx(std::exp(0.2221 * std::log(0.1) + 0.7779 * std::log(0.3))).epsilon(1e-3));
  CHECK(quest.estimate().trials == 1);
}

TEST_CASE(
    "QUEST+'s replay is a pure function of the answers, and its levels lie on the block's grid",
    "[study][quest]") {
  Block block;
  block.type = BlockType::kJnd;
  block.method = JndMethod::kQuestPlus;
  block.min_level = 1.01;
  block.max_level = 2.0;
  const QuestPlusGrid grid = quest_plus_grid(block);
  REQUIRE(grid.levels.size() == 30);
  CHECK(grid.levels.front() == 1.01);
  CHECK(grid.levels.back() == 2.0);
  REQUIRE(grid.thresholds.size() == 40);
  CHECK(grid.thresholds.front() == Approx(0.01));
  CHECK(grid.thresholds.back() == Approx(1.0));
  const std::vector<bool> answers{true, true, false, true, false, false, true, true};
  std::vector<bool> so_far;
  QuestPlus quest(grid);
  for (bool answer : answers) {
    const std::size_t level = quest.next_level();
    CHECK(quest_plus_level(block, so_far) == grid.levels[level]);
    quest.update(level, answer);
    so_far.push_back(answer);
  }
  CHECK(quest_plus_estimate(block, answers).weber_fraction == quest.estimate().weber_fraction);
  // Before any answer the estimate is the prior's: the grid's middle in ln w, 0.1.
  CHECK(quest_plus_estimate(block, {}).weber_fraction == Approx(0.1).epsilon(1e-9));
}

TEST_CASE("QUEST+ converges on simulated observers and its 95 % credible interval covers the truth",
          "[study][quest]") {
  // 100 observers of the analysis's psychometric function (pse 0, the participant model's
  // curve) with Weber fractions log-uniform on [0.05, 0.4] and lapses uniform on [0, 0.06]
  // (the participant model's), 60 trials each with the block's defaults (QUEST+'s fixed
  // lapse 0.03, the slopes of kQuestPlusSlopes).
  Block block;
  block.type = BlockType::kJnd;
  block.method = JndMethod::kQuestPlus;
  block.min_level = 1.01;
  block.max_level = 2.0;
  const QuestPlusGrid grid = quest_plus_grid(block);
  std::mt19937_64 random(2028);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const int runs = 100, trials = 60;
  int close = 0, covered = 0;
  double sum_error = 0.0;
  for (int run = 0; run < runs; ++run) {
    doorbench::testing::ObserverTruth truth;
    truth.weber_fraction =
        std::exp(std::log(0.05) + uniform(random) * (std::log(0.4) - std::log(0.05)));
    truth.lapse = 0.06 * uniform(random);
    QuestPlus quest(grid);
    for (int t = 0; t < trials; ++t) {
      const std::size_t level = quest.next_level();
      quest.update(level, uniform(random) < truth.probability(std::log(grid.levels[level])));
    }
    const QuestPlusEstimate estimate = quest.estimate();
    const double error = std::log(estimate.weber_fraction / truth.weber_fraction);
    sum_error += error;
    close += std::abs(error) < std::log(1.5);  // within a factor 1.5 of the truth
    covered += estimate.ci_low <= truth.weber_fraction && truth.weber_fraction <= estimate.ci_high;
  }
  INFO("close " << close << ", covered " << covered << ", mean ln error " << sum_error / runs);
  // 60 trials pin w down to about a factor 1.5 (the intervals' typical half-width): most
  // estimates fall within it (81 of 100 with this seed).
  CHECK(close >= 75);
  CHECK(covered >= 90);
  CHECK(covered <= 99);
  CHECK(std::abs(sum_error / runs) < 0.15);  // -0.084 with this seed: little bias
}

TEST_CASE(
    "The run's kept QUEST+ track gives the replay's levels, also when the answers start again",
    "[study][quest]") {
  const Campaign campaign = parse_campaign(
      "[campaign]\nname = \"q\"\n[variants]\nreference = \"base\"\n[participants]\ncount = 2\n"
      "[[blocks]]\nname = \"q\"\ntype = \"jnd\"\nparameter = \"J\"\nmethod = \"quest+\"\ntrials = "
      "12\n",
      "q.toml", ".");
  const Block& block = campaign.blocks.back();
  StimulusMaker maker(campaign);
  PlanRow row{"P01", "q", 1, "stronger:J", "J*?", "J*1", 1};
  // Two participants' answers one after the other (as the power simulation asks).
  const std::vector<std::vector<bool>> tracks{
      {true, true, false, true, true, false, true, false, true, true}, {false, false, true, false}};
  for (const std::vector<bool>& answers : tracks) {
    std::vector<bool> so_far;
    for (std::size_t i = 0; i <= answers.size(); ++i) {
      INFO("after " << i << " answers");
      CHECK(maker.make(row, so_far).first.name ==
            jnd_stimulus_name("J", quest_plus_level(block, so_far)));
      if (i < answers.size()) so_far.push_back(answers[i]);
    }
  }
  // Answers as many as the kept ones but not extending them: replayed.
  const std::vector<bool> branch{false, false, true, true, true};
  CHECK(maker.make(row, branch).first.name ==
        jnd_stimulus_name("J", quest_plus_level(block, branch)));
}

TEST_CASE(
    "Power: a quest+ block's line is the panels' median QUEST+ threshold, near the simulated JND",
    "[study][quest][power]") {
  // The simulated participants' heaviness (J) Weber fractions are log-normal around 10 %
  // (study/participant_model.h), so the panels' median threshold lies near the level 1.10.
  const Campaign campaign = parse_campaign(
      "[campaign]\nname = \"q\"\n[variants]\nreference = \"base\"\n[participants]\ncount = 12\n"
      "[[blocks]]\nname = \"q\"\ntype = \"jnd\"\nparameter = \"J\"\nmethod = \"quest+\"\ntrials = "
      "40\n",
      "q.toml", ".");
  PowerOptions options;
  options.panels = 20;
  const std::vector<PowerLine> lines = simulate_power(campaign, 7, options);
  REQUIRE(lines.size() == 1);
  CHECK(lines[0].question == "stronger:J (quest+)");
  CHECK(lines[0].is_threshold);
  CHECK(lines[0].panels == 20);
  CHECK(lines[0].threshold_median > 1.08);
  CHECK(lines[0].threshold_median < 1.125);
  CHECK(lines[0].threshold_p05 <= lines[0].threshold_median);
  CHECK(lines[0].threshold_median <= lines[0].threshold_p95);
}
