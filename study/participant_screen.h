#pragma once
// What the participant faces while the people-testing verbs run (`ab`, `campaign run` with
// --station): a screen that shows the door being played and, after each trial, asks the
// trial's question in words and takes the answer the participant gives on it. study/ words
// the questions and waits for the answers; the screen itself (the station's window,
// station/) is supplied by the caller through ParticipantScreen: study/ may use
// acquisition, analysis and haptic only (docs/architecture.md), and app/ joins the two.
//
// Blind by construction: a screen is told only the words to show (a presentation's label,
// a question, its choices and anchors, the tuning keys' actions), the door's angle through
// the playback's snapshot and, when the variant names them, the scene and the sound set to
// stage it in (files, never shown as words), never a Stimulus, a variant's name or its
// parameters.
//
// Thread safety: a ParticipantScreen is called from the run's one thread; an implementation
// hands the requests to its own drawing thread.
#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "haptic/door_snapshot.h"
#include "study/campaign_run.h"
#include "study/question.h"

namespace doorbench::study {

// One question as the screen shows it: its words, the choices (at most 9: the keys 1 to 9
// pick them), a rating scale's words at its ends, and what each choice answers (as
// parse_answer reads a typed answer).
struct ScreenQuestion {
  std::string prompt;                   // "Which felt heavier?"
  std::vector<std::string> choices;     // the buttons' words: "1", "2", "no difference"
  std::vector<std::string> answers;     // per choice: "1", "2", "same"; a rating's "5"
  std::string low_anchor, high_anchor;  // a rating scale's ends ("light", "heavy"), or empty
};

// The screens that ask `question` (one for a choice between the two presentations; two for a
// rating, the first presentation's then the second's), presentations called by `labels`.
// Throws std::invalid_argument for a tune question (it is tuned, not asked) and for a rating
// scale above 9 points ("the station asks ratings of 2 to 9 points (keys 1 to 9); this one
// has 12").
std::vector<ScreenQuestion> screen_questions(const Question& question,
                                             const AnswerLabels& labels = {"1", "2"});

// "" when the screen can ask every question of `rows`, else why not (the first row's
// question it cannot ask: "trial 4 asks rating:pleasant:12: the station asks ratings of 2
// to 9 points ..."), for refusing a run before the device moves.
std::string screen_problem(const std::vector<PlanRow>& rows);

// What the screen shows during a presentation.
struct ScreenPresentation {
  std::string caption;                // "Presentation 1", "Tune the door"
  std::vector<std::string> key_help;  // a tuning's keys and what each does: "+  heavier"
  Staging staging;  // the variant's scene and sound set (Stimulus::staging); none: the screen's own
};

// The presentation of `stimulus` called `caption`: its scene and sound set with it.
ScreenPresentation screen_presentation(std::string caption, const Stimulus& stimulus);

// What a tune trial's first presentation shows: "Tune the door with the keys, then press
// Enter" and each tuning key with what it does ("+   heavier", ..., "r   back to the start").
ScreenPresentation tuning_screen();

class ParticipantScreen {
 public:
  virtual ~ParticipantScreen() = default;
  // A presentation starts: show `shown` in its scene (or the screen's own), the door at the
  // angle `door` publishes, with its sounds (null for the real door on the bench: the
  // screen's door rests closed, silent). `door` must outlive the end_presentation() call
  // that follows. Returns what is shown and played, as trials.csv spells it (Presented).
  virtual Presented begin_presentation(const ScreenPresentation& shown,
                                       const haptic::DoorSnapshotChannel* door) = 0;
  // The presentation is over: stop reading its door (the door rests closed, in the screen's
  // own scene).
  virtual void end_presentation() = 0;
  // Shows `question` from now on (replacing any); take_choice() gives its answer.
  virtual void ask(const ScreenQuestion& question) = 0;
  // The index of the choice the participant picked since ask(), if any (the question is
  // then gone).
  virtual std::optional<std::size_t> take_choice() = 0;
  // Scripted input, as the participant's would come (a key or a click on the choice's
  // button): picks `choice` of the question asked. `by_click` picks by clicking.
  virtual void script_choice(std::size_t choice, bool by_click) = 0;
  // The characters the participant typed since the last call ('\n' for Enter).
  virtual std::string take_typed() = 0;
  // "" while the screen works; else why it cannot ask any more (its window was closed, its
  // thread stopped), for the run's error.
  virtual std::string fault() const = 0;
};

// Asks `question` on `screen` and waits for the participant's answer(s); returns the answer
// as a typed one would be spelled ("1", "same", "5 3"), for parse_answer. With
// `scripted_text` (an answer from a script or a simulated participant) the answer is
// given through the screen's scripted input (keys, or for a rating's second presentation a
// click) and what the screen reports picked is returned. Throws std::runtime_error with the
// screen's fault, std::invalid_argument for a scripted text that does not answer `question`.
std::string ask_on_screen(ParticipantScreen& screen, const Question& question,
                          const AnswerLabels& labels = {"1", "2"},
                          const std::optional<std::string>& scripted_text = std::nullopt);

// A respondent who answers on the participant's screen. Alone (`scripted` null) it is a
// person at the station: answers picked on the screen, a tune trial tuned with the screen's
// keys (the presenter's, with PresentationCall::respondent). With `scripted` (a simulated
// participant, an answers file) each answer `scripted` gives is pressed on the screen as the
// participant would press it and the screen's answer is the one kept; `scripted` tunes as it
// does alone. The operator's stream gets progress only ("trial 3: asked on the station,
// 42 s into the run"), never the question.
class ScreenRespondent : public Respondent {
 public:
  ScreenRespondent(ParticipantScreen& screen, Respondent* scripted = nullptr);
  std::string answer(const PlanRow& row, const Stimulus& first, const Stimulus& second,
                     std::ostream& prompts) override;
  DoorModel tune(const PlanRow& row, const DoorModel& start, std::ostream& prompts) override;
  bool tunes_at_the_device() const override;
  std::optional<std::string> scripted_tuning_keys(int trial, std::string& where) override;
  void set_attempt(int attempt) override;

 private:
  ParticipantScreen* screen_;
  Respondent* scripted_;
  std::chrono::steady_clock::time_point started_;
};

}  // namespace doorbench::study
