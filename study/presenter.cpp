#include "study/presenter.h"

#include <unistd.h>

#include <algorithm>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <utility>

#include "core/number_format.h"
#include "study/tuning_keys.h"

namespace doorbench::study {
namespace {

// The virtual user's open-close cycle for a presentation: its length, between 4 s (faster
// would be a slam the velocity trip stops) and 10 s.
double hand_cycle_s(double presentation_s) {
  return std::clamp(presentation_s, 4.0, 10.0);
}

std::string key_text(char key) {
  return std::string("key ").append(1, key);
}

bool is_tuning_key(char key) {
  if (key == kResetKey) return true;
  return std::any_of(tuning_keys().begin(), tuning_keys().end(),
                     [key](const TuningKey& tuning) { return tuning.key == key; });
}

// A person's tuning during a tune trial's first presentation (docs/campaign.md, "A person's
// tune trial"): each press is applied with apply_key to the door being played and handed to
// the loop with Playback::change_parameters (on the control thread: the new set is checked,
// recorded and taken by the tick through the mailbox; the tick never waits, allocates or does
// I/O for it); a press the model or the playback refuses leaves the door as it was. Every
// press is a "tuning" event of the session. The operator sees the key and its outcome, never
// a value.
class PresentationTuning {
 public:
  PresentationTuning(const DoorModel& start, std::ostream& screen)
      : start_(start), current_(start), screen_(&screen) {}

  void press(haptic::Playback& playback, char key) {
    const double time_s = playback.loop().status().time_s;
    std::string outcome, brief = "refused";
    const KeyOutcome result =
        key == kResetKey ? KeyOutcome{start_, "reset", "", "", 0.0, 0.0, "back to the start"}
                         : apply_key(current_, key);
    if (result.model) {
      const std::string problem =
          playback.change_parameters(*result.model, key_text(key) + ": " + result.action);
      if (problem.empty()) {
        current_ = *result.model;
        outcome = "played (" + result.action + ")";
        brief = "played";
      } else {
        outcome = "not played: " + problem;
        brief = "not played (the playback refused it)";
      }
    } else {
      outcome = "refused: " + result.message;
    }
    playback.recorder().add_event(
        {.time_s = time_s,
         .kind = "tuning",
         .channel = "",
         .detail = key_text(key) + ": " + result.message + " (" + outcome + ")"});
    *screen_ << key_text(key) << ": " << brief << "\n";
  }
  const DoorModel& current() const { return current_; }

 private:
  DoorModel start_, current_;
  std::ostream* screen_;
};

// The participant's screen during one presentation: begin() shows it, the destructor ends
// it (on every path); follow() makes a playback's start and end do the same.
class ScreenShowing {
 public:
  explicit ScreenShowing(ParticipantScreen* screen) : screen_(screen) {}
  ~ScreenShowing() { end(); }
  ScreenShowing(const ScreenShowing&) = delete;
  ScreenShowing& operator=(const ScreenShowing&) = delete;

  void begin(const ScreenPresentation& shown, const haptic::DoorSnapshotChannel* door) {
    if (screen_ == nullptr) return;
    presented_ = screen_->begin_presentation(shown, door);
    begun_ = true;
  }
  void end() {
    if (begun_) screen_->end_presentation();
    begun_ = false;
  }
  // `play`'s playback shows `shown` with its door while it runs (`this` must outlive it).
  void follow(PlaySettings& play, ScreenPresentation shown) {
    if (screen_ == nullptr) return;
    play.on_start = [this, shown](const haptic::DoorSnapshotChannel& door) { begin(shown, &door); };
    play.on_end = [this] { end(); };
  }
  // What the screen showed and played (nothing: "none", "none"), into `out` when given.
  void tell(Presented* out) const {
    if (out != nullptr) *out = presented_;
  }

