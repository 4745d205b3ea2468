// The start values' line and the tables agree: on the physical reference door
// fitted with the sensory model, no opening stroke unlatches from closed, so only the
// closing side of the latch is read; the start from the data scales theta0 and theta1 to it
// as the fit does, and the line says so instead of "the latch read off the data was not
// used" beside a table that marks the latch "read off the data". The report's status column
// reads "start scaled to the latch read off" (it read "start start scaled ...").
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The line of `text` that starts with `start` ("" when none).
std::string line_starting(const std::string& text, const std::string& start) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(start, 0) == 0) return line;
  }
  return "";
}

}  // namespace

TEST_CASE("the start values' line and the tables say the same of the latch", "[cli][fit]") {
  using doorbench::testing::run_doorbench_shell;
  const doorbench::testing::TempDir dir("start_line");
  const std::string run = (dir / "run.csv").string();
  REQUIRE(run_doorbench_shell(
              "simulate --model physical --hand open-close --duration-s 6 --out '" + run + "'", dir)
              .status == 0);
  const auto init = run_doorbench_shell(
      "fit '" + run + "' --model sensory --init-only --out '" + (dir / "init").string() + "'", dir);
  INFO(init.err);
  REQUIRE(init.status == 0);
  const std::string md = read_text(dir / "init" / "start.md");
  const std::string line = line_starting(md, "start values from the data: ");
  INFO(line);
  const std::string latch_part =
      "k_lock, theta2, theta3 read off the force-angle curves near closed; theta0, theta1 "
      "scaled to the latch read off; the others the reference door's; no opening stroke "
      "unlatches from closed: theta0, theta1, k_inf not read.";
  REQUIRE(line.size() > latch_part.size());
  CHECK(line.substr(line.size() - latch_part.size()) == latch_part);
  CHECK(line.find("not used") == std::string::npos);
  // The table: the same parameters, the same words.
  for (const char* name : {"k_lock", "theta2", "theta3"}) {
    const std::string row = line_starting(md, std::string("| ") + name + " |");
    INFO(row);
    CHECK(row.substr(row.rfind(" | ") + 3) == "the data (latch read-off) |");
  }
  for (const char* name : {"theta0", "theta1"}) {
    const std::string row = line_starting(md, std::string("| ") + name + " |");
    INFO(row);
    CHECK(row.substr(row.rfind(" | ") + 3) == "scaled to the latch read off |");
  }
  // The fit from the reference door's parameter file scales the same angles itself: its
  // report's status column says "start scaled to the latch read off", once.
  const auto fit = run_doorbench_shell(
      "fit '" + run + "' --model sensory --params '" + DOORBENCH_SOURCE_DIR +
          "/analysis/data/reference-door.json' --folds 0 --out '" + (dir / "fit").string() + "'",
      dir);
  INFO(fit.err);
  REQUIRE(fit.status == 0);
  const std::string report = read_text(dir / "fit" / "report.md");
  for (const char* name : {"theta0", "theta1"}) {
    const std::string row = line_starting(report, std::string("  ") + name + " ");
    INFO(row);
    CHECK_THAT(row, Catch::Matchers::EndsWith(", start scaled to the latch read off"));
  }
  CHECK(report.find("start start") == std::string::npos);
  CHECK(report.find("the latch read off the data was not used") == std::string::npos);
}
