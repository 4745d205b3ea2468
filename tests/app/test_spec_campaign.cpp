// `doorbench spec --campaign`: analysis.json read (hand-written here, in the schema `campaign
// analyze` writes), the errors word for word, --felt-share, the TO-BE door chosen, and one
// end-to-end run writing the perceptual tolerance table.
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>

#include "analysis/model/parameter_file.h"
#include "app/commands.h"
#include "app/spec_campaign.h"
#include "app/spec_run.h"
#include "core/number_format.h"
#include "fixtures/temp_dir.h"
#include "study/statistics/analysis_for_spec.h"
#include "tests/support/run_doorbench.h"

using Catch::Matchers::Contains;
using doorbench::CampaignForSpec;
using doorbench::app::parse_felt_share;
using doorbench::study::read_campaign_for_spec;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

namespace {

const char* kPreference =
    R"("preference_scale": [{"variant": "A", "worth": 0, "ci_low": null, "ci_high": null},
                            {"variant": "B", "worth": 0.8, "ci_low": 0.3, "ci_high": 1.3,
                             "file": "variants/B.json"},
                            {"variant": "C", "worth": -0.2, "ci_low": -0.7, "ci_high": 0.3}])";

const char* kJnd =
    R"("jnd": [{"parameter": "k_l", "reference": "k_l*1.00", "participant": "P01",
                "method": "psychometric fit", "weber_fraction": 0.4, "ci_low": 0.2,
                "ci_high": null, "criterion": "75%"},
               {"parameter": "k_l", "reference": "k_l*1.00", "participant": "panel",
                "method": "psychometric fit, pooled", "weber_fraction": 0.17, "ci_low": 0.14,
                "ci_high": 0.21, "criterion": "75.0% of the lapse-free cumulative normal"},
               {"parameter": "J_d", "reference": "J_d*1.00", "participant": "panel",
                "method": "psychometric fit, pooled", "weber_fraction": 0.1, "ci_low": 0.09,
                "ci_high": 0.11, "criterion": "75%"}])";

std::string analysis(const std::string& sections) {
  return "{" + sections + "}";
}

std::string error_of(const std::filesystem::path& folder) {
  try {
    read_campaign_for_spec(folder);
  } catch (const std::exception& error) {
    return error.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("spec --campaign: analysis.json missing or malformed, word for word",
          "[spec][campaign]") {
  TempDir dir("spec_campaign_errors");
  const std::string file = (dir / "out" / "analysis.json").string();
  std::filesystem::create_directories(dir / "out");
  CHECK(error_of(dir / "out") == file +
                                     ": no such file (--campaign takes a `doorbench campaign "
                                     "analyze` output folder)");
  dir.write("out/analysis.json", "[1, 2]");
  CHECK(error_of(dir / "out") == file + ": a JSON object expected");
  dir.write("out/analysis.json", analysis(R"("jnd": {"parameter": "k_l"})"));
  CHECK(error_of(dir / "out") == file + ": jnd: an array expected");
  dir.write("out/analysis.json",
            analysis(R"("jnd": [{"participant": "panel", "parameter": "k_l", "reference": "r",
                                 "weber_fraction": "17%", "ci_low": 0.1, "ci_high": 0.2}])"));
  CHECK(error_of(dir / "out") == file + ": jnd[0].weber_fraction: a number expected");
  dir.write("out/analysis.json",
            analysis(R"("jnd": [{"participant": "panel", "parameter": "k_l", "reference": "r",
                                 "weber_fraction": -0.1, "ci_low": 0.1, "ci_high": 0.2}])"));
  CHECK(error_of(dir / "out") == file + ": jnd[0].weber_fraction: a positive number expected");
  dir.write("out/analysis.json",
            analysis(R"("jnd": [{"participant": "panel", "reference": "r", "weber_fraction": 0.1,
                                 "ci_low": 0.1, "ci_high": 0.2}])"));
  CHECK(error_of(dir / "out") == file + ": jnd[0].parameter: missing");
  dir.write("out/analysis.json",
            analysis(R"("jnd": [{"participant": "panel", "parameter": "k_l", "reference": "r",
                                 "weber_fraction": 0.1, "ci_low": "low", "ci_high": 0.2}])"));
  CHECK(error_of(dir / "out") == file + ": jnd[0].ci_low: a number or null expected");
  dir.write("out/analysis.json", analysis(R"("preference_scale": [{"worth": 0.2}])"));
  CHECK(error_of(dir / "out") == file + ": preference_scale[0].variant: missing");
  dir.write("out/analysis.json", analysis(R"("tuning": {"parameters": [{"parameter": "F0",
                                                          "centre": "high"}]})"));
  CHECK(error_of(dir / "out") == file + ": tuning.parameters[0].centre: a number or null expected");
  dir.write("out/analysis.json", "{\"jnd\": [");
  CHECK_THAT(error_of(dir / "out"), Contains(file + ": not JSON: "));
}

