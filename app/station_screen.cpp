#include "app/station_screen.h"

#include <stdexcept>

#include "app/number_options.h"

namespace doorbench::app {

station::StationRequest StationCommandOptions::request() const {
  station::StationRequest request;
  request.scene_file = scene;
  request.window.display = display;
  request.sound = !no_sound;
  request.window.max_frame_rate_hz = fps;
  request.window.nice = nice;
  return request;
}

void add_station_options(CLI::App& verb, StationCommandOptions& options) {
  CLI::Option* station = verb.add_flag(
      "--station", options.station,
      "Open the participant's station: the door drawn full screen at the played angle, with "
      "its sounds (docs/station.md)");
  verb.add_option("--station-display", options.display,
                  "The display the participant faces: its name or index (default: the primary)")
      ->needs(station);
  verb.add_flag("--no-sound", options.no_sound, "The station without its sounds")->needs(station);
  verb.add_option("--scene", options.scene,
                  "The station's scene file (TOML; default: the built-in dishwasher)")
      ->needs(station);
  verb.add_option("--station-fps", options.fps,
                  "Draw the station at most this often (Hz; default: the display's rate)")
      ->check(number_range(1.0, 1000.0))
      ->needs(station);
  verb.add_option("--station-nice", options.nice,
                  "The nice value the station draws at (0 to 19; above 0 it yields to other work)")
      ->check(number_range(0, 19))
      ->capture_default_str()
      ->needs(station);
}

station::StationRequest campaign_station_request(const StationCommandOptions& options,
                                                 const study::Campaign& campaign) {
  station::StationRequest request = options.request();
  for (const study::Variant& variant : campaign.variants) {
    if (!variant.scene_file.empty()) request.scenes.push_back(variant.scene_file);
    if (!variant.sounds_file.empty()) request.sound_sets.push_back(variant.sounds_file);
  }
  return request;
}

StationScreen::StationScreen(const station::StationRequest& request)
    : session_(request),
      own_(request.scene_file.empty() ? "built-in" : request.scene_file.string()) {
  session_.start();
}

StationScreen::~StationScreen() {
  session_.close();
}

study::Presented StationScreen::begin_presentation(const study::ScreenPresentation& shown,
                                                   const haptic::DoorSnapshotChannel* door) {
  const study::Staging& staging = shown.staging;
  session_.stage(staging.scene_file, staging.sounds_file);
  session_.station()->show({shown.caption, shown.key_help});
  if (door != nullptr) session_.follow(*door);
  study::Presented presented;
  presented.scene = staging.scene_file.empty() ? own_ : staging.scene;
  presented.sounds = !session_.sound_playing()      ? "none"
                     : !staging.sounds_file.empty() ? staging.sounds
                     : !staging.scene_file.empty()  ? staging.scene
                                                    : own_;
  return presented;
}

void StationScreen::end_presentation() {
  session_.unfollow();
  session_.station()->show({});
  session_.stage({}, {});
}

void StationScreen::ask(const study::ScreenQuestion& question) {
  session_.station()->ask(station::Question{
      question.prompt, question.choices, question.low_anchor, question.high_anchor, {}});
}

std::optional<std::size_t> StationScreen::take_choice() {
  const std::optional<station::Answer> answer = session_.station()->take_answer();
  if (!answer) return std::nullopt;
  return std::size_t(answer->choice);
}

void StationScreen::script_choice(std::size_t choice, bool by_click) {
  session_.station()->pick(choice, by_click);
}

std::string StationScreen::take_typed() {
  return session_.station()->take_typed();
}

std::string StationScreen::fault() const {
  const station::Station* live = session_.station();
  if (live == nullptr) return "the station is closed";
  if (live->running()) return "";
  const station::StationReport report = live->report();
  if (report.closed) return "the station's window was closed";
  return "the station stopped: " + report.error;
}

std::string StationScreen::close() {
  session_.close();
  return session_.brief_report();
}

}  // namespace doorbench::app
