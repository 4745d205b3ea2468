// `doorbench campaign report ANALYSIS --out DIR`: the report and every plot again from
// analysis.json alone, the same as `campaign analyze` drew them; the plots redrawn from the
// JSON equal the ones the sections draw from their fits; the SVG check over both folders;
// the errors word for word.
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>

#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "study/statistics/analysis.h"
#include "study/trials_table.h"
#include "tests/study/simulated_panel.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/svg_check.h"

using doorbench::testing::append_row;
using doorbench::testing::kTrialsHeader;
using doorbench::testing::read_file;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;
using json = nlohmann::json;

namespace {

// Every section at once, in dir/campaign: pairs A/B (both orders, a tie), identify-real,
// ratings of heaviness (B about two points heavier), a jnd block of J_d (cumulative normal,
// Weber fraction about 8 %), and six tuned doors in two groups (J 10 % apart).
void write_campaign(const TempDir& dir) {
  std::string text = kTrialsHeader;
  const char* answers[] = {"2", "2", "1", "same", "2", "1", "2", "1", "2", "2"};
  for (int t = 0; t < 10; ++t) {
    const bool a_first = t % 2 == 0;
    append_row(text, {t < 5 ? "P01" : "P02", "pair", std::to_string(t + 1), "preference-2ac",
                      a_first ? "A" : "B", a_first ? "B" : "A", answers[t]});
  }
  const char* ir[] = {"1", "2", "1", "2", "1", "1", "2", "2"};
  for (int t = 0; t < 8; ++t) {
    const bool real_first = t % 2 == 0;
    append_row(text, {"P01", "ir", std::to_string(t + 1), "identify-real",
                      real_first ? "real" : "A", real_first ? "A" : "real", ir[t]});
  }
  doorbench::testing::PanelRandom random(8);
  auto door = json::parse(doorbench::reference_door_json());
  const double reference_j = door["sensory"]["J"]["value"].get<double>();
  for (int p = 1; p <= 6; ++p) {
    const std::string id = std::string("P0").append(std::to_string(p));
    for (int r = 0; r < 3; ++r) {
      const int a = 2 + (p + r) % 3, b = std::min(7, a + 2 - (r == 2 ? 1 : 0));
      append_row(text, {id, "rating", std::to_string(r + 1), "rating:heavy:7", "A", "B",
                        std::to_string(a).append(" ").append(std::to_string(b))});
    }
    int trial = 0;
    for (int rep = 0; rep < 8; ++rep) {
      for (const char* level :
           {"J_d*0.80", "J_d*0.90", "J_d*0.95", "J_d*1.05", "J_d*1.10", "J_d*1.20"}) {
        const double factor = std::stod(std::string(level).substr(4));
        const double p_stronger = 0.5 * std::erfc(-std::log(factor) / 0.12 / std::sqrt(2.0));
        const bool stronger = random.uniform() < p_stronger;
        const bool comparison_first = ++trial % 2 == 1;
        append_row(text,
                   {id, "jnd", std::to_string(trial), "stronger:J_d",
                    comparison_first ? level : "J_d*1.00", comparison_first ? "J_d*1.00" : level,
                    stronger == comparison_first ? "1" : "2"});
      }
    }
    door["sensory"]["J"]["value"] = reference_j * (p > 3 ? 1.1 : 1.0) * (1.0 + 0.01 * p);
    dir.write("campaign/tuned/" + id + ".json", door.dump());
    append_row(text, {id, "tune", "1", "tune", "", "", "tuned/" + id + ".json"});
  }
  dir.write("campaign/trials.csv", text);
}

doorbench::testing::DoorbenchRun run_verb(const std::string& args, const TempDir& dir) {
  return run_doorbench_shell(args, dir);
}

}  // namespace