TEST_CASE("spec --campaign: no jnd section means typical JNDs, said so", "[spec][campaign]") {
  TempDir dir("spec_campaign_typical");
  dir.write("out/analysis.json", analysis(kPreference));
  const CampaignForSpec c = read_campaign_for_spec(dir / "out");
  const std::string file = (dir / "out" / "analysis.json").string();
  REQUIRE(c.notes.size() == 1);
  CHECK(c.notes[0] == "no jnd section in " + file +
                          ": typical published JNDs used (stiffness 15%, friction 20%)");
  REQUIRE(c.jnds.size() == doorbench::kFeltQuantities.size());
  for (const doorbench::FeltJnd& jnd : c.jnds) CHECK_FALSE(jnd.measured);
  CHECK(c.jnds[0].source == "typical: stiffness 15%");
  CHECK(c.jnds[0].weber_fraction == 0.15);
  CHECK(c.jnds[3].source == "typical: friction 20%");
  CHECK(c.favourite == "B");
  CHECK(c.favourite_file == dir / "out" / "variants/B.json");
  CHECK(c.preference.size() == 3);
  CHECK(std::isnan(c.preference[0].ci_low));
}

TEST_CASE("spec --campaign: the panel's measured JND stands for the quantities it governs",
          "[spec][campaign]") {
  TempDir dir("spec_campaign_measured");
  dir.write("out/analysis.json", analysis(std::string(kPreference) + ", " + kJnd));
  const CampaignForSpec c = read_campaign_for_spec(dir / "out");
  REQUIRE(c.thresholds.size() == 2);  // the panel's rows only
  // The catch's spring k_l: both latch peaks; friction and balance keep the typical values.
  CHECK(c.jnds[0].measured);
  CHECK(c.jnds[0].weber_fraction == 0.17);
  CHECK(c.jnds[0].source == "measured: k_l (panel, psychometric fit, pooled)");
  CHECK(c.jnds[1].measured);
  CHECK_FALSE(c.jnds[2].measured);
  CHECK_FALSE(c.jnds[5].measured);
  CHECK(c.jnds[5].source == "typical: stiffness 15%");
  REQUIRE(c.notes.size() == 1);
  CHECK(c.notes[0] ==
        "the panel's JND of J_d stands for no felt quantity of the specification: not used");
}

TEST_CASE("spec --felt-share: percent or fraction, strictly between 0 and 1", "[spec][campaign]") {
  CHECK(parse_felt_share("5%") == 0.05);
  CHECK(parse_felt_share("0.05") == 0.05);
  CHECK(parse_felt_share("12.5%") == 0.125);
  for (const char* bad : {"5", "0", "0%", "100%", "150%", "1", "-2%", "five", "", "5%%", "0.05x"}) {
    INFO(bad);
    CHECK_THROWS_WITH(parse_felt_share(bad), std::string("--felt-share: '") + bad +
                                                 "' is not a share between 0 and 1 (e.g. 5% or "
                                                 "0.05)");
  }
}

