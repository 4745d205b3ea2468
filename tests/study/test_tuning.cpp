// Tuning: the panel's distribution per parameter in perceptual steps, clusters when the
// panel splits (and not when it does not), the doors read from the trials table's files,
// and the plot.
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "study/statistics/tuning.h"

using doorbench::study::analyze_tuning;
using doorbench::study::render_tuning_plot;
using doorbench::study::TunedDoor;
using doorbench::study::TuningOptions;

namespace {

// Doors with J, k_l and theta0 (no step); log-normal around the given centres.
std::vector<TunedDoor> panel(int doors, double j, double k, double sd_log, std::mt19937_64& random,
                             const std::string& prefix = "P") {
  std::normal_distribution<double> normal(0.0, sd_log);
  std::vector<TunedDoor> out;
  for (int i = 0; i < doors; ++i) {
    out.push_back({prefix + std::to_string(i + 1),
                   "",
                   {{"J", j * std::exp(normal(random))},
                    {"k_l", k * std::exp(normal(random))},
                    {"theta0", 0.1 + 0.01 * normal(random)}}});
  }
  return out;
}

}  // namespace

TEST_CASE("tuning: each parameter's centre, spread and interval, in perceptual steps",
          "[study][tuning]") {
  const std::vector<TunedDoor> doors{{"P1", "", {{"J", 0.10}, {"k_l", 100.0}, {"A_x", -0.02}}},
                                     {"P2", "", {{"J", 0.121}, {"k_l", 100.0}, {"A_x", 0.01}}},
                                     {"P3", "", {{"J", 0.11}, {"k_l", 100.0}, {"A_x", 0.04}}}};
  TuningOptions options;
  options.measured_weber["k_l"] = 0.25;
  const auto result = analyze_tuning(doors, options);
  REQUIRE(result.parameters.size() == 3);
  const auto& j = result.parameters[0];
  const double mean_log = (std::log(0.10) + std::log(0.121) + std::log(0.11)) / 3.0;
  CHECK(j.centre == Approx(std::exp(mean_log)));
  double squares = 0.0;
  for (const double v : {0.10, 0.121, 0.11}) squares += std::pow(std::log(v) - mean_log, 2);
  const double sd = std::sqrt(squares / 2.0);
  CHECK(j.spread == Approx(sd));
  CHECK(j.ci_high == Approx(std::exp(mean_log + 4.302652729911275 * sd / std::sqrt(3.0))));
  CHECK(*j.weber_fraction == 0.10);
  CHECK(j.weber_source == "typical: inertia 10%");
  CHECK(*j.spread_steps == Approx(sd / std::log(1.1)));
  const auto& k = result.parameters[1];
  CHECK(k.weber_source == "measured (jnd)");
  CHECK(*k.spread_steps == 0.0);
  const auto& a = result.parameters[2];
  CHECK_FALSE(a.log_scale);
  CHECK(a.centre == Approx(0.01));
  CHECK_FALSE(a.spread_steps.has_value());
  CHECK(a.weber_source == "none");
  const auto json = result.to_json();
  CHECK(json["parameters"][2]["spread_steps"].is_null());
  CHECK(json["parameters"][0]["scale"] == "log");
  CHECK(json["doors"][1]["parameters"]["J"] == 0.121);
}

TEST_CASE("tuning: a panel of two groups splits, one group does not", "[study][tuning]") {
  std::mt19937_64 random(11);
  int false_splits = 0;
  for (int seed = 0; seed < 20; ++seed) {
    const auto one = panel(20, 0.1, 300.0, 0.08, random);
    if (analyze_tuning(one).clusters.split) ++false_splits;
  }
  CHECK(false_splits <= 2);
  auto doors = panel(10, 0.08, 300.0, 0.05, random, "A");
  const auto heavy = panel(10, 0.13, 300.0, 0.05, random, "B");
  doors.insert(doors.end(), heavy.begin(), heavy.end());
  const auto result = analyze_tuning(doors);
  REQUIRE(result.clusters.split);
  CHECK(result.clusters.dimensions == std::vector<std::string>{"J", "k_l"});
  for (int i = 0; i < 20; ++i)
    CHECK(result.clusters.group[i] == result.clusters.group[i < 10 ? 0 : 10]);
  const double expected = std::log(0.13 / 0.08) / std::log(1.1);
  CHECK(result.clusters.separation == Approx(expected).epsilon(0.15));
  CHECK(std::abs(result.clusters.separation_steps.at("J")) == Approx(expected).epsilon(0.15));
  const std::string svg = render_tuning_plot(result);
  CHECK(svg.find("<svg") != std::string::npos);
  CHECK(svg.find("B7 (") != std::string::npos);
  CHECK(result.to_json()["clusters"]["groups"].size() == 2);
}

TEST_CASE("tuning: the doors of a trials table are read from their parameter files",
          "[study][tuning]") {
  doorbench::testing::TempDir dir("tuning");
  auto door = nlohmann::json::parse(doorbench::reference_door_json());
  door["sensory"]["J"]["value"] = 0.123;
  dir.write("tuned/P01.json", door.dump());
  door["sensory"]["J"]["value"] = 0.2;
  dir.write("tuned/P02-first.json", door.dump());
  door["sensory"]["J"]["value"] = 0.15;
  dir.write("tuned/P02.json", door.dump());
  const std::string header = "participant,block,trial,question,first,second,answer\n";
  const auto table = doorbench::study::parse_trials_table(
      header +
          "P01,tune,1,tune,,,tuned/P01.json\nP02,tune,1,tune,,,tuned/P02-first.json\n"
          "P02,tune,2,tune,,,tuned/P02.json\nP02,r,3,rating:heavy:5,A,B,1 2\n",
      "trials.csv");
  const auto doors = doorbench::study::tuned_doors(table, dir.path);
  REQUIRE(doors.size() == 2);
  CHECK(doors[0].participant == "P01");
  CHECK(doors[0].parameters[0] == std::pair<std::string, double>{"J", 0.123});
  CHECK(doors[1].file == "tuned/P02.json");
  CHECK(doors[1].parameters[0].second == 0.15);
  const auto physical = std::find_if(doors[0].parameters.begin(), doors[0].parameters.end(),
                                     [](const auto& p) { return p.first == "J_d"; });
  CHECK(physical != doors[0].parameters.end());
  CHECK_THROWS_WITH(
      doorbench::study::tuned_doors(
          doorbench::study::parse_trials_table(header + "P01,t,1,tune,,,\n", "t.csv"), dir.path),
      "t.csv:2: answer is empty (a tune row names its tuned parameter file)");
  CHECK_THROWS_WITH(
      analyze_tuning(std::vector<TunedDoor>{{"P1", "", {{"J", 1.0}}}, {"P2", "", {{"k", 1.0}}}}),
      "tuning: the door of P2 names other parameters than that of P1");
}
