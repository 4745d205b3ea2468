// The three sections `campaign analyze` writes for ratings, thresholds and tuning, from one
// trials.csv written by hand (as 29's analyze verb calls them), and the psychometric plot.
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "study/statistics/ratings.h"
#include "study/statistics/thresholds.h"
#include "study/statistics/tuning.h"
#include "tests/support/files.h"

namespace study = doorbench::study;

TEST_CASE("ratings and jnd and tuning sections come from one hand-written trials.csv",
          "[study][ratings][thresholds][tuning]") {
  doorbench::testing::TempDir dir("stats_from_trials");
  std::string csv = "participant,block,trial,question,first,second,answer,time_s\n";
  std::mt19937_64 random(4);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  auto door = nlohmann::json::parse(doorbench::reference_door_json());
  const double reference_j = door["sensory"]["J"]["value"].get<double>();
  for (int p = 1; p <= 6; ++p) {
    const std::string id = "P0" + std::to_string(p);
    // Ratings: B is rated about two points heavier than A.
    for (int r = 0; r < 3; ++r) {
      const int a = 2 + (p + r) % 3, b = std::min(7, a + 2 - (r == 2 ? 1 : 0));
      csv += id + ",rating," + std::to_string(r + 1) + ",rating:heavy:7," +
             (r % 2 ? "B,A," : "A,B,") +
             (r % 2 ? std::to_string(b) + " " + std::to_string(a)
                    : std::to_string(a) + " " + std::to_string(b)) +
             ",1.5\n";
    }
    // A jnd block by constant stimuli around J_d*1.00, the comparison first in odd trials.
    int trial = 0;
    for (int rep = 0; rep < 8; ++rep) {
      for (const double factor : {0.8, 0.9, 0.95, 1.05, 1.1, 1.2}) {
        const double p_stronger = 0.5 * std::erfc(-std::log(factor) / 0.12 / std::sqrt(2.0));
        const bool stronger = uniform(random) < p_stronger;
        char label[32];
        std::snprintf(label, sizeof label, "J_d*%.2f", factor);
        const bool comparison_first = ++trial % 2 == 1;
        csv += id + ",jnd," + std::to_string(trial) + ",stronger:J_d," +
               (comparison_first ? std::string(label) + ",J_d*1.00,"
                                 : std::string("J_d*1.00,") + label + ",") +
               (stronger == comparison_first ? "1" : "2") + ",2.0\n";
      }
    }
    // The tuned door: J 10 % heavier for the last three.
    door["sensory"]["J"]["value"] = reference_j * (p > 3 ? 1.1 : 1.0) * (1.0 + 0.01 * p);
    dir.write("tuned/" + id + ".json", door.dump());
    csv += id + ",tune,1,tune,,,tuned/" + id + ".json,30\n";
  }
  const auto path = dir.write("campaign/trials.csv", csv);
  const auto table = study::read_trials_table(path);

  nlohmann::json analysis;
  const auto ratings = study::fit_ratings(study::rating_observations(table));
  analysis["ratings"] = ratings.to_json();
  const auto thresholds = study::fit_thresholds(study::stronger_observations(table));
  analysis["jnd"] = thresholds.to_json();
  study::TuningOptions tuning_options;
  tuning_options.measured_weber = study::measured_weber_fractions(thresholds);
  const auto tuning = study::analyze_tuning(study::tuned_doors(table, dir.path), tuning_options);
  analysis["tuning"] = tuning.to_json();

  REQUIRE(analysis["ratings"].size() == 2);
  CHECK(analysis["ratings"][1]["variant"] == "B");
  CHECK(analysis["ratings"][1]["ci_low"].get<double>() > 0.0);  // B rated heavier, clearly
  REQUIRE(analysis["jnd"].size() == 7);                         // the panel and six participants
  const auto& panel = analysis["jnd"][0];
  CHECK(panel["participant"] == "panel");
  CHECK(panel["reference"] == "J_d*1.00");
  CHECK(panel["trials"] == 288);
  const double truth = std::expm1(0.12 * 0.6744897501960817);
  CHECK(panel["ci_low"].get<double>() < truth);
  CHECK(panel["ci_high"].get<double>() > truth);
  CHECK(tuning_options.measured_weber.at("J_d") == panel["weber_fraction"].get<double>());
  const auto& j = analysis["tuning"]["parameters"][0];
  CHECK(j["parameter"] == "J");
  CHECK(j["weber_source"] == "typical: inertia 10%");
  CHECK(analysis["tuning"]["doors"].size() == 6);

  const auto svg_path = (dir / "jnd-J_d.svg").string();
  study::write_psychometric_plot(svg_path, thresholds.parameters[0]);
  const std::string svg = doorbench::testing::read_file(svg_path);
  CHECK(svg.find("J_d around J_d*1.00") != std::string::npos);
  CHECK(svg.find("panel&#39;s answers") != std::string::npos);  // XML-escaped: core/html_escape.h
  CHECK(svg.find("comparison / reference") != std::string::npos);
}
