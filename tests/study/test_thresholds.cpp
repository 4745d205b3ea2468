// Thresholds from jnd blocks: the psychometric fit against a brute-force likelihood grid,
// staircases read from their reversals, and the trials adapter's reading and errors.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "study/statistics/numeric_minimize.h"
#include "study/statistics/psychometric_likelihood.h"
#include "study/statistics/thresholds.h"
#include "tests/study/threshold_simulation.h"

using doorbench::study::fit_psychometric;
using doorbench::study::parse_trials_table;
using doorbench::study::psychometric_log_likelihood;
using doorbench::study::PsychometricShape;
using doorbench::study::staircase_threshold;
using doorbench::study::stronger_observations;
using doorbench::study::StrongerObservation;
using doorbench::study::ThresholdOptions;
using doorbench::study::weber_fraction;
using doorbench::testing::ObserverTruth;

namespace {

const std::vector<double> kFactors{0.7, 0.8, 0.9, 0.95, 1.05, 1.1, 1.2, 1.3};

}  // namespace

TEST_CASE("thresholds: the fitted JND and its interval agree with a brute-force likelihood grid",
          "[study][thresholds]") {
  std::mt19937_64 random(29);
  ObserverTruth truth;
  truth.pse = 0.02;
  const auto trials = doorbench::testing::simulate_constant_stimuli(truth, kFactors, 30, 1, random);
  const ThresholdOptions options;
  const auto fit = fit_psychometric(trials, options);
  // The grid: PSE, ln spread and lapse, every combination; the profile over ln spread.
  const int spread_steps = 241;
  const double log_low = std::log(0.02), log_high = std::log(0.6);
  std::vector<double> profile(spread_steps, -INFINITY);
  double best = -INFINITY, best_spread = 0.0;
  for (int s = 0; s < spread_steps; ++s) {
    const double spread = std::exp(log_low + (log_high - log_low) * s / (spread_steps - 1));
    for (int p = 0; p <= 80; ++p) {
      const double pse = -0.1 + 0.2 * p / 80.0;
      for (int l = 0; l <= 20; ++l) {
        const double lapse = 0.1 * l / 20.0;
        const double ll = psychometric_log_likelihood(trials, PsychometricShape::kCumulativeNormal,
                                                      pse, spread, lapse);
        profile[s] = std::max(profile[s], ll);
        if (ll > best) best = ll, best_spread = spread;
      }
    }
  }
  // The fit's maximum is at least the grid's, and not far above it (the grid is fine).
  CHECK(fit.log_likelihood >= best - 1e-9);
  CHECK(fit.log_likelihood - best < 0.05);
  const double grid_step = (log_high - log_low) / (spread_steps - 1);
  CHECK(std::abs(std::log(fit.spread) - std::log(best_spread)) < 3 * grid_step);
  CHECK(fit.weber_fraction ==
        Approx(weber_fraction(PsychometricShape::kCumulativeNormal, best_spread, 0.75))
            .epsilon(0.05));
  // The interval's ends: where the grid's profile falls 1.92 below the grid's maximum.
  double grid_low = INFINITY, grid_high = -INFINITY;
  for (int s = 0; s < spread_steps; ++s) {
    if (best - profile[s] <= 1.920729) {
      const double spread = std::exp(log_low + grid_step * s);
      grid_low =
          std::min(grid_low, weber_fraction(PsychometricShape::kCumulativeNormal, spread, 0.75));
      grid_high =
          std::max(grid_high, weber_fraction(PsychometricShape::kCumulativeNormal, spread, 0.75));
    }
  }
  INFO("fit " << fit.weber_fraction << " [" << fit.ci_low << ", " << fit.ci_high << "], grid ["
              << grid_low << ", " << grid_high << "]");
  CHECK(fit.ci_low == Approx(grid_low).epsilon(0.03));
  CHECK(fit.ci_high == Approx(grid_high).epsilon(0.03));
  CHECK(fit.ci_low < truth.weber_fraction);
  CHECK(fit.ci_high > truth.weber_fraction);
}

