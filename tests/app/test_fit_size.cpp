// The fit's size said before it starts, and --max-windows (docs/fitting.md, "The fit's
// size"): the count on stderr and in
// report.md is the window fit's own (result.json's "windows"), and beyond --max-windows whole
// pairs of strokes spread over the recording are fitted, said word for word.
#include <catch2/catch.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

namespace {

using doorbench::testing::DoorbenchRun;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The stderr line that starts with "the window fit: ".
std::string size_line(const std::string& err) {
  const std::size_t at = err.find("\nthe window fit: ");
  if (at == std::string::npos) return "";
  return err.substr(at + 1, err.find('\n', at + 1) - at - 1);
}

}  // namespace

TEST_CASE(
    "fit says its windows before it starts, and --max-windows fits strokes spread over "
    "the recording",
    "[cli][fit]") {
  const TempDir dir("fit_size");
  const auto session = dir / "s.h5";
  REQUIRE(doorbench::testing::record_built_in_session(session, 40.0, 3, "sensory") == 40000);
  const auto fit = [&](const std::string& name, const std::string& options) {
    const auto out = dir / name;
    const DoorbenchRun run = run_doorbench_shell(
        "fit '" + session.string() + "' --folds 0 " + options + " --out '" + out.string() + "'",
        dir);
    INFO(run.err);
    REQUIRE(run.status == 0);
    const nlohmann::json result = nlohmann::json::parse(read_text(out / "result.json"));
    return std::make_tuple(size_line(run.err), result.at("windows").get<int>(),
                           result.at("strokes").get<int>(), read_text(out / "report.md"));
  };

  const auto [line, windows, strokes, report] = fit("all", "");
  REQUIRE(strokes >= 4);
  CHECK(line == "the window fit: " + std::to_string(windows) + " windows of 0.2 s on " +
                    std::to_string(strokes) + " strokes");
  CHECK_THAT(report, Catch::Contains("\n\n" + line + ".\n\n"));
  // report.md reads outcome first: the result, then the data and set-up (the size line among
  // them), the full report, the plots.
  CHECK_THAT(report, Catch::StartsWith("# Fit of the sensory model to " + session.string() +
                                       "\n\n## Result\n\nFit of the sensory model ("));
  const std::size_t result_at = report.find("\n## Result\n");
  const std::size_t rmse_at = report.find("\n\nWindow RMSE of omega ");
  const std::size_t data_at = report.find("\n## The data and the fit's set-up\n");
  const std::size_t size_at = report.find("\n" + line + ".\n");
  const std::size_t full_at = report.find("\n## In full\n\n```\ndoorbench fit report\n");
  const std::size_t plots_at = report.find("\n## Plots\n\n![");
  CHECK(result_at < rmse_at);
  CHECK(rmse_at < data_at);
  CHECK(data_at < size_at);
  CHECK(size_at < full_at);
  CHECK(full_at < plots_at);
  CHECK(plots_at != std::string::npos);

  // One window fewer than all: whole pairs of strokes, fewer windows than the limit.
  const int limit = windows - 1;
  const auto [cut_line, cut_windows, cut_strokes, cut_report] =
      fit("cut", "--max-windows " + std::to_string(limit));
  CHECK(cut_windows <= limit);
  CHECK(cut_strokes % 2 == 0);
  CHECK(cut_strokes < strokes);
  CHECK(cut_line == "the window fit: " + std::to_string(cut_windows) + " windows of 0.2 s on " +
                        std::to_string(cut_strokes) + " of the " + std::to_string(strokes) +
                        " strokes, spread evenly over the recording (all " +
                        std::to_string(windows) + " windows would exceed --max-windows " +
                        std::to_string(limit) + ")");
  CHECK_THAT(cut_report, Catch::Contains("\n\n" + cut_line + ".\n\n"));

  // Fewer than one pair's windows: one pair, said so.
  const auto [least_line, least_windows, least_strokes, least_report] =
      fit("least", "--max-windows 1");
  CHECK(least_strokes == 2);
  CHECK(least_line == "the window fit: " + std::to_string(least_windows) +
                          " windows of 0.2 s on 2 of the " + std::to_string(strokes) +
                          " strokes, spread evenly over the recording (all " +
                          std::to_string(windows) +
                          " windows would exceed --max-windows 1; one pair of strokes is the "
                          "least the fit takes)");
  // 0: every window.
  CHECK(std::get<1>(fit("zero", "--max-windows 0")) == windows);
}