TEST_CASE("campaign report redraws what campaign analyze drew from analysis.json alone",
          "[study][campaign]") {
  TempDir dir("campaign_report");
  write_campaign(dir);
  const auto analyzed = run_verb("campaign analyze '" + (dir / "campaign").string() +
                                     "' --no-pdf --out '" + (dir / "analysis").string() + "'",
                                 dir);
  INFO("analyze: " << analyzed.err);
  REQUIRE(analyzed.status == 0);
  const auto reported = run_verb("campaign report '" + (dir / "analysis").string() +
                                     "' --no-pdf --out '" + (dir / "report").string() + "'",
                                 dir);
  INFO("report: " << reported.out << reported.err);
  REQUIRE(reported.status == 0);
  CHECK(reported.err.empty());
  CHECK_THAT(reported.out,
             Catch::Matchers::Contains("wrote " + (dir / "report" / "report.html").string() +
                                       " and 6 plot(s)\nno PDF (not asked for)\n"));
  // Every plot the issue asks for, byte for byte the same in both folders.
  for (const char* file : {"preference-scale.svg", "identify-real.svg", "two-ac.svg",
                           "ratings-heavy.svg", "jnd-J_d.svg", "tuning.svg", "report.html"}) {
    INFO(file);
    REQUIRE(std::filesystem::exists(dir / "report" / file));
    CHECK(read_file(dir / "report" / file) == read_file(dir / "analysis" / file));
  }
  CHECK_FALSE(std::filesystem::exists(dir / "report" / "analysis.json"));
  const std::string html = read_file(dir / "report" / "report.html");
  CHECK(html.find("Ratings of heavy") != std::string::npos);
  CHECK(html.find("Which felt stronger: J_d") != std::string::npos);
  CHECK(html.find("Tuned doors, perceptual steps") != std::string::npos);
  // The SVG check (tests/support/check_svg.py): XML, legends keyed in their series' colours.
  const doorbench::testing::SvgCheck svgs =
      doorbench::testing::check_svgs({dir / "analysis", dir / "report"});
  INFO(svgs.output);
  CHECK(svgs.status == 0);
  CHECK(svgs.svgs == 24);  // 6 files and 6 inline in each folder
}

TEST_CASE("is_analysis_plot_file knows the names analysis_plots gives, and no others",
          "[study][campaign]") {
  using doorbench::study::is_analysis_plot_file;
  for (const char* name : {"preference-scale.svg", "identify-real.svg", "two-ac.svg", "tuning.svg",
                           "ratings-heavy.svg", "ratings-heavy_light.svg", "jnd-J_d.svg"}) {
    INFO(name);
    CHECK(is_analysis_plot_file(name));
  }
  for (const char* name : {"report.html", "report.pdf", "notes.svg", "ratings-.txt", "jnd-J d.svg",
                           "tuning.svg.bak", "global-search.svg"}) {
    INFO(name);
    CHECK_FALSE(is_analysis_plot_file(name));
  }
}

TEST_CASE("the plots redrawn from analysis.json equal the ones the sections draw from the fits",
          "[study][campaign]") {
  TempDir dir("campaign_report_same");
  write_campaign(dir);
  const auto table = doorbench::study::read_trials_table(dir / "campaign" / "trials.csv");
  doorbench::study::AnalysisOptions options;
  options.preference.bootstrap_replicates = 0;
  std::vector<doorbench::study::AnalysisPlot> from_fits;
  const json analysis = doorbench::study::analyze_trials(table, options, {}, &from_fits);
  // Through the text analysis.json holds.
  const auto from_json = doorbench::study::analysis_plots(json::parse(analysis.dump(2)));
  std::map<std::string, std::string> redrawn;
  for (const auto& plot : from_json) redrawn[plot.file] = plot.svg;
  REQUIRE(from_fits.size() == 2);  // jnd-J_d.svg and tuning.svg
  for (const auto& plot : from_fits) {
    INFO(plot.file);
    REQUIRE(redrawn.count(plot.file) == 1);
    CHECK(redrawn[plot.file] == plot.svg);
  }
  // The data behind the psychometric curve: the pooled answers per level, counted here.
  std::map<std::string, std::pair<int, int>> counted;  // comparison -> trials, stronger
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (table.value(r, "question") != "stronger:J_d") continue;
    const bool comparison_first = table.value(r, "first") != "J_d*1.00";
    const std::string comparison = table.value(r, comparison_first ? "first" : "second");
    ++counted[comparison].first;
    if (table.value(r, "answer") == (comparison_first ? "1" : "2")) ++counted[comparison].second;
  }
  const json& levels = analysis.at("jnd_levels");
  REQUIRE(levels.size() == 1);
  CHECK(levels[0].at("parameter") == "J_d");
  CHECK(levels[0].at("shape") == "cumulative normal");
  REQUIRE(levels[0].at("counts").size() == counted.size());
  for (const json& level : levels[0].at("counts")) {
    const double ratio = level.at("ratio").get<double>();
    char name[32];
    std::snprintf(name, sizeof name, "J_d*%.2f", ratio);
    INFO(name);
    REQUIRE(counted.count(name) == 1);
    CHECK(level.at("trials") == counted[name].first);
    CHECK(level.at("stronger") == counted[name].second);
    CHECK(level.at("log_ratio").get<double>() == Approx(std::log(ratio)));
  }
}

