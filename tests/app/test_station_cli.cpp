// `doorbench play --station` as a participant's lab runs it: under Xvfb the station's window
// opens beside a real-time play, draws frames, plays the latch's clicks into OpenAL Soft's
// wave-file output and says so in the summary; a bad scene file,
// a display that is not there or a station option without --station stop it with a message
// naming the cause, before the device moves.
#include <catch2/catch.hpp>
#include <fstream>
#include <regex>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

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

TEST_CASE("play --station draws the door and sounds it beside a real-time play under Xvfb",
          "[station][xvfb]") {
  testing::TempDir dir("station_cli");
  const auto session = dir.path / "played.h5";
  // OpenAL Soft's wave-file output stands in for a sound card.
  const auto wav = dir.path / "output.wav";
  std::ofstream(dir.path / "alsoft.conf")
      << "[general]\ndrivers = wave\n\n[wave]\nfile = " << wav.string() << "\n";
  const testing::DoorbenchRun run = testing::run_doorbench_shell(
      "play --device sim --hand-cycle-s 3 --station --duration-s 3.5 --out '" + session.string() +
          "'",
      dir,
      kUnderXvfb + " env ALSOFT_CONF='" + (dir.path / "alsoft.conf").string() +
          "' ALSOFT_DRIVERS=wave");
  INFO("stderr: " << run.err);
  REQUIRE(run.status == 0);
  std::smatch match;
  REQUIRE(std::regex_search(run.out, match, std::regex("station: ([0-9]+) frames")));
  CHECK(std::stoi(match[1]) >= 10);
  CHECK(std::filesystem::exists(session));
  // The virtual user opened and closed the door: the latch clicked on the way.
  REQUIRE(std::regex_search(run.out, match,
                            std::regex("sound: Wave File Writer, ([0-9]+) latch clicks")));
  CHECK(std::stoi(match[1]) >= 2);
  CHECK(std::filesystem::file_size(wav) > 48000);
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
  std::ofstream(dir.path / "noise.wav") << "not a sound";
  std::ofstream(dir.path / "sounds.toml") << "[sound]\nlatch_wav = \"noise.wav\"\n";
  run = testing::run_doorbench_shell(
      play + "--station --scene '" + (dir.path / "sounds.toml").string() + "'", dir, kUnderXvfb);
  CHECK(run.status == 1);
  CHECK_THAT(last_line(run.err),
             Catch::Matchers::StartsWith("doorbench: " + (dir.path / "noise.wav").string() +
                                         ": cannot read the sound: "));
}
