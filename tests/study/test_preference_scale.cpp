#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "study/statistics/preference_scale.h"
#include "tests/study/simulated_panel.h"

using doorbench::study::fit_preference_scale;
using doorbench::study::pair_data;
using doorbench::study::parse_trials_table;
using doorbench::study::PreferenceOptions;
using doorbench::study::PreferenceScaleError;
using doorbench::study::TrialsTableError;
using doorbench::testing::kTrialsHeader;
using doorbench::testing::PairPanel;
using doorbench::testing::simulate_pairs;

namespace {

// `n` identical rows.
std::string rows(int n, const std::string& participant, const std::string& question,
                 const std::string& first, const std::string& second, const std::string& answer) {
  std::string text;
  for (int k = 0; k < n; ++k)
    text += participant + ",pair," + std::to_string(k + 1) + "," + question + "," + first + "," +
            second + "," + answer + "\n";
  return text;
}

PreferenceOptions no_bootstrap(std::string reference = {}) {
  PreferenceOptions options;
  options.bootstrap_replicates = 0;
  options.reference = std::move(reference);  // (moved: GCC 12's -Wrestrict misfires on assign)
  return options;
}

}  // namespace

// Two variants in one order, no ties: the model is saturated and the MLE is the odds.
TEST_CASE("two variants: the worth is the log of the observed odds", "[study]") {
  const std::string text = std::string(kTrialsHeader) +
                           rows(10, "P1", "preference", "A", "B", "1") +
                           rows(30, "P1", "preference", "A", "B", "2");
  const auto scale =
      fit_preference_scale(pair_data(parse_trials_table(text, "t.csv")), no_bootstrap());
  REQUIRE(scale.worths.size() == 2);
  CHECK(scale.worths[0].worth.value == 0);
  CHECK(scale.worths[0].worth.interval == "reference");
  CHECK(scale.worths[1].worth.value == Approx(std::log(3.0)).epsilon(1e-10));
  // Wald SE of a log odds: sqrt(1/10 + 1/30).
  CHECK(scale.worths[1].worth.se_wald == Approx(std::sqrt(1.0 / 10 + 1.0 / 30)).epsilon(1e-8));
  CHECK_FALSE(scale.order);
  CHECK_FALSE(scale.nu);
}

// Davidson with two variants is saturated too: pi_B = n_B / n_A, nu = n_same / sqrt(n_A n_B).
TEST_CASE("two variants with ties: Davidson's nu is the ties over the wins' geometric mean",
          "[study]") {
  const std::string text = std::string(kTrialsHeader) +
                           rows(8, "P1", "preference-2ac", "A", "B", "1") +
                           rows(18, "P1", "preference-2ac", "A", "B", "2") +
                           rows(6, "P1", "preference-2ac", "A", "B", "same");
  const auto scale =
      fit_preference_scale(pair_data(parse_trials_table(text, "t.csv")), no_bootstrap());
  CHECK(scale.worths[1].worth.value == Approx(std::log(18.0 / 8)).epsilon(1e-10));
  REQUIRE(scale.nu);
  CHECK(scale.nu->value == Approx(6 / std::sqrt(8.0 * 18)).epsilon(1e-10));
  CHECK(scale.nu->ci_low < scale.nu->value);
  CHECK(scale.nu->ci_high > scale.nu->value);
}

// Both orders of one pair: logit P(first) is delta - lambda_B (A first) and delta + lambda_B
// (B first), two binomials, saturated.
TEST_CASE("both orders: the order effect and the worth from the two logits", "[study]") {
  const std::string text =
      std::string(kTrialsHeader) + rows(12, "P1", "preference", "A", "B", "1") +
      rows(8, "P1", "preference", "A", "B", "2") + rows(15, "P1", "preference", "B", "A", "1") +
      rows(5, "P1", "preference", "B", "A", "2");
  const auto scale =
      fit_preference_scale(pair_data(parse_trials_table(text, "t.csv")), no_bootstrap());
  const double l1 = std::log(12.0 / 8), l2 = std::log(15.0 / 5);
  REQUIRE(scale.order);
  CHECK(scale.order->value == Approx((l1 + l2) / 2).epsilon(1e-10));
  CHECK(scale.worths[1].worth.value == Approx((l2 - l1) / 2).epsilon(1e-10));
}