TEST_CASE("thresholds: the Weibull shape fits Weibull data and reads its own 75% point",
          "[study][thresholds]") {
  // Data at a Weibull's exact probabilities, many trials: the fit recovers its spread.
  std::vector<StrongerObservation> trials;
  const double spread = 0.1;
  for (const double factor : kFactors) {
    const double z = std::log(factor) / spread + std::log(std::log(2.0));
    const double p = 1.0 - std::exp(-std::exp(z));
    const int n = 4000, stronger = static_cast<int>(std::lround(p * n));
    for (int i = 0; i < n; ++i) {
      trials.push_back({"P1", "b", i, "k_l", "k_l", std::log(factor), i < stronger});
    }
  }
  ThresholdOptions options;
  options.shape = PsychometricShape::kWeibull;
  const auto fit = fit_psychometric(trials, options);
  CHECK(fit.spread == Approx(spread).epsilon(0.01));
  CHECK(fit.pse == Approx(0.0).margin(0.002));
  CHECK(fit.lapse < 0.01);
  // F(pse + JND) = 0.75 on the lapse-free Weibull.
  const double x75 = std::log1p(fit.weber_fraction) + fit.pse;
  CHECK(1.0 - std::exp(-std::exp((x75 - fit.pse) / fit.spread + std::log(std::log(2.0)))) ==
        Approx(0.75).epsilon(1e-9));
}

TEST_CASE("thresholds: a staircase's reversals give its threshold and its rule",
          "[study][thresholds]") {
  // A 1-up-2-down run written by hand: levels in ln ratio, answers (1 = comparison stronger).
  const std::vector<double> levels{0.3, 0.3, 0.2, 0.2, 0.1, 0.2, 0.2, 0.1, 0.1, 0.0, 0.1, 0.1, 0.0};
  const std::vector<int> answers{1, 1, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 1};
  std::vector<StrongerObservation> trials;
  for (std::size_t t = 0; t < levels.size(); ++t) {
    trials.push_back(
        {"P1", "stair", static_cast<int>(t), "J_d", "J_d", levels[t] + 0.05, answers[t] == 1});
  }
  ThresholdOptions options;
  options.staircase_reversals = 3;
  const auto s = staircase_threshold(trials, options);
  REQUIRE(s.has_value());
  CHECK(s->down_rule == 2);
  CHECK(s->target == Approx(std::sqrt(0.5)));
  // Reversals (turns) at 0.1 (down→up), 0.2 (up→down), 0.0 (down→up), 0.1 (up→down), each
  // level + 0.05; the last three are averaged.
  CHECK(s->reversals_total == 4);
  CHECK(s->reversals_used == 3);
  CHECK(s->weber_fraction == Approx(std::expm1((0.25 + 0.05 + 0.15) / 3.0)));
  // The same levels in a random order with the same answers are not a staircase.
  std::swap(trials[0], trials[6]);
  std::swap(trials[2], trials[9]);
  CHECK_FALSE(staircase_threshold(trials, options).has_value());
  // A simulated 1-up-3-down staircase converges near its 79.4% point.
  std::mt19937_64 random(7);
  ObserverTruth truth;
  truth.lapse = 0.0;
  const auto run = doorbench::testing::simulate_staircase(truth, 3, 0.4, 0.02, 400, "P2", random);
  options.staircase_reversals = 20;
  const auto stair = staircase_threshold(run, options);
  REQUIRE(stair.has_value());
  CHECK(stair->down_rule == 3);
  // P(stronger | level) = 0.794 at level = spread * z(0.794) (PSE 0, no lapse).
  const double expected = std::expm1(truth.spread() * 0.8202);
  CHECK(stair->weber_fraction == Approx(expected).epsilon(0.25));
  CHECK(stair->fit.trials == 400);
}

TEST_CASE("thresholds: jnd rows of a trials table become observations around the reference",
          "[study][thresholds]") {
  const std::string header = "participant,block,trial,question,first,second,answer\n";
  const auto table = parse_trials_table(header +
                                            "P01,jnd1,1,stronger:J_d,J_d*1.00,J_d*1.10,2\n"
                                            "P01,jnd1,2,stronger:J_d,J_d*0.90,J_d*1.00,2\n"
                                            "P01,jnd1,3,rating:heavy:7,A,B,3 5\n"
                                            "P01,jnd1,4,stronger:J_d,J_d*1.10,J_d*1.00,2\n",
                                        "trials.csv");
  const auto trials = stronger_observations(table);
  REQUIRE(trials.size() == 3);
  CHECK(trials[0].reference == "J_d*1.00");
  CHECK(trials[0].level == Approx(std::log(1.1)));
  CHECK(trials[0].comparison_stronger);
  CHECK(trials[1].level == Approx(std::log(0.9)));
  CHECK_FALSE(trials[1].comparison_stronger);
  CHECK(trials[2].level == Approx(std::log(1.1)));
  CHECK_FALSE(trials[2].comparison_stronger);
  CHECK(trials[2].trial == 4);

  const auto refused = [&](const std::string& row) {
    return stronger_observations(parse_trials_table(header + row, "t.csv"));
  };
  CHECK_THROWS_WITH(refused("P01,j,1,stronger:J_d,J_d*1.00,J_d*1.10,same\n"),
                    "t.csv:2: answer 'same' is not 1 or 2 (which felt stronger)");
  CHECK_THROWS_WITH(refused("P01,j,1,stronger:J_d,J_d*1.00,k_l*1.10,1\n"),
                    "t.csv:2: second 'k_l*1.10' is not J_d or J_d*FACTOR with a positive FACTOR");
  CHECK_THROWS_WITH(refused("P01,j,1,stronger:J_d,J_d*-1,J_d*1.10,1\n"),
                    "t.csv:2: first 'J_d*-1' is not J_d or J_d*FACTOR with a positive FACTOR");
  CHECK_THROWS_WITH(refused("P01,j,1,stronger:J_d,J_d*1.00,J_d*1.10,1\n"
                            "P01,j,2,stronger:J_d,J_d*0.90,J_d*1.20,1\n"),
                    "t.csv:2: block 'j' of participant 'P01': no variant is in every trial, so "
                    "none is the reference");
}