 private:
  ParticipantScreen* screen_;
  bool begun_ = false;
  Presented presented_;
};

// The keys of a scripted tune trial's line (spaces ignored); throws naming `where` for any
// other character.
std::string keys_of(const std::string& line, const std::string& where, int trial) {
  std::string keys;
  for (char key : line) {
    if (key == ' ' || key == '\t') continue;
    if (!is_tuning_key(key)) {
      throw std::runtime_error(where + ": trial " + std::to_string(trial) +
                               ": a tune trial's line holds the keys pressed (+ - U u C c S s N n "
                               "r; empty: the start kept), not '" +
                               std::string(1, key) + "'");
    }
    keys.push_back(key);
  }
  return keys;
}

}  // namespace

bool PresenterOptions::simulated() const {
  return device.rfind("sim", 0) == 0;
}

bool PresenterOptions::simulated_time() const {
  return simulated() && !real_time;
}

std::string PresenterOptions::validate() const {
  if (!simulated() && device.rfind("hapticmaster://", 0) != 0) {
    return "--device must be sim, sim:rotary or hapticmaster://HOST[:PORT], not " + device;
  }
  if (real_time && !simulated()) {
    return "--real-time is for a simulated device (sim, sim:rotary); a HapticMaster always plays "
           "in real time";
  }
  if (!(presentation_s > 0.0 && presentation_s <= 600.0)) {
    return "--presentation-s must be above 0 and at most 600";
  }
  return "";
}

DevicePresenter::DevicePresenter(PresenterOptions options, PlayOnDevice play,
                                 RecordRealDoor record_real, std::ostream& screen)
    : options_(std::move(options)),
      play_(std::move(play)),
      record_real_(std::move(record_real)),
      screen_(&screen) {
  if (const std::string problem = options_.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  if (!play_) throw std::invalid_argument("a presenter needs a device to play on");
}

Presenter DevicePresenter::as_presenter() const {
  return [this](const PresentationCall& call) { present(call); };
}

void DevicePresenter::present(const PresentationCall& call) const {
  if (call.stimulus == nullptr) throw std::logic_error("a presentation without a stimulus");
  const double duration_s = call.duration_s > 0.0 ? call.duration_s : options_.presentation_s;
  const std::string notes =
      options_.operator_name + ": " +
      (call.participant.empty() ? "" : "participant " + call.participant + ", ") + "trial " +
      std::to_string(call.trial) + ", presentation " + std::to_string(call.position) +
      ", variant " + call.stimulus->name +
      (call.stimulus->source.empty() ? "" : " (" + call.stimulus->source + ")");
  const ScreenPresentation shown = screen_presentation(
      "Presentation " + (call.label.empty() ? std::to_string(call.position) : call.label),
      *call.stimulus);
  if (!call.stimulus->model) {
    if (!record_real_) throw std::logic_error("the real door without a rig to record it from");
    ScreenShowing showing(participant_screen_);
    showing.begin(shown, nullptr);
    showing.tell(call.presented);
    record_real_(
        {duration_s, call.session_path, options_.operator_name, notes + ", the real door"});
    return;
  }
  PlaySettings play;
  play.device = options_.device;
  play.simulated_time = options_.simulated_time();
  play.duration_s = duration_s;
  play.hand_cycle_s = hand_cycle_s(duration_s);
  play.seed = static_cast<std::uint64_t>(1000 * call.trial + call.position);
  play.session_path = call.session_path;
  play.model_source =
      call.stimulus->source.empty() ? "stimulus " + call.stimulus->name : call.stimulus->source;
  play.operator_name = options_.operator_name;
  play.notes = notes;
  if (call.tuned) {
    *call.tuned = tune_at_the_device(play, *call.stimulus->model, call);
    return;
  }
  ScreenShowing showing(participant_screen_);
  showing.follow(play, shown);
  const haptic::PlaybackSummary summary = play_(*call.stimulus->model, play);
  showing.tell(call.presented);
  if (!summary.stop_cause.empty()) {
    throw std::runtime_error("the presentation stopped after " +
                             format_significant(summary.duration_s, 3) +
                             " s: " + summary.stop_cause);
  }
}

// From a terminal: real time (also on the simulated device), until Enter, at most 600 s.
// From an answers file: the trial's line holds the keys (spaces ignored; empty: the start
// kept), pressed one per control call (every 0.1 s of the presentation, simulated time on
// the simulated device).
DoorModel DevicePresenter::tune_at_the_device(PlaySettings play, const DoorModel& start,
                                              const PresentationCall& call) const {
  if (call.respondent == nullptr) {
    throw std::logic_error("a tune trial at the device needs the respondent who tunes");
  }
  const std::string at_trial = "trial " + std::to_string(call.trial);
  auto tuning = std::make_shared<PresentationTuning>(start, *screen_);
  std::string where;
  const std::optional<std::string> line = call.respondent->scripted_tuning_keys(call.trial, where);
  std::string keys;
  std::size_t pressed = 0;
  ScreenShowing showing(participant_screen_);
  ScreenPresentation tuning_shown = tuning_screen();
  tuning_shown.staging = call.stimulus->staging;
  showing.follow(play, tuning_shown);
  if (!line && participant_screen_ != nullptr) {
    ParticipantScreen* screen = participant_screen_;
    screen->take_typed();  // what was typed before the tuning is not a tuning key
    *screen_ << at_trial << ": tuning on the station, Enter there when done\n";
    play.simulated_time = false;
    play.duration_s = 600.0;
    play.control = [screen, tuning](haptic::Playback& playback) {
      for (const char key : screen->take_typed()) {
        if (key == '\n') return false;  // the person ends the tuning
        tuning->press(playback, key);
      }
      return true;
    };
  } else if (!line) {
    auto terminal = std::make_shared<TerminalKeys>(STDIN_FILENO, "stdin");
    *screen_ << at_trial << ": tune with the keys, Enter when done\n" << key_map_text();
    play.simulated_time = false;
    play.duration_s = 600.0;
    play.control = [terminal, tuning](haptic::Playback& playback) {
      while (const std::optional<char> key = terminal->poll(0.0)) {
        if (*key == '\n' || *key == '\r') return false;  // the person ends the tuning
        tuning->press(playback, *key);
      }
      return true;
    };
  } else {
    keys = keys_of(*line, where, call.trial);
    *screen_ << at_trial << ": tuning with " << keys.size() << " keys from " << where << "\n";
    play.control = [tuning, &keys, &pressed](haptic::Playback& playback) {
      if (pressed < keys.size()) tuning->press(playback, keys[pressed++]);
      return true;
    };
  }
  const haptic::PlaybackSummary summary = play_(start, play);
  showing.tell(call.presented);
  if (!summary.stop_cause.empty()) {
    throw std::runtime_error("the tuning stopped after " +
                             format_significant(summary.duration_s, 3) +
                             " s: " + summary.stop_cause);
  }
  if (pressed < keys.size()) {
    throw std::runtime_error(at_trial + ": the presentation ended after " +
                             std::to_string(pressed) + " of the " + std::to_string(keys.size()) +
                             " keys (one is pressed every 0.1 s); give a longer --presentation-s");
  }
  return tuning->current();
}

}  // namespace doorbench::study