TEST_CASE("a large simulated panel recovers worths, nu and the order effect", "[study]") {
  PairPanel panel;
  panel.nu = 0.6;
  panel.delta = 0.3;
  panel.participants = 40;
  panel.repetitions = 5;
  const std::string text = std::string(kTrialsHeader) + simulate_pairs(panel, 7);
  PreferenceOptions options;
  options.bootstrap_replicates = 200;
  const auto scale = fit_preference_scale(pair_data(parse_trials_table(text, "sim.csv")), options);
  for (std::size_t v = 0; v < panel.worths.size(); ++v) {
    INFO("variant " << panel.variants[v]);
    CHECK(std::abs(scale.worths[v].worth.value - panel.worths[v]) <
          4 * std::max(scale.worths[v].worth.se_wald, 1e-9));
  }
  REQUIRE(scale.nu);
  CHECK(std::abs(std::log(scale.nu->value) - std::log(panel.nu)) < 4 * scale.nu->se_wald);
  REQUIRE(scale.order);
  CHECK(std::abs(scale.order->value - panel.delta) < 4 * scale.order->se_wald);
  // D (worth 1.0) is clearly the favourite.
  CHECK(scale.worths[3].p_favourite > 0.95);
  CHECK(scale.replicates_used == 200);
}

TEST_CASE("participants who disagree widen the interval through the participant bootstrap",
          "[study]") {
  PairPanel panel;
  panel.heterogeneity_sd = 1.0;
  panel.participants = 20;
  panel.repetitions = 4;
  const std::string text = std::string(kTrialsHeader) + simulate_pairs(panel, 11);
  PreferenceOptions options;
  options.bootstrap_replicates = 400;
  const auto scale = fit_preference_scale(pair_data(parse_trials_table(text, "sim.csv")), options);
  for (std::size_t v = 1; v < scale.worths.size(); ++v) {
    INFO("variant " << scale.worths[v].variant);
    CHECK(scale.worths[v].worth.se_bootstrap > 1.2 * scale.worths[v].worth.se_wald);
    CHECK(scale.worths[v].worth.interval == "bootstrap");
  }
}

TEST_CASE("a variant that was never preferred is refused by name", "[study]") {
  const std::string text = std::string(kTrialsHeader) + rows(5, "P1", "preference", "A", "B", "1") +
                           rows(5, "P1", "preference", "C", "B", "1") +
                           rows(3, "P1", "preference", "A", "C", "2") +
                           rows(3, "P1", "preference", "A", "C", "1");
  REQUIRE_THROWS_WITH(
      fit_preference_scale(pair_data(parse_trials_table(text, "t.csv")), no_bootstrap()),
      "variant 'B' was never preferred: its worth is -infinity");
}

TEST_CASE("pair answers other than 1, 2 and same (2-AC only) are refused with the line",
          "[study]") {
  const std::string same =
      std::string(kTrialsHeader) + rows(1, "P1", "preference", "A", "B", "same");
  REQUIRE_THROWS_WITH(pair_data(parse_trials_table(same, "t.csv")),
                      "t.csv:2: answer 'same' to a preference question (expected 1 or 2)");
  const std::string other =
      std::string(kTrialsHeader) + rows(1, "P1", "preference-2ac", "A", "B", "x");
  REQUIRE_THROWS_WITH(pair_data(parse_trials_table(other, "t.csv")),
                      "t.csv:2: answer 'x' to a preference-2ac question (expected 1, 2 or same)");
  const std::string self = std::string(kTrialsHeader) + rows(1, "P1", "preference", "A", "A", "1");
  REQUIRE_THROWS_WITH(pair_data(parse_trials_table(self, "t.csv")),
                      "t.csv:2: a preference trial compares 'A' with itself");
  const std::string empty = std::string(kTrialsHeader) + rows(1, "P1", "preference", "A", "", "1");
  REQUIRE_THROWS_WITH(pair_data(parse_trials_table(empty, "t.csv")),
                      "t.csv:2: a preference trial without a variant in 'second'");
}

TEST_CASE("the reference variant can be named and must exist", "[study]") {
  const std::string text = std::string(kTrialsHeader) +
                           rows(10, "P1", "preference", "A", "B", "1") +
                           rows(30, "P1", "preference", "A", "B", "2");
  const auto scale =
      fit_preference_scale(pair_data(parse_trials_table(text, "t.csv")), no_bootstrap("B"));
  CHECK(scale.worths[0].worth.value == Approx(-std::log(3.0)).epsilon(1e-10));
  CHECK(scale.worths[1].worth.interval == "reference");
  REQUIRE_THROWS_WITH(
      fit_preference_scale(pair_data(parse_trials_table(text, "t.csv")), no_bootstrap("Z")),
      "reference variant 'Z' is not in any preference trial");
}
