// The ratings fit against an independent implementation: R's ordinal package (clmm with
// the Laplace approximation and with adaptive Gauss–Hermite quadrature, clm when the
// participants' spread is estimated at 0), on simulated data sets written to CSV.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "fixtures/temp_dir.h"
#include "study/statistics/ratings.h"
#include "tests/study/rating_simulation.h"

using doorbench::study::AttributeRatings;
using doorbench::study::fit_attribute_ratings;
using doorbench::study::RatingObservation;
using doorbench::study::RatingsOptions;
using doorbench::testing::RatingTruth;
using doorbench::testing::simulate_ratings;
using doorbench::testing::TempDir;

namespace {

struct REstimate {
  double value = 0.0, se = 0.0;
};

// Runs tests/study/r/clmm_fit.R on the observations; name -> (value, se).
std::map<std::string, REstimate> r_fit(const std::vector<RatingObservation>& observations, int nagq,
                                       const TempDir& dir) {
  std::string csv = "participant,variant,rating\n";
  for (const auto& o : observations) {
    csv += o.participant + "," + o.variant + "," + std::to_string(o.rating) + "\n";
  }
  const auto data = dir.write("ratings.csv", csv);
  const auto out = dir / "r_fit.csv";
  const std::string command = "/usr/bin/Rscript '" DOORBENCH_SOURCE_DIR
                              "/tests/study/r/clmm_fit.R' '" +
                              data.string() + "' " + std::to_string(nagq) + " '" + out.string() +
                              "' 2> '" + (dir / "r_stderr.txt").string() + "'";
  REQUIRE(std::system(command.c_str()) == 0);
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);  // header
  std::map<std::string, REstimate> estimates;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string name, value, se;
    std::getline(fields, name, ',');
    std::getline(fields, value, ',');
    std::getline(fields, se, ',');
    name = name.substr(1, name.size() - 2);  // quoted by write.csv
    estimates[name] = {std::stod(value), se == "NA" ? 0.0 : std::stod(se)};
  }
  return estimates;
}

void check_close(double ours, double theirs, double relative, const std::string& what) {
  INFO(what << ": doorbench " << ours << ", R " << theirs);
  CHECK(std::abs(ours - theirs) <= relative * std::abs(theirs));
}

// Compares every threshold and variant effect (1e-4 relative), the SD, the log-likelihood
// and the standard errors (1e-2 relative: both sides differentiate numerically, and with the
// Laplace approximation R's standard errors differ from ours by up to 0.4 % on these data).
void compare_with_r(const std::vector<RatingObservation>& observations, int nagq,
                    const std::string& label) {
  TempDir dir("ratings_r");
  RatingsOptions options;
  options.quadrature_nodes = std::max(nagq, 1);
  options.random_effect = nagq > 0;
  const AttributeRatings ours = fit_attribute_ratings(observations, options);
  const auto r = r_fit(observations, nagq, dir);
  INFO(label << ", nAGQ " << nagq);
  REQUIRE(ours.converged);
  for (std::size_t k = 0; k < ours.thresholds.size(); ++k) {
    const std::string name =
        std::to_string(ours.used_categories[k]) + "|" + std::to_string(ours.used_categories[k + 1]);
    REQUIRE(r.contains(name));
    check_close(ours.thresholds[k], r.at(name).value, 1e-4, "threshold " + name);
  }
  for (std::size_t v = 1; v < ours.effects.size(); ++v) {
    const std::string name = "variant" + ours.effects[v].variant;
    REQUIRE(r.contains(name));
    check_close(ours.effects[v].estimate, r.at(name).value, 1e-4, name);
    check_close(ours.effects[v].std_error, r.at(name).se, 1e-2, name + " standard error");
  }
  check_close(ours.participant_sd, r.at("sd").value, 1e-4, "participant SD");
  check_close(ours.log_likelihood, r.at("logLik").value, 1e-6, "log-likelihood");
}

}  // namespace

TEST_CASE("ratings: the cumulative-logit mixed model agrees with R's ordinal::clmm",
          "[study][ratings]") {
  RatingTruth small;  // 12 participants, 4 variants, 5 categories
  RatingTruth panel;
  panel.participants = 20;
  panel.thresholds = {-2.5, -1.4, -0.5, 0.4, 1.3, 2.4};  // 7 categories
  panel.effects = {0.0, -1.0, 0.6};
  panel.participant_sd = 1.5;
  panel.repetitions = 3;
  RatingTruth three_point;
  three_point.thresholds = {-0.5, 0.9};
  three_point.effects = {0.0, 1.2};
  three_point.participants = 8;
  three_point.repetitions = 4;
  three_point.participant_sd = 0.6;
  const auto a = simulate_ratings(small, 3);
  const auto b = simulate_ratings(panel, 20);
  const auto c = simulate_ratings(three_point, 8);
  SECTION("Laplace (nAGQ 1)") {
    compare_with_r(a, 1, "12 participants, 5 categories");
    compare_with_r(b, 1, "20 participants, 7 categories");
    compare_with_r(c, 1, "8 participants, 3 categories");
  }
  SECTION("adaptive Gauss-Hermite (nAGQ 10)") {
    compare_with_r(a, 10, "12 participants, 5 categories");
    compare_with_r(b, 10, "20 participants, 7 categories");
    compare_with_r(c, 10, "8 participants, 3 categories");
  }
}

TEST_CASE("ratings: without a participant spread the fixed-effect model agrees with R's clm",
          "[study][ratings]") {
  RatingTruth truth;
  truth.participant_sd = 0.0;
  truth.participants = 15;
  // Seeds where the mixed model's SD comes out at its boundary 0 are kept as clm.
  int boundary_cases = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const auto data = simulate_ratings(truth, seed);
    compare_with_r(data, 0, "fixed effects, seed " + std::to_string(seed));
    const AttributeRatings mixed = fit_attribute_ratings(data);
    if (!mixed.random_effect) {
      ++boundary_cases;
      RatingsOptions fixed_only;
      fixed_only.random_effect = false;
      const AttributeRatings fixed = fit_attribute_ratings(data, fixed_only);
      for (std::size_t v = 0; v < fixed.effects.size(); ++v) {
        CHECK(mixed.effects[v].estimate == fixed.effects[v].estimate);
      }
    }
  }
  CHECK(boundary_cases > 0);
}
