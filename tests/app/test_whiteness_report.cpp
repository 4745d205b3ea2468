// The residual-whiteness line of the fit's and the loop's text reports
// (ResidualWhiteness::report_line): report.md states it under the full report. Their SVG
// plots are checked as XML with their legends on the way.
#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "analysis/model/parameter_file.h"
#include "app/fit_output.h"
#include "fixtures/temp_dir.h"
#include "fixtures/tremor_recording.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/svg_check.h"

namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("fit and loop reports state the residual's whiteness in a line", "[cli][whiteness]") {
  const doorbench::testing::TempDir dir("whiteness_report");
  const std::string csv = doorbench::testing::simulate_open_close_csv(dir, "run.csv", 8, 200);
  REQUIRE_FALSE(csv.empty());
  // 200 Hz: lags of 5 ms up to 0.5 s, 100 of them (201 for the cross-correlation).
  const std::string line =
      "residual whiteness: autocorrelation outside the 99 % band \\(±[0-9.e-]+\\) at [0-9]+ "
      "of 100 lags \\(largest \\|r\\| [0-9.e-]+ at lag [0-9.e-]+ s\\); cross-correlation with "
      "the force outside it at [0-9]+ of 201 lags \\(largest \\|r\\| [0-9.e-]+ at lag "
      "-?[0-9.e-]+ s\\); verdict: (white|not white)[^\n]*\\.\n";
  // report.md of `doorbench VERB` on the CSV.
  auto report_of = [&](const std::string& verb) {
    const auto run = doorbench::testing::run_doorbench_shell(
        verb + " -q '" + csv + "' --out '" + (dir / verb).string() + "'", dir);
    REQUIRE(run.status == 0);
    // Its plots, including the whiteness plot, are XML with their legends' keys drawn.
    const doorbench::testing::SvgCheck svgs = doorbench::testing::check_svgs({dir / verb});
    INFO(svgs.output);
    CHECK(svgs.status == 0);
    CHECK(svgs.svgs >= 5);
    CHECK(svgs.legend_entries >= 10);
    return read_file((dir / verb / "report.md").string());
  };
  SECTION("fit") {
    const std::string report = report_of("fit");
    INFO(report);
    CHECK(std::regex_search(report, std::regex("```\n\nThe fitted model's " + line)));
  }
  SECTION("loop") {
    const std::string report = report_of("loop");
    INFO(report);
    CHECK(std::regex_search(
        report, std::regex("```\n\nThe final model's " + line + "\nPlots of the final model:")));
  }
}

// Too few samples for the lags: no whiteness plot, and the report says why.
TEST_CASE("the fit's plots say the residual's whiteness was not computed on too short data",
          "[cli][whiteness]") {
  const doorbench::testing::TempDir dir("whiteness_short");
  const doorbench::DoorModel door = doorbench::reference_model(doorbench::ModelKind::kSensory);
  doorbench::PreparedData data = doorbench::testing::tremor_recording(door, {});
  data.strokes.resize(1);  // its first 200 samples: 0.2 s at 1 kHz
  doorbench::Stroke& stroke = data.strokes.front();
  for (std::vector<double>* channel :
       {&stroke.time_s, &stroke.force_N, &stroke.theta_rad, &stroke.omega_rad_s}) {
    channel->resize(200);
  }
  data.interval_median_s = stroke.time_s[1] - stroke.time_s[0];
  REQUIRE(data.interval_median_s == Approx(0.001));
  dir.write("residual-whiteness.svg", "<svg/>\n");  // an earlier run's, under --overwrite
  const doorbench::app::FitPlots plots =
      doorbench::app::write_fit_plots(dir.path, door, data, doorbench::FitOptions{});
  // 0.5 s of lags at 1 ms: 500, and at least twice as many samples.
  CHECK(plots.whiteness ==
        "residual whiteness: not computed (200 finite samples (not constant) needed at least "
        "1000)");
  CHECK(std::find(plots.files.begin(), plots.files.end(), "residual-whiteness.svg") ==
        plots.files.end());
  CHECK_FALSE(std::filesystem::exists(dir.path / "residual-whiteness.svg"));
  CHECK(std::filesystem::exists(dir.path / "rate.svg"));
}
