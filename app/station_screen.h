#pragma once
// The participant's station (station/) as the study's participant screen
// (study/participant_screen.h), and the station's options, spelled alike on `play`, `ab` and
// `campaign run`: --station, --station-display NAME|INDEX, --scene FILE, --no-sound,
// --station-fps HZ, --station-nice N.
// study/ may not use station/ (docs/architecture.md), so app/ joins them here.
//
// Thread safety: one control thread (the run's); the station draws on its own thread.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "station/station_session.h"
#include "study/campaign_file.h"
#include "study/participant_screen.h"

namespace doorbench::app {

struct StationCommandOptions {
  bool station = false;
  std::string display;  // --station-display
  std::string scene;    // --scene
  bool no_sound = false;
  double fps = 0.0;  // --station-fps (0: the display's rate)
  int nice = 0;      // --station-nice
  station::StationRequest request() const;
};

// Adds --station, --station-display, --scene, --no-sound, --station-fps and --station-nice
// to `verb` (all but the first need --station).
void add_station_options(CLI::App& verb, StationCommandOptions& options);

class StationScreen : public study::ParticipantScreen {
 public:
  // Reads the scene and its sounds, and the other scenes and sound sets the request names
  // (a campaign's variants'; throws SceneError naming the file and key), and opens the
  // window (throws std::runtime_error: no display, no such display), before any trial.
  explicit StationScreen(const station::StationRequest& request);
  ~StationScreen() override;

  // Stages the presentation in its scene and sound set (the station's own when it names
  // none) and says what is shown and played: the names the presentation gives them, the
  // station's own "built-in" or --scene file as given, "none" for sounds not playing.
  study::Presented begin_presentation(const study::ScreenPresentation& shown,
                                      const haptic::DoorSnapshotChannel* door) override;
  void end_presentation() override;
  void ask(const study::ScreenQuestion& question) override;
  std::optional<std::size_t> take_choice() override;
  void script_choice(std::size_t choice, bool by_click) override;
  std::string take_typed() override;
  std::string fault() const override;

  // Closes the window and the sound; their two report lines (frames, sounds).
  std::string close();

 private:
  station::StationSession session_;
  std::string own_;  // the station's own scene and sounds, as trials.csv names them
};

// The request of `options` with the scenes and sound sets of `campaign`'s variants.
station::StationRequest campaign_station_request(const StationCommandOptions& options,
                                                 const study::Campaign& campaign);

}  // namespace doorbench::app
