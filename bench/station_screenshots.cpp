// Not a timing: renders docs/station.md's pictures of the participant's station (run under
// Xvfb: xvfb-run -a build/bench/doorbench_station_screenshots docs/images): the built-in
// dishwasher at 0.45 rad, the same in side-by-side stereo, and a rating question over it.
#include <cstdio>
#include <filesystem>

#include "station/station_window.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: doorbench_station_screenshots OUT_DIR\n");
    return 2;
  }
  using namespace doorbench::station;
  const std::filesystem::path out = argv[1];
  StationWindowOptions options;
  options.width_px = 960;
  options.height_px = 600;
  Scene scene = default_scene();
  station_screenshot(scene, 0.45, out / "station-default.png", options);
  Question rating;
  rating.prompt = "How heavy did the door feel?";
  rating.choices = {"1", "2", "3", "4", "5", "6", "7"};
  rating.low_anchor = "very light";
  rating.high_anchor = "very heavy";
  station_screenshot(scene, 0.3, out / "station-question.png", options, &rating);
  scene.stereo.mode = StereoMode::kSideBySide;
  scene.stereo.screen_width_m = 1.2;
  scene.stereo.screen_height_m = 0.75;
  scene.stereo.screen_distance_m = 1.8;
  station_screenshot(scene, 0.45, out / "station-side-by-side.png", options);
  std::printf("wrote station-default.png, station-question.png, station-side-by-side.png in %s\n",
              out.string().c_str());
  return 0;
}
