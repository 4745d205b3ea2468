// The perceptual tolerance table (analysis/design/perceptual_tolerance.h) against a direct
// Monte Carlo written here independently, the Wilson interval's coverage, and the proposal.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "analysis/design/panel_spec.h"
#include "analysis/design/perceptual_tolerance.h"
#include "analysis/model/parameter_file.h"

using Catch::Matchers::WithinAbs;
using doorbench::DoorModel;
using doorbench::FeltJnd;
using doorbench::FeltQuantities;
using doorbench::PerceptualRow;
using doorbench::ToleranceSpec;

namespace {

// The test's own criterion: over the JND when the ratio leaves [1/(1+w), 1+w] (or flips sign).
bool over_jnd(double value, double nominal, double w) {
  const double ratio = value / nominal;
  return !(ratio >= 1.0 / (1.0 + w) && ratio <= 1.0 + w);
}

// The test's own Wilson 95 % interval.
std::pair<double, double> wilson(int k, int n) {
  const double z = 1.959963984540054;
  const double p = static_cast<double>(k) / n;
  const double denominator = 1 + z * z / n;
  const double centre = (p + z * z / (2.0 * n)) / denominator;
  const double half = z * std::sqrt(p * (1 - p) / n + z * z / (4.0 * n * n)) / denominator;
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

// Small JNDs so that the shares are neither 0 nor 1 (the comparison can fail).
std::vector<FeltJnd> test_jnds() {
  std::vector<FeltJnd> jnds;
  for (const auto& info : doorbench::kFeltQuantities) {
    FeltJnd jnd = doorbench::typical_felt_jnd(info.name);
    jnd.weber_fraction = 0.03;
    jnd.source = "test";
    jnds.push_back(jnd);
  }
  return jnds;
}

}  // namespace

TEST_CASE("Wilson's interval: a published value and its coverage", "[perceptual_tolerance]") {
  // 0 of 10: the upper end is z^2 / (n + z^2) = 0.2775 (Wilson 1927; Agresti & Coull 1998).
  const auto none = doorbench::wilson_interval(0, 10);
  CHECK(none.low == 0.0);
  CHECK_THAT(none.high, WithinAbs(0.27753, 1e-4));
  // 5 of 10: 0.2366 to 0.7634.
  const auto half = doorbench::wilson_interval(5, 10);
  CHECK_THAT(half.low, WithinAbs(0.23659, 1e-4));
  CHECK_THAT(half.high, WithinAbs(0.76341, 1e-4));
  CHECK(std::isnan(doorbench::wilson_interval(0, 0).low));
  // Coverage on simulated binomial counts with a known p: 2000 draws each.
  std::mt19937_64 random(7);
  // np >= 10 here: for fewer expected successes Wilson's coverage oscillates and dips a
  // little below 93 % at some (p, n) (measured: 92.9 % at p 0.02, n 200).
  for (const double p : {0.05, 0.3}) {
    for (const int n : {200, 1000}) {
      std::binomial_distribution<int> binomial(n, p);
      int covered = 0;
      for (int draw = 0; draw < 2000; ++draw) {
        const auto interval = doorbench::wilson_interval(binomial(random), n);
        if (interval.low <= p && p <= interval.high) ++covered;
      }
      INFO("p " << p << " n " << n << " covered " << covered);
      CHECK(covered >= 0.93 * 2000);
      CHECK(covered <= 0.975 * 2000);
    }
  }
}

TEST_CASE("the felt-as-different criterion is symmetric in the log ratio",
          "[perceptual_tolerance]") {
  CHECK_FALSE(doorbench::felt_as_different(11.9, 10.0, 0.2));
  CHECK(doorbench::felt_as_different(12.1, 10.0, 0.2));
  CHECK_FALSE(doorbench::felt_as_different(10.0 / 1.19, 10.0, 0.2));
  CHECK(doorbench::felt_as_different(10.0 / 1.21, 10.0, 0.2));
  CHECK(doorbench::felt_as_different(0.5, -7.0, 0.2));  // the holding force changed sign
  CHECK_FALSE(doorbench::felt_as_different(-7.5, -7.0, 0.2));
  CHECK(doorbench::typical_felt_jnd("friction_open_N").source == "typical: friction 20%");
  CHECK(doorbench::typical_felt_jnd("peak_unlatch_force_N").source == "typical: stiffness 15%");
  CHECK_THROWS_WITH(doorbench::typical_felt_jnd("colour"), "no felt quantity named colour");
}

TEST_CASE("the perceptual table's shares equal a direct Monte Carlo of the same doors",
          "[perceptual_tolerance]") {
  const DoorModel design = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  const ToleranceSpec spec = doorbench::default_tolerances(design);
  doorbench::MonteCarloOptions mc;
  mc.samples = 150;
  mc.threads = 2;
  mc.seed = 11;
  const doorbench::ToleranceResult result = doorbench::tolerance_analysis(design, spec, mc);
  const std::vector<FeltJnd> jnds = test_jnds();
  const std::vector<PerceptualRow> rows = doorbench::perceptual_shares(result, jnds);
  REQUIRE(rows.size() == doorbench::kFeltQuantities.size());

  // (1) The same doors rebuilt from their draws, their felt quantities computed again here,
  // counted by the test's own criterion: the counts must be equal.
  const FeltQuantities nominal = doorbench::felt_quantities(design);
  std::vector<FeltQuantities> felt;
  for (const std::vector<double>& draw : result.draws) {
    std::vector<double> values(design.parameter_values().begin(), design.parameter_values().end());
    for (std::size_t p = 0; p < result.tolerances.size(); ++p) {
      values[static_cast<std::size_t>(*design.find_parameter(result.tolerances[p].name))] = draw[p];
    }
    felt.push_back(doorbench::felt_quantities(design.with_parameter_values(values)));
  }
  int assessed = 0;
  for (std::size_t q = 0; q < rows.size(); ++q) {
    const auto member = doorbench::kFeltQuantities[q].member;
    int doors = 0, over = 0;
    for (const FeltQuantities& door : felt) {
      if (!std::isfinite(door.*member)) continue;
      ++doors;
      if (over_jnd(door.*member, nominal.*member, 0.03)) ++over;
    }
    INFO(rows[q].quantity << ": " << over << " of " << doors << " here, " << rows[q].felt_different
                          << " of " << rows[q].doors << " in the table");
    CHECK(rows[q].doors == doors);
    CHECK(rows[q].felt_different == over);
    CHECK_THAT(rows[q].share, WithinAbs(static_cast<double>(over) / doors, 1e-12));
    const auto interval = wilson(over, doors);
    CHECK_THAT(rows[q].ci_low, WithinAbs(interval.first, 1e-12));
    CHECK_THAT(rows[q].ci_high, WithinAbs(interval.second, 1e-12));
    if (over > 0 && over < doors) ++assessed;
  }
  CHECK(assessed >= 3);  // the comparison is not of zeros and ones only

  // (2) Doors drawn here with another generator (normal, band = ±3σ, redrawn beyond it,
  // clamped to the bounds): the shares agree within the two estimates' binomial noise.
  std::mt19937_64 random(99);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<int> over(rows.size(), 0), doors(rows.size(), 0);
  const int draws = 150;
  for (int s = 0; s < draws; ++s) {
    std::vector<double> values(design.parameter_values().begin(), design.parameter_values().end());
    for (const doorbench::ParameterTolerance& t : spec.parameters) {
      const int i = *design.find_parameter(t.name);
      const double band = t.percent ? std::abs(values[i]) * t.plus_minus / 100.0 : t.plus_minus;
      double unit = 0;
      do {
        unit = normal(random) / 3.0;
      } while (std::abs(unit) > 1.0);
      const auto bounds = design.parameter_bounds()[i];
      values[i] = std::clamp(values[i] + band * unit, bounds.lower, bounds.upper);
    }
    const FeltQuantities door = doorbench::felt_quantities(design.with_parameter_values(values));
    for (std::size_t q = 0; q < rows.size(); ++q) {
      const double value = door.*doorbench::kFeltQuantities[q].member;
      if (!std::isfinite(value)) continue;
      ++doors[q];
      if (over_jnd(value, nominal.*doorbench::kFeltQuantities[q].member, 0.03)) ++over[q];
    }
  }
  for (std::size_t q = 0; q < rows.size(); ++q) {
    const double direct = static_cast<double>(over[q]) / doors[q];
    const double pooled = (direct + rows[q].share) / 2;
    const double se = std::sqrt(pooled * (1 - pooled) * (1.0 / doors[q] + 1.0 / rows[q].doors));
    INFO(rows[q].quantity << ": table " << rows[q].share << ", direct " << direct);
    CHECK(std::abs(direct - rows[q].share) <= 4 * se + 0.02);
  }
}

// The reference door's spring is exactly at its free length when closed (L = L0), so the
// smallest L0 tolerance decides whether it pulls near closed and moves the unlatching peak by
// more than 3 % in a quarter of the doors, however tight (docs/design-spec.md): no common
// factor down to 1/64 gets every share under 20 %. The proposal says so.
TEST_CASE("the proposal says when no factor reaches the level", "[perceptual_tolerance]") {
  const DoorModel design = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  doorbench::MonteCarloOptions mc;
  mc.samples = 60;
  mc.threads = 2;
  mc.seed = 5;
  doorbench::PerceptualToleranceOptions options;
  options.felt_share = 0.2;
  options.min_factor = 0.25;
  std::vector<double> reported;
  options.progress = [&reported](double factor, double, int) { reported.push_back(factor); };
  const doorbench::PerceptualProposal proposal = doorbench::propose_perceptual_tolerances(
      design, doorbench::default_tolerances(design), mc, test_jnds(), options);
  CHECK_FALSE(proposal.reached);
  CHECK(proposal.factors_tried == std::vector<double>{1.0, 0.5, 0.25});
  CHECK(reported == proposal.factors_tried);
  CHECK(proposal.factor == 0.25);
  REQUIRE(proposal.worst_shares.back() > 0.2);
  CHECK_THAT(proposal.summary, Catch::Matchers::StartsWith("even the tolerances × 0.25 leave a "
                                                           "share of "));
  CHECK_THAT(proposal.summary, Catch::Matchers::EndsWith("% felt as different (over 20%)"));
}

TEST_CASE("the proposal keeps every share under the level and no larger factor tried does",
          "[perceptual_tolerance]") {
  // The reference door with its spring 2 mm shorter: stretched when closed, off the L0 edge.
  const DoorModel reference = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  std::vector<double> values(reference.parameter_values().begin(),
                             reference.parameter_values().end());
  values[static_cast<std::size_t>(*reference.find_parameter("L0"))] -= 0.002;
  const DoorModel design = reference.with_parameter_values(values);
  const ToleranceSpec spec = doorbench::default_tolerances(design);
  doorbench::MonteCarloOptions mc;
  mc.samples = 60;
  mc.threads = 2;
  mc.seed = 5;
  const std::vector<FeltJnd> jnds = test_jnds();
  doorbench::PerceptualToleranceOptions options;
  options.felt_share = 0.2;
  options.bisection_steps = 3;
  const doorbench::PerceptualProposal proposal =
      doorbench::propose_perceptual_tolerances(design, spec, mc, jnds, options);
  INFO(proposal.summary);
  REQUIRE(proposal.reached);
  CHECK(proposal.factor < 1.0);  // JNDs of 3 % call for tighter tolerances than the defaults
  REQUIRE(proposal.tolerances.size() == spec.parameters.size());
  for (std::size_t p = 0; p < spec.parameters.size(); ++p) {
    CHECK_THAT(proposal.tolerances[p].plus_minus,
               WithinAbs(spec.parameters[p].plus_minus * proposal.factor, 1e-12));
  }
  // Run again at the proposed tolerances and count here: every share at or under 20 %.
  const doorbench::ToleranceResult again =
      doorbench::tolerance_analysis(design, ToleranceSpec{proposal.tolerances}, mc);
  const FeltQuantities nominal = again.nominal;
  for (const auto& info : doorbench::kFeltQuantities) {
    int doors = 0, over = 0;
    for (const FeltQuantities& door : again.felt) {
      if (!std::isfinite(door.*info.member)) continue;
      ++doors;
      if (over_jnd(door.*info.member, nominal.*info.member, 0.03)) ++over;
    }
    INFO(info.name << ": " << over << " of " << doors);
    CHECK(over <= 0.2 * doors);
  }
  // The bracket: a factor tried within 2^(1/8) above the proposal left a share over 20 %.
  bool bracketed = false;
  for (std::size_t i = 0; i < proposal.factors_tried.size(); ++i) {
    const double f = proposal.factors_tried[i];
    if (f > proposal.factor && f <= proposal.factor * std::pow(2.0, 1.0 / 8) * (1 + 1e-9) &&
        proposal.worst_shares[i] > 0.2) {
      bracketed = true;
    }
  }
  CHECK(bracketed);
}

TEST_CASE("choose_favourite: the variant of largest worth with its file, the first of equals",
          "[design]") {
  doorbench::CampaignForSpec campaign;
  doorbench::choose_favourite(campaign);
  CHECK(campaign.favourite.empty());
  CHECK(campaign.favourite_file.empty());

  campaign.preference = {
      {"A", 0.0, -0.2, 0.2}, {"B", 0.7, 0.4, 1.0}, {"C", 0.7, 0.3, 1.1}, {"D", -0.4, -0.8, 0.0}};
  campaign.variant_files = {
      {"A", "variants/A.json"}, {"B", "variants/B.json"}, {"C", "variants/C.json"}};
  doorbench::choose_favourite(campaign);
  CHECK(campaign.favourite == "B");
  CHECK(campaign.favourite_file == "variants/B.json");

  campaign.preference[1].worth = 0.5;
  campaign.variant_files.erase("C");
  doorbench::choose_favourite(campaign);
  CHECK(campaign.favourite == "C");
  CHECK(campaign.favourite_file.empty());
}

TEST_CASE("a Monte Carlo in ranges of samples draws the doors one run of them all draws",
          "[perceptual_tolerance]") {
  const DoorModel design = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  const ToleranceSpec spec = doorbench::default_tolerances(design);
  doorbench::MonteCarloOptions mc;
  mc.samples = 12;
  mc.threads = 2;
  mc.seed = 7;
  const doorbench::ToleranceResult whole = doorbench::tolerance_analysis(design, spec, mc);
  mc.samples = 5;
  mc.first_sample = 7;
  const doorbench::ToleranceResult part = doorbench::tolerance_analysis(design, spec, mc);
  REQUIRE(part.draws.size() == 5);
  for (std::size_t s = 0; s < part.draws.size(); ++s) {
    CHECK(part.draws[s] == whole.draws[s + 7]);
    CHECK(part.felt[s].peak_unlatch_force_N == whole.felt[s + 7].peak_unlatch_force_N);
  }
  mc.first_sample = -1;
  CHECK(mc.validate() == "monte carlo first_sample must be >= 0");
}

// With JNDs of 3 % the reference door's default tolerances leave most doors felt as different
// (docs/design-spec.md: 65 %): at a level of 20 % one batch of 20 says so, and its shares are
// those of a run of the same 20 doors.
TEST_CASE("a factor's Monte Carlo stops after the batch where the answer is clear",
          "[perceptual_tolerance]") {
  const DoorModel design = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  const ToleranceSpec spec = doorbench::default_tolerances(design);
  doorbench::MonteCarloOptions mc;
  mc.samples = 60;
  mc.threads = 2;
  mc.seed = 5;
  doorbench::PerceptualToleranceOptions options;
  options.felt_share = 0.2;
  options.batch_samples = 20;
  options.min_factor = 0.5;
  std::vector<int> reported;
  options.progress = [&reported](double, double, int samples) { reported.push_back(samples); };
  const doorbench::PerceptualProposal proposal =
      doorbench::propose_perceptual_tolerances(design, spec, mc, test_jnds(), options);
  REQUIRE(proposal.samples_run.size() == proposal.factors_tried.size());
  CHECK(reported == proposal.samples_run);
  REQUIRE(proposal.worst_shares.front() > 0.5);
  CHECK(proposal.samples_run.front() == 20);
  mc.samples = 20;
  const std::vector<PerceptualRow> rows =
      doorbench::perceptual_shares(doorbench::tolerance_analysis(design, spec, mc), test_jnds());
  CHECK(proposal.worst_shares.front() == doorbench::worst_share(rows));

  options.batch_samples = 1;
  CHECK_THROWS_WITH(
      doorbench::propose_perceptual_tolerances(design, spec, mc, test_jnds(), options),
      "batch_samples must be 0 or >= 2");
  options.batch_samples = 0;
  options.factor_precision = 0;
  CHECK_THROWS_WITH(
      doorbench::propose_perceptual_tolerances(design, spec, mc, test_jnds(), options),
      "factor_precision must be > 0");
}
