// The fit's global stage on many recordings (docs/PERFORMANCE.md, "The fit's global stage"): on
// 20 draws of the recording family at 50 Hz, 20 at 1 kHz and the 50 Hz, 4-stroke robot recording
// with an untared load cell, `fit` with --folds 0, 3 and 4 ends at the same parameters (1e-6
// relative), at a window cost never above the best of the three the fit of one start reached
// before the stage (its restarts came from a fold or from the start model). Those costs are
// doorbench_fit_study's lines for main at 35f0889 (studies/fit_study_runs_today.csv and
// studies/fit_study_runs_today_1k.csv), measured with the same recordings, starts and options.
//
// The fit started from the true door (as given, no latch read off) ends no more than 1 % below
// the fit from the data on every recording but the one where it was measured to
// (docs/PERFORMANCE.md, "Fits with softer switches" and "Screening the fits with softer
// switches"): 40 of 41, where the aim is 39.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "tests/support/model_difference.h"
#include "tests/support/robot_recording.h"

namespace doorbench {
namespace {

// The lowest final cost of the fits from the data, any --folds, per recording, over the study's
// CSV files (columns recording,start,folds,cpu_s,wall_s,final_cost,...).
std::map<std::string, double> best_costs_before_the_stage() {
  std::map<std::string, double> best;
  for (const char* name : {"fit_study_runs_today.csv", "fit_study_runs_today_1k.csv"}) {
    const std::string path = std::string(DOORBENCH_SOURCE_DIR) + "/studies/" + name;
    std::ifstream file(path);
    REQUIRE(file);
    std::string line;
    std::getline(file, line);
    while (std::getline(file, line)) {
      std::vector<std::string> fields;
      std::stringstream stream(line);
      for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
      if (fields.size() < 6 || fields[1] != "data") continue;
      const double cost = std::stod(fields[5]);
      const auto [it, inserted] = best.emplace(fields[0], cost);
      if (!inserted) it->second = std::min(it->second, cost);
    }
  }
  return best;
}

// The recording whose fit from the true door ends more than 1 % below the fit from the data
// (studies/fit_study_runs_soft_screen_truth.csv: −1.49 %): a true-door basin that no start of
// the global stage reaches.
bool measured_truth_miss(const std::string& recording) {
  return recording == "family1000-3";
}

// As `doorbench fit` without --params: the reference door with the recording's handle radius,
// its values taken from the data, RK4 steps of at most 1 ms (substeps_for_1ms_steps). `truth`:
// the door the recording was made with.
void check_folds_and_cost(const std::string& recording, const PreparedData& data,
                          const DoorModel& truth, const std::map<std::string, double>& before) {
  INFO(recording);
  const DoorModel start = testing::fit_start_read_off(data);
  const auto fit_with_folds = [&](int folds) {
    FitOptions options;
    options.substeps_per_sample = substeps_for_1ms_steps(data);
    options.cross_validation_folds = folds;
    return fit_model(start, data, options);
  };
  const FitResult none = fit_with_folds(0);
  for (int folds : {3, 4}) {
    INFO("--folds " << folds);
    const FitResult with = fit_with_folds(folds);
    CHECK(testing::largest_relative_difference(none.model, with.model) <= 1e-6);
    CHECK(with.summary.final_cost == Approx(none.summary.final_cost).epsilon(1e-9));
  }
  REQUIRE(before.count(recording) == 1);
  INFO("cost " << none.summary.final_cost << ", the best before the stage "
               << before.at(recording));
  CHECK(none.summary.final_cost <= before.at(recording) * (1.0 + 1e-6));
  FitOptions from_truth;
  from_truth.substeps_per_sample = substeps_for_1ms_steps(data);
  from_truth.cross_validation_folds = 0;
  from_truth.latch_start_from_data = false;
  const double truth_cost = fit_model(truth, data, from_truth).summary.final_cost;
  INFO("from the true door " << truth_cost);
  if (!measured_truth_miss(recording)) CHECK(truth_cost >= 0.99 * none.summary.final_cost);
}

// Draws first_seed .. last_seed of the recording family at one rate (testing::family_draw).
void check_family_draws(double rate_hz, std::uint32_t first_seed, std::uint32_t last_seed) {
  const std::map<std::string, double> before = best_costs_before_the_stage();
  for (std::uint32_t seed = first_seed; seed <= last_seed; ++seed) {
    const PreparedData data = testing::family_draw(seed, rate_hz);
    REQUIRE(data.sample_rate_hz == Approx(rate_hz));
    check_folds_and_cost(
        "family" + std::to_string(static_cast<int>(rate_hz)) + "-" + std::to_string(seed), data,
        testing::sensory_reference(), before);
  }
}

}  // namespace

TEST_CASE(
    "Global search on many draws: --folds 0, 3 and 4 agree, at no more than the cost before "
    "the stage and at most 1 % above the fit from the true door, on the robot recording and the "
    "family's 50 Hz draws 1-10",
    "[fitting][global][slow]") {
  check_folds_and_cost("robot50", testing::robot_recording(), testing::robot_door(),
                       best_costs_before_the_stage());
  check_family_draws(50.0, 1, 10);
}

TEST_CASE(
    "Global search on many draws: --folds 0, 3 and 4 agree, at no more than the cost before "
    "the stage and at most 1 % above the fit from the true door, on the family's 50 Hz draws 11-20",
    "[fitting][global][slow]") {
  check_family_draws(50.0, 11, 20);
}

TEST_CASE(
    "Global search on many draws: --folds 0, 3 and 4 agree, at no more than the cost before "
    "the stage and at most 1 % above the fit from the true door, on the family's 1 kHz draws 1-5",
    "[fitting][global][slow]") {
  check_family_draws(1000.0, 1, 5);
}

TEST_CASE(
    "Global search on many draws: --folds 0, 3 and 4 agree, at no more than the cost before "
    "the stage and at most 1 % above the fit from the true door, on the family's 1 kHz draws 6-10",
    "[fitting][global][slow]") {
  check_family_draws(1000.0, 6, 10);
}

TEST_CASE(
    "Global search on many draws: --folds 0, 3 and 4 agree, at no more than the cost before "
    "the stage and at most 1 % above the fit from the true door, on the family's 1 kHz draws 11-15",
    "[fitting][global][slow]") {
  check_family_draws(1000.0, 11, 15);
}

TEST_CASE(
    "Global search on many draws: --folds 0, 3 and 4 agree, at no more than the cost before "
    "the stage and at most 1 % above the fit from the true door, on the family's 1 kHz draws 16-20",
    "[fitting][global][slow]") {
  check_family_draws(1000.0, 16, 20);
}

}  // namespace doorbench
