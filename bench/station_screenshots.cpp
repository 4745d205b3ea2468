// Not a timing: renders docs/station.md's pictures of the participant's station (run under
// Xvfb: xvfb-run -a build/bench/doorbench_station_screenshots docs/images): the built-in
// dishwasher at 0.45 rad, the same in side-by-side stereo, and a trial as `ab` and
// `campaign run --station` show it: a presentation's caption, a rating question and a 2-AC
// preference in the study's words (study/participant_screen.h), and a tune trial's keys.
#include <cstdio>
#include <filesystem>

#include "station/station_window.h"
#include "study/participant_screen.h"

namespace {

doorbench::station::Question on_station(const doorbench::study::ScreenQuestion& asked) {
  return {asked.prompt, asked.choices, asked.low_anchor, asked.high_anchor, {}};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: doorbench_station_screenshots OUT_DIR\n");
    return 2;
  }
  using namespace doorbench::station;
  namespace study = doorbench::study;
  const std::filesystem::path out = argv[1];
  StationWindowOptions options;
  options.width_px = 960;
  options.height_px = 600;
  Scene scene = default_scene();
  station_screenshot(scene, 0.45, out / "station-default.png", options);
  const Question rating =
      on_station(study::screen_questions(*study::Question::parse("rating:heavy-light:7"))[0]);
  station_screenshot(scene, 0.0, out / "station-question.png", options, &rating);
  const Question preference =
      on_station(study::screen_questions(*study::Question::parse("preference-2ac"))[0]);
  station_screenshot(scene, 0.0, out / "station-preference.png", options, &preference);
  const study::ScreenPresentation tune = study::tuning_screen();
  station_screenshot(scene, 0.6, out / "station-tune.png", options, nullptr,
                     Caption{tune.caption, tune.key_help});
  station_screenshot(scene, 0.9, out / "station-presentation.png", options, nullptr,
                     Caption{"Presentation 1", {}});
  scene.stereo.mode = StereoMode::kSideBySide;
  scene.stereo.screen_width_m = 1.2;
  scene.stereo.screen_height_m = 0.75;
  scene.stereo.screen_distance_m = 1.8;
  station_screenshot(scene, 0.45, out / "station-side-by-side.png", options);
  std::printf(
      "wrote station-default.png, station-question.png, station-preference.png, "
      "station-tune.png, station-presentation.png, station-side-by-side.png in %s\n",
      out.string().c_str());
  return 0;
}
