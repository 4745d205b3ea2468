// `doorbench play --station` as a participant's lab runs it: under Xvfb the station's window
// opens beside a real-time play, draws frames and says so in the summary; a bad scene file,
// a display that is not there or a station option without --station stop it with a message
// naming the cause, before the device moves.
#include <catch2/catch.hpp>
#include <fstream>
#include <regex>
#include <string>

#include "tests/support/run_doorbench.h"
#include "tests/support/temp_dir.h"

using namespace doorbench;

namespace {

const std::string kUnderXvfb = "xvfb-run -a -s '-screen 0 1600x1200x24 -noreset'";

// The message doorbench ended with: its stderr's last line (after the "playing ..." line).
std::string last_line(const std::string& err) {
  const std::size_t end = err.find_last_not_of('\n');
  if (end == std::string::npos) return "";
  const std::size_t begin = err.rfind('\n', end);
  return err.substr(begin == std::string::npos ? 0 : begin + 1,
                    end + 1 - (begin == std::string::npos ? 0 : begin + 1));
}

}  // namespace

TEST_CASE("play --station draws the door beside a real-time play under Xvfb", "[station][xvfb]") {
  testing::TempDir dir("station_cli");
  const auto session = dir.path / "played.h5";
  const testing::DoorbenchRun run = testing::run_doorbench_shell(
      "play --device sim --station --duration-s 1.5 --no-fifo --out '" + session.string() + "'",
      dir, kUnderXvfb);
  INFO("stderr: " << run.err);
  REQUIRE(run.status == 0);
  std::smatch match;
  REQUIRE(std::regex_search(run.out, match, std::regex("station: ([0-9]+) frames")));
  CHECK(std::stoi(match[1]) >= 10);
  CHECK(std::filesystem::exists(session));
}

TEST_CASE("play --station: a scene file, a display or an option that cannot be used is named",
          "[station][xvfb]") {
  testing::TempDir dir("station_cli_errors");
  const auto session = dir.path / "played.h5";
  const std::string play =
      "play --device sim --simulated-time --duration-s 1 --out '" + session.string() + "' ";
  std::ofstream(dir.path / "scene.toml") << "[camera]\nvertical_fov_deg = 400\n";
  testing::DoorbenchRun run = testing::run_doorbench_shell(
      play + "--station --scene '" + (dir.path / "scene.toml").string() + "'", dir, kUnderXvfb);
  CHECK(run.status == 1);
  CHECK(last_line(run.err) == "doorbench: " + (dir.path / "scene.toml").string() +
                                  ":2: camera.vertical_fov_deg: must be in [5, 150] (got 400)");

  run = testing::run_doorbench_shell(play + "--station --station-display 7", dir, kUnderXvfb);
  CHECK(run.status == 1);
  CHECK_THAT(last_line(run.err),
             Catch::Matchers::StartsWith(
                 "doorbench: --station-display '7': no such display (displays: 0 'screen' "));
  CHECK_FALSE(std::filesystem::exists(session));  // nothing half-written is left

  run = testing::run_doorbench_shell(play + "--station", dir, "env -u DISPLAY");
  CHECK(run.status == 1);
  CHECK_THAT(last_line(run.err),
             Catch::Matchers::StartsWith("doorbench: station: cannot start GLFW: "));

  run = testing::run_doorbench_shell(play + "--scene scene.toml", dir);
  CHECK(run.status == 2);
  CHECK_THAT(run.err, Catch::Matchers::StartsWith("doorbench: --scene requires --station"));
}
