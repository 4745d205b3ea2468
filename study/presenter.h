#pragma once
// The one presenter of the people-testing verbs (`ab`, `campaign run`): it plays a trial's
// presentation on the haptic device through the render loop, or records the real door on the
// bench, into the session the call names. A tune trial's first presentation for a person is
// the tuning itself: the keys of study/tuning_keys.h move the playing door, live from a
// terminal or, from an answers file, the trial's line of keys pressed one per 0.1 s.
//
// With a participant's screen (show_on) the presentations are shown on it too
// (study/participant_screen.h), and a person tunes with its keys.
//
// It holds the rules the verbs share: which devices there are, simulated against real time,
// the virtual user's seed and cycle, the sessions' notes, and the one line that says why a
// presentation stopped early ("the presentation stopped after 0.42 s: CAUSE"). The playing
// and the recording themselves are the caller's (PlayOnDevice, RecordRealDoor: the render
// loop on an opened device, the rig's recorder), so study/ depends on haptic/ only for the
// playback's summary and its live parameter changes.
//
// Thread safety: a presenter is called from one thread at a time (the run's).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>

#include "analysis/model/door_model.h"
#include "haptic/playback.h"
#include "study/campaign_run.h"
#include "study/participant_screen.h"

namespace doorbench::study {

struct PresenterOptions {
  std::string device = "sim";    // sim | sim:rotary | hapticmaster://HOST[:PORT]
  bool real_time = false;        // a simulated device played in real time
  double presentation_s = 10.0;  // each presentation's length, unless the call gives its own
  std::string operator_name = "doorbench";  // the sessions' operator ("doorbench ab")

  // "" when usable, else one line naming the option: "--device must be sim, sim:rotary or
  // hapticmaster://HOST[:PORT], not X", "--real-time is for a simulated device ...",
  // "--presentation-s must be above 0 and at most 600".
  std::string validate() const;
  bool simulated() const;       // a simulated device (sim, sim:rotary)
  bool simulated_time() const;  // simulated and not --real-time
};

// What the presenter asks the device to play.
struct PlaySettings {
  std::string device;  // PresenterOptions::device
  bool simulated_time = true;
  double duration_s = 0.0;
  double hand_cycle_s = 0.0;  // the simulated virtual user's open-close cycle
  std::uint64_t seed = 0;     // the simulated virtual user's
  std::filesystem::path session_path;
  std::string model_source;  // for the session: where the model came from
  std::string operator_name;
  std::string notes;
  // Live tuning: called about every 0.1 s of the playback on the control thread; it may call
  // playback.change_parameters(). Returning false ends the presentation. Empty: none.
  std::function<bool(haptic::Playback&)> control;
  // Called once the playback exists, before its first tick, with the render loop's door
  // snapshot (the participant's screen follows it), and `on_end` once it is over, before the
  // playback goes, on every path. Empty: none.
  std::function<void(const haptic::DoorSnapshotChannel&)> on_start;
  std::function<void()> on_end;
};
// Plays `model` as `settings` say and returns the playback's summary (whose stop_cause is
// empty when the presentation ran its whole length). Throws on a device or session fault.
using PlayOnDevice =
    std::function<haptic::PlaybackSummary(const DoorModel& model, const PlaySettings& settings)>;

struct RealDoorSettings {
  double duration_s = 0.0;
  std::filesystem::path session_path;
  std::string operator_name;
  std::string notes;
};
// Records the real door on the bench for `settings.duration_s`. Throws on a fault.
using RecordRealDoor = std::function<void(const RealDoorSettings& settings)>;

class DevicePresenter {
 public:
  // Throws std::invalid_argument with options.validate()'s text. `record_real` may be empty
  // when no stimulus is the real door. Operator messages (a tuning's keys) go to `screen`.
  DevicePresenter(PresenterOptions options, PlayOnDevice play, RecordRealDoor record_real,
                  std::ostream& screen);

  // Plays or records `call`'s presentation (the Presenter contract of study/campaign_run.h).
  // Throws std::runtime_error "the presentation stopped after X s: CAUSE" when it ended
  // early, "the tuning stopped after ..." for a tuning, and what the device or the
  // recording threw.
  void present(const PresentationCall& call) const;
  // This presenter as a study::Presenter (it must outlive the function).
  Presenter as_presenter() const;

  const PresenterOptions& options() const { return options_; }
  // The participant's screen (null: none): each presentation is shown on it as "Presentation
  // LABEL" with the door played, a tuning as "Tune the door" with the keys' actions, and a
  // person's tuning keys are taken from it instead of the terminal. It must outlive the
  // presenter's calls.
  void show_on(ParticipantScreen* screen) { participant_screen_ = screen; }

 private:
  DoorModel tune_at_the_device(PlaySettings play, const DoorModel& start,
                               const PresentationCall& call) const;

  PresenterOptions options_;
  PlayOnDevice play_;
  RecordRealDoor record_real_;
  std::ostream* screen_;
  ParticipantScreen* participant_screen_ = nullptr;
};

}  // namespace doorbench::study