TEST_CASE("campaign report's errors word for word", "[study][campaign]") {
  TempDir dir("campaign_report_errors");
  const std::string missing = (dir / "nothing").string();
  auto run =
      run_verb("campaign report '" + missing + "' --out '" + (dir / "r").string() + "'", dir);
  CHECK(run.status == 2);
  CHECK(run.err == "doorbench: " + missing +
                       ": no such folder (give a `doorbench campaign analyze` output folder) (see "
                       "doorbench campaign report --help)\n");
  std::filesystem::create_directories(dir / "empty");
  run = run_verb(
      "campaign report '" + (dir / "empty").string() + "' --out '" + (dir / "r").string() + "'",
      dir);
  CHECK(run.status == 2);
  CHECK(run.err == "doorbench: " + (dir / "empty" / "analysis.json").string() +
                       ": no such file (give a `doorbench campaign analyze` output folder) (see "
                       "doorbench campaign report --help)\n");
  dir.write("other/analysis.json", "{\"preference_scale\": []}");
  run = run_verb(
      "campaign report '" + (dir / "other").string() + "' --out '" + (dir / "r").string() + "'",
      dir);
  CHECK(run.status == 1);
  CHECK(run.err == "doorbench: " + (dir / "other" / "analysis.json").string() +
                       ": not a campaign analysis (no input object; written by `doorbench "
                       "campaign analyze`?)\n");
  CHECK_FALSE(std::filesystem::exists(dir / "r"));
  // The output rule: not into the analysis folder (it holds the input), not over a report.
  write_campaign(dir);
  REQUIRE(run_verb("campaign analyze '" + (dir / "campaign").string() + "' --no-pdf --out '" +
                       (dir / "analysis").string() + "'",
                   dir)
              .status == 0);
  run = run_verb("campaign report '" + (dir / "analysis").string() + "' --no-pdf --out '" +
                     (dir / "analysis").string() + "' --overwrite",
                 dir);
  CHECK(run.err == "doorbench: " + (dir / "analysis").string() +
                       ": holds an input of this command (" +
                       (dir / "analysis" / "analysis.json").string() +
                       ") (doorbench never writes onto its input)\n");
  dir.write("r/report.html", "an earlier report");
  run = run_verb("campaign report '" + (dir / "analysis").string() + "' --no-pdf --out '" +
                     (dir / "r").string() + "'",
                 dir);
  CHECK(run.err == "doorbench: " + (dir / "r").string() +
                       ": exists and is not empty (give --overwrite to write into it)\n");
  CHECK(read_file(dir / "r" / "report.html") == "an earlier report");
  run = run_verb("campaign report '" + (dir / "analysis").string() + "' --no-pdf --out '" +
                     (dir / "r").string() + "' --overwrite",
                 dir);
  CHECK(run.status == 0);
  CHECK(read_file(dir / "r" / "report.html") == read_file(dir / "analysis" / "report.html"));
}