TEST_CASE("spec --campaign: the TO-BE door from the favourite variant or the tuned centre",
          "[spec][campaign]") {
  TempDir dir("spec_campaign_tobe");
  const doorbench::DoorModel asis = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  std::vector<double> values(asis.parameter_values().begin(), asis.parameter_values().end());
  values[doorbench::physical::kFl0] *= 0.7;
  dir.write("out/variants/B.json",
            doorbench::to_parameter_json(asis.with_parameter_values(values)));
  dir.write("out/analysis.json", analysis(kPreference));
  std::string source;
  const doorbench::DoorModel favourite =
      doorbench::campaign_tobe_model(read_campaign_for_spec(dir / "out"), asis, source);
  CHECK(favourite.parameter_values()[doorbench::physical::kFl0] ==
        values[doorbench::physical::kFl0]);
  CHECK_THAT(source, Contains("the panel's favourite variant B (largest worth"));

  dir.write("out/analysis.json", analysis(R"("tuning": {"doors": [{}, {}, {}], "parameters": [
                {"parameter": "F0", "centre": 230.0}, {"parameter": "physical.k_l", "centre": 900},
                {"parameter": "J_d", "centre": null}]})"));
  const doorbench::DoorModel tuned =
      doorbench::campaign_tobe_model(read_campaign_for_spec(dir / "out"), asis, source);
  CHECK(tuned.parameter_values()[*tuned.find_parameter("F0")] == 230.0);
  CHECK(tuned.parameter_values()[*tuned.find_parameter("k_l")] == 900.0);
  CHECK(tuned.parameter_values()[*tuned.find_parameter("T_h")] ==
        asis.parameter_values()[*asis.find_parameter("T_h")]);
  CHECK(source ==
        "the centre of the panel's 3 tuned doors (tuning section; 2 physical parameters, the "
        "rest AS-IS), because there is no preference scale");

  dir.write("out/analysis.json", analysis(R"("preference_scale": [{"variant": "A", "worth": 0,
                                              "ci_low": null, "ci_high": null}])"));
  const std::string file = (dir / "out" / "analysis.json").string();
  CHECK_THROWS_WITH(
      doorbench::campaign_tobe_model(read_campaign_for_spec(dir / "out"), asis, source),
      file +
          ": no TO-BE feel: the favourite variant A names no parameter file and no tuning "
          "section gives a door's parameters (give TO-BE recordings instead)");
}

TEST_CASE("spec: the campaign options refused word for word", "[spec][campaign]") {
  TempDir dir("spec_campaign_usage");
  doorbench::app::SpecCommandOptions options;
  options.asis_path = (dir / "asis.json").string();
  options.out_dir = (dir / "spec").string();
  CHECK_THROWS_WITH(doorbench::app::run_spec(options),
                    "spec: give TO-BE recordings or --campaign FOLDER");
  options.tobe_paths = {(dir / "tobe.csv").string()};
  options.felt_share = "5%";
  CHECK_THROWS_WITH(doorbench::app::run_spec(options), "--felt-share needs --campaign");
  options.campaign_dir = (dir / "out").string();
  options.felt_share = "50";
  CHECK_THROWS_WITH(doorbench::app::run_spec(options),
                    "--felt-share: '50' is not a share between 0 and 1 (e.g. 5% or 0.05)");
  options.no_tolerances = true;
  CHECK_THROWS_WITH(doorbench::app::run_spec(options),
                    "--campaign needs the tolerance analysis: drop --no-tolerances");
}

TEST_CASE("CLI: spec --campaign writes the perceptual tolerance table", "[cli][spec][campaign]") {
  TempDir dir("spec_campaign_cli");
  const doorbench::DoorModel asis = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  std::vector<double> values(asis.parameter_values().begin(), asis.parameter_values().end());
  values[doorbench::physical::kFl0] *= 0.7;
  const auto asis_file = dir.write("asis.json", doorbench::to_parameter_json(asis));
  dir.write("out/variants/B.json",
            doorbench::to_parameter_json(asis.with_parameter_values(values)));
  dir.write("out/analysis.json", analysis(std::string(kPreference) + ", " + kJnd));
  const auto run =
      run_doorbench_shell("spec --campaign '" + (dir / "out").string() + "' --asis '" +
                              asis_file.string() + "' --out '" + (dir / "spec").string() +
                              "' --samples 40 --starts 1 --no-pdf --felt-share 10%",
                          dir);
  INFO("stdout: " << run.out << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Contains("TO-BE feel from the panel: the panel's favourite variant B"));
  CHECK_THAT(run.out, Contains("tolerances judged by the panel:\n"));
  CHECK_THAT(run.out, Contains("measured: k_l (panel, psychometric fit, pooled)"));
  const auto json = nlohmann::json::parse(doorbench::read_text_file(dir / "spec" / "spec.json"));
  const auto& p = json["perceptual"];
  REQUIRE(p.is_object());
  CHECK(p["felt_share"] == 0.1);
  CHECK(p["preference_scale"].size() == 3);
  CHECK(p["thresholds"].size() == 2);
  REQUIRE(p["quantities"].size() == doorbench::kFeltQuantities.size());
  for (const auto& q : p["quantities"]) {
    INFO(q.dump());
    const auto& given = q["as_given"];
    CHECK(given["doors"].get<int>() > 30);
    if (given["share"].is_number()) {
      CHECK(given["share"].get<double>() ==
            static_cast<double>(given["felt_different"].get<int>()) / given["doors"].get<int>());
      CHECK(given["ci_low"].get<double>() <= given["share"].get<double>());
    }
    if (q["proposed"]["share"].is_number() && p["proposal"]["reached"].get<bool>()) {
      CHECK(q["proposed"]["share"].get<double>() <= 0.1);
    }
  }
  CHECK(p["quantities"][0]["jnd_source"] == "measured: k_l (panel, psychometric fit, pooled)");
  CHECK(p["quantities"][3]["jnd_source"] == "typical: friction 20%");
  // The alternatives are judged with the panel's JNDs where it measured them.
  CHECK_THAT(json["equivalence"]["criterion"].get<std::string>(),
             Contains("its JND (the panel's measured ones for "));
  CHECK(p["proposal"]["tolerances"].size() == json["tolerances"]["parameters"].size());
  const std::string html = doorbench::read_text_file(dir / "spec" / "spec.html");
  CHECK_THAT(html, Contains("Tolerances judged by the panel's perception"));
  CHECK_THAT(html, Contains("The panel's preference scale"));
  CHECK_THAT(html, Contains("Thresholds measured (panel)"));
}

