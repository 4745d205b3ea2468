// Coverage of the ratings' and thresholds' 95 % intervals over 50 simulated campaigns with a
// known truth (docs/campaign.md, "Coverage of the intervals: ratings and thresholds"): each
// kind of interval must cover the truth in 90–99 % of its draws. Prints the table.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <random>

#include "study/statistics/ratings.h"
#include "study/statistics/thresholds.h"
#include "tests/study/rating_simulation.h"
#include "tests/study/threshold_simulation.h"

using doorbench::study::fit_ratings;
using doorbench::study::fit_thresholds;
using doorbench::study::StrongerObservation;
using doorbench::testing::ObserverTruth;
using doorbench::testing::RatingTruth;

namespace {

constexpr int kCampaigns = 50;

struct CoverageTally {
  const char* what;
  int covered = 0, draws = 0;
  void add(bool inside) {
    covered += inside ? 1 : 0;
    ++draws;
  }
  double share() const { return static_cast<double>(covered) / draws; }
};

void print(const std::vector<CoverageTally>& tallies) {
  std::printf("| interval | draws | covered | coverage |\n|---|---:|---:|---:|\n");
  for (const CoverageTally& t : tallies) {
    std::printf("| %s | %d | %d | %.1f %% |\n", t.what, t.draws, t.covered, 100.0 * t.share());
  }
}

}  // namespace

TEST_CASE("coverage: rating effects' Wald intervals cover the truth in 90-99% of 50 campaigns",
          "[study][ratings][coverage][slow]") {
  RatingTruth truth;  // 4 variants, 5 categories
  truth.participants = 20;
  truth.participant_sd = 1.0;
  CoverageTally laplace{"rating effect (clmm, 10-node AGQ), 20 participants x 4 variants x 2"};
  for (int campaign = 0; campaign < kCampaigns; ++campaign) {
    const auto data = doorbench::testing::simulate_ratings(truth, 1000 + campaign);
    const auto result = fit_ratings(data);
    REQUIRE(result.attributes.size() == 1);
    const auto& effects = result.attributes[0].effects;
    for (std::size_t v = 1; v < effects.size(); ++v) {
      laplace.add(effects[v].ci_low <= truth.effects[v] && truth.effects[v] <= effects[v].ci_high);
    }
  }
  print({laplace});
  CHECK(laplace.share() >= 0.90);
  CHECK(laplace.share() <= 0.99);
}

TEST_CASE("coverage: Weber fractions' profile intervals cover the truth in 90-99% of 50 campaigns",
          "[study][thresholds][coverage][slow]") {
  // Two parameters per campaign, each a panel of 20 participants by constant stimuli.
  ObserverTruth inertia;
  inertia.weber_fraction = 0.10;
  inertia.lapse = 0.02;
  ObserverTruth stiffness;
  stiffness.weber_fraction = 0.18;
  stiffness.lapse = 0.05;
  const std::vector<double> factors{0.75, 0.85, 0.92, 0.97, 1.03, 1.08, 1.15, 1.3};
  CoverageTally panel{"Weber fraction, panel (pooled fit), 20 participants x 8 levels x 10"};
  CoverageTally each{"Weber fraction, one participant (80 trials)"};
  CoverageTally band{"P(stronger) at each of the 8 levels, panel's curve band (delta method)"};
  std::mt19937_64 random(2029);
  for (int campaign = 0; campaign < kCampaigns; ++campaign) {
    for (const ObserverTruth* truth : {&inertia, &stiffness}) {
      auto trials = doorbench::testing::simulate_constant_stimuli(*truth, factors, 10, 20, random);
      const auto result = fit_thresholds(trials);
      REQUIRE(result.parameters.size() == 1);
      const auto& p = result.parameters[0];
      panel.add(p.panel.ci_low <= truth->weber_fraction &&
                truth->weber_fraction <= p.panel.ci_high);
      for (const double factor : factors) {
        const auto point = p.panel.curve_point(std::log(factor));
        const double true_p = truth->probability(std::log(factor));
        band.add(point.low <= true_p && true_p <= point.high);
      }
      for (const auto& [participant, fit] : p.participants) {
        each.add(fit.ci_low <= truth->weber_fraction && truth->weber_fraction <= fit.ci_high);
      }
    }
  }
  print({panel, each, band});
  CHECK(band.share() >= 0.90);
  CHECK(band.share() <= 0.99);
  CHECK(panel.share() >= 0.90);
  CHECK(panel.share() <= 0.99);
  CHECK(each.share() >= 0.90);
  CHECK(each.share() <= 0.99);
}
