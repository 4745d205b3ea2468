// Ratings: the trials adapter and its errors, the JSON rows, merged unused categories, and
// the refused inputs (the fit itself is checked against R in test_ratings_r_oracle.cpp).
#include <catch2/catch.hpp>

#include "study/statistics/ratings.h"
#include "tests/study/rating_simulation.h"

using doorbench::study::fit_attribute_ratings;
using doorbench::study::fit_ratings;
using doorbench::study::parse_trials_table;
using doorbench::study::rating_observations;
using doorbench::study::RatingObservation;
using doorbench::study::RatingsOptions;

namespace {
const std::string kRatingsHeader = "participant,block,trial,question,first,second,answer\n";
}

TEST_CASE("ratings: rating rows give one observation per presented variant", "[study][ratings]") {
  const auto table = parse_trials_table(kRatingsHeader +
                                            "P01,r,1,rating:heavy-light:7,A,B,3 6\n"
                                            "P01,p,2,preference,A,B,1\n"
                                            "P02,r,1,rating:smooth:jerky:5,B,A,5 1\n",
                                        "trials.csv");
  const auto o = rating_observations(table);
  REQUIRE(o.size() == 4);
  CHECK(o[0].attribute == "heavy-light");
  CHECK(o[0].categories == 7);
  CHECK(o[0].variant == "A");
  CHECK(o[0].rating == 3);
  CHECK(o[1].variant == "B");
  CHECK(o[1].rating == 6);
  CHECK(o[2].attribute == "smooth:jerky");  // the last ':' separates K
  CHECK(o[2].variant == "B");
  CHECK(o[3].rating == 1);
  CHECK(o[3].participant == "P02");
}

TEST_CASE("ratings: malformed rating rows are refused with their line", "[study][ratings]") {
  const auto refused = [](const std::string& row) {
    return rating_observations(parse_trials_table(kRatingsHeader + row, "t.csv"));
  };
  CHECK_THROWS_WITH(refused("P01,r,1,rating:heavy:7,A,B,3\n"),
                    "t.csv:2: answer '3' is not two ratings 1..7 (first variant's, second's)");
  CHECK_THROWS_WITH(refused("P01,r,1,rating:heavy:7,A,B,3 8\n"),
                    "t.csv:2: answer '3 8' is not two ratings 1..7 (first variant's, second's)");
  CHECK_THROWS_WITH(
      refused("P01,r,1,rating:heavy:x,A,B,3 4\n"),
      "t.csv:2: question 'rating:heavy:x' is not rating:ATTRIBUTE:K with K in 2..100");
  CHECK_THROWS_WITH(refused("P01,r,1,rating:7,A,B,3 4\n"),
                    "t.csv:2: question 'rating:7' is not rating:ATTRIBUTE:K with K in 2..100");
}

TEST_CASE("ratings: the JSON rows, the reference at 0, and unused categories merged",
          "[study][ratings]") {
  doorbench::testing::RatingTruth truth;  // K = 5
  auto data = doorbench::testing::simulate_ratings(truth, 5);
  // The same ratings declared on a 7-point scale (nobody used 6 or 7): the fit is that of
  // the categories used.
  for (auto& o : data) o.categories = 7;
  const auto seven = fit_attribute_ratings(data);
  for (auto& o : data) o.categories = 5;
  const auto five = fit_attribute_ratings(data);
  CHECK(seven.used_categories == five.used_categories);
  CHECK(seven.effects[2].estimate == Approx(five.effects[2].estimate).epsilon(1e-9));
  const auto result = fit_ratings(data);
  const auto json = result.to_json();
  REQUIRE(json.size() == 4);
  CHECK(json[0]["variant"] == "V1");
  CHECK(json[0]["estimate"] == 0.0);
  CHECK(json[0]["reference"] == true);
  CHECK(json[3]["attribute"] == "heavy");
  CHECK(json[3]["ci_low"].get<double>() < json[3]["estimate"].get<double>());
  CHECK(json[3]["estimate"].get<double>() < json[3]["ci_high"].get<double>());
  CHECK(result.models_json()[0]["model"] == "clmm");
  // The reference follows variant_order.
  RatingsOptions options;
  options.variant_order = {"V3", "V1", "V2", "V4"};
  const auto reordered = fit_attribute_ratings(data, options);
  CHECK(reordered.effects[1].estimate == Approx(-five.effects[2].estimate).epsilon(1e-4));
}

TEST_CASE("ratings: inputs that cannot be fitted are refused by name", "[study][ratings]") {
  std::vector<RatingObservation> same{{"P1", "heavy", 5, "A", 3}, {"P1", "heavy", 5, "B", 3}};
  CHECK_THROWS_WITH(fit_attribute_ratings(same), "ratings of 'heavy': every rating is the same");
  std::vector<RatingObservation> one{{"P1", "heavy", 5, "A", 3}, {"P1", "heavy", 5, "A", 4}};
  CHECK_THROWS_WITH(fit_attribute_ratings(one), "ratings of 'heavy': one variant only");
  RatingsOptions options;
  options.quadrature_nodes = 0;
  CHECK_THROWS_WITH(fit_attribute_ratings(same, options),
                    "ratings: quadrature_nodes must be 1..50 (1: Laplace), not 0");
  options = {};
  options.variant_order = {"A"};
  CHECK_THROWS_WITH(
      fit_attribute_ratings(std::vector<RatingObservation>{{"P1", "heavy", 5, "B", 3}}, options),
      "ratings of 'heavy': variant 'B' is not in variant_order");
}