// The analysis.json `campaign analyze` writes (not one written by hand): a pair block and a
// jnd block of k_l from a trials table, analysed by the command, then read for the spec.
TEST_CASE("spec --campaign reads what campaign analyze writes", "[spec][campaign]") {
  TempDir dir("spec_campaign_analyze");
  std::string table = "participant,block,trial,question,first,second,answer\n";
  int trial = 0;
  for (const char* participant : {"P1", "P2"}) {
    for (int t = 0; t < 10; ++t) {  // B preferred 7 times of 10
      const bool a_first = t % 2 == 0;
      const bool prefer_b = t < 7;
      table += std::string(participant) + ",pair," + std::to_string(++trial) + ",preference," +
               (a_first ? "A,B," : "B,A,") + ((prefer_b == a_first) ? "2" : "1") + "\n";
    }
    // k_l: comparisons 0.8 .. 1.25 x the reference, "stronger" more often the larger.
    const double factors[] = {0.8, 0.9, 0.95, 1.05, 1.1, 1.25};
    const int stronger_of_10[] = {1, 2, 4, 6, 8, 9};
    for (int level = 0; level < 6; ++level) {
      for (int t = 0; t < 10; ++t) {
        const bool comparison_first = t % 2 == 0;
        const std::string comparison = "k_l*" + doorbench::format_number(factors[level]);
        const bool stronger = t < stronger_of_10[level];
        table += std::string(participant) + ",jnd," + std::to_string(++trial) + ",stronger:k_l," +
                 (comparison_first ? comparison + ",k_l*1.00," : "k_l*1.00," + comparison + ",") +
                 ((stronger == comparison_first) ? "1" : "2") + "\n";
      }
    }
  }
  const auto trials = dir.write("trials.csv", table);
  const auto run = run_doorbench_shell(
      "campaign analyze '" + trials.string() + "' --out '" + (dir / "out").string() + "'", dir);
  INFO("stdout: " << run.out << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
  const auto analysis =
      nlohmann::json::parse(doorbench::read_text_file(dir / "out" / "analysis.json"));
  const CampaignForSpec c = read_campaign_for_spec(dir / "out");
  CHECK(c.favourite == "B");
  REQUIRE(c.preference.size() == 2);
  double panel_weber = 0;
  for (const auto& row : analysis["jnd"]) {
    if (row["participant"] == "panel" && row["parameter"] == "k_l") {
      panel_weber = row["weber_fraction"].get<double>();
    }
  }
  REQUIRE(panel_weber > 0);
  CHECK(c.jnds[0].measured);
  CHECK(c.jnds[0].weber_fraction == panel_weber);
  CHECK(c.jnds[0].source == "measured: k_l (panel, psychometric fit, pooled)");
  CHECK_FALSE(c.jnds[3].measured);
}