// The fit's Newton steps and covariance use the likelihood's analytic gradient and Hessian:
// they must equal central differences of the likelihood itself, for both shapes, with and
// without the PSE and the lapse fitted, at points away from the optimum.
TEST_CASE("thresholds: the likelihood's analytic gradient and Hessian equal central differences",
          "[study][thresholds]") {
  namespace st = doorbench::study::statistics;
  std::mt19937_64 random(7);
  ObserverTruth truth;
  truth.pse = 0.03;
  const auto trials = doorbench::testing::simulate_constant_stimuli(truth, kFactors, 12, 1, random);
  for (const PsychometricShape shape :
       {PsychometricShape::kCumulativeNormal, PsychometricShape::kWeibull}) {
    for (const bool fit_pse : {true, false}) {
      for (const bool fit_lapse : {true, false}) {
        INFO("shape " << int(shape) << ", pse " << fit_pse << ", lapse " << fit_lapse);
        st::PsychometricProblem problem{st::count_levels(trials), shape, {fit_pse, fit_lapse, 0.1}};
        Eigen::VectorXd x(problem.layout.size());
        int i = 0;
        if (fit_pse) x[i++] = -0.02;
        x[i++] = std::log(0.12);
        if (fit_lapse) x[i] = -0.7;
        const auto analytic = st::psychometric_derivatives(problem, x);
        const st::Objective value = [&](const Eigen::VectorXd& at) {
          return st::psychometric_derivatives(problem, at).value;
        };
        // The value is the per-trial likelihood's, counted per level.
        const auto v = st::unpack(x, problem.layout);
        CHECK(analytic.value == Approx(-psychometric_log_likelihood(
                                           trials, shape, v.pse, std::exp(v.log_spread), v.lapse))
                                    .epsilon(1e-12));
        const Eigen::VectorXd gradient = st::numeric_gradient(value, x);
        const Eigen::MatrixXd hessian = st::numeric_hessian(value, x);
        for (Eigen::Index r = 0; r < x.size(); ++r) {
          CHECK(analytic.gradient[r] == Approx(gradient[r]).epsilon(1e-6).margin(1e-6));
          for (Eigen::Index c = 0; c < x.size(); ++c)
            CHECK(analytic.hessian(r, c) == Approx(hessian(r, c)).epsilon(1e-4).margin(1e-3));
        }
      }
    }
  }
}

// The curve's band: inside 0..1, around the curve, narrowest where the data are dense, and
// wider with fewer trials.
TEST_CASE("thresholds: the fitted curve's pointwise band surrounds the curve and narrows with data",
          "[study][thresholds]") {
  std::mt19937_64 random(11);
  ObserverTruth truth;
  const auto few = doorbench::testing::simulate_constant_stimuli(truth, kFactors, 10, 1, random);
  const auto many = doorbench::testing::simulate_constant_stimuli(truth, kFactors, 160, 1, random);
  const auto fit_few = fit_psychometric(few), fit_many = fit_psychometric(many);
  for (const double level : {std::log(0.8), 0.0, std::log(1.1), std::log(1.3)}) {
    INFO("level " << level);
    const auto a = fit_few.curve_point(level), b = fit_many.curve_point(level);
    CHECK(a.p == Approx(fit_few.probability(level)));
    CHECK(0.0 < a.low);
    CHECK(a.low < a.p);
    CHECK(a.p < a.high);
    CHECK(a.high < 1.0);
    CHECK(b.high - b.low < a.high - a.low);
  }
}
