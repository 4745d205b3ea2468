// The residual-whiteness line of the fit's and the loop's text reports (issue 21, item 9;
// ResidualWhiteness::report_line): report.md states it under the full report.
#include <catch2/catch.hpp>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "tests/support/run_doorbench.h"
#include "tests/support/temp_dir.h"

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
