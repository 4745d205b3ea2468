#pragma once
// Running one participant's schedule (docs/campaign.md, "Running", "Resume"): each trial's
// two presentations through a Presenter (the app plays them on the device and records each as
// a session), the answer from a Respondent (a person through the operator's keyboard or an
// answers file, or a simulated participant), and the row appended to DIR/trials.csv, written
// with one write(), flushed and fsync()ed before the next trial starts.
//
// Resume: the rows already in trials.csv for this participant (and attempt) are checked
// against the plan, in order, and the run continues at the next unanswered trial; a torn
// last line (a write cut by a crash) is cut off first. Sessions and tuned files of the
// unanswered trial left by the interrupted run are moved into sessions/P/interrupted/, never
// overwritten. A participant who has answered every trial is refused unless `redo`: then a
// new attempt (column `attempt`) starts from trial 1 and the earlier rows stay as they are.
// Two runs of one participant at once are refused (a lock file under DIR/locks/).
//
// The prompts (the operator's screen) name trial numbers and the labels 1 and 2 only, never
// a variant or a stimulus.
// Thread safety: one run per participant at a time (enforced across processes).
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "study/campaign_plan.h"
#include "study/participant_model.h"
#include "study/quest_plus.h"

namespace doorbench::study {

// What a presentation is seen and heard in beside the door felt: a variant's scene and sound
// set (Variant::scene, ::sounds as the campaign file spells them, and the files); empty: the
// station's own.
struct Staging {
  std::string scene, sounds;
  std::filesystem::path scene_file, sounds_file;
};

// What a presentation plays: a model, or the real door on the bench (model empty).
struct Stimulus {
  std::string name;  // a variant's name, "J*1.1", or a tune start's steps
  std::optional<DoorModel> model;
  std::string parameters;  // the rendered parameters, "J=1.045 k=0.12 ..." (empty: real door)
  std::string source;      // where the model came from, for the session (a parameter file)
  Staging staging;         // the variant's scene and sound set (none: the station's own)
};

// What a presentation showed and played beside the door felt, as trials.csv spells it
// (docs/campaign.md, "trials.csv"): the scene drawn and where the sounds came from (a
// variant's file as the campaign spells it, the station's --scene file as given, or
// "built-in"), or "none" when nothing was shown or heard (no station; --no-sound, no audio
// output or the real door for the sounds).
struct Presented {
  std::string scene = "none";
  std::string sounds = "none";
};

class Respondent;

struct PresentationCall {
  std::string participant;
  int trial = 0;
  int position = 1;  // 1 or 2
  const Stimulus* stimulus = nullptr;
  std::filesystem::path session_path;  // must not exist; the presenter records it there
  // Set for a tune trial's first presentation when the respondent tunes at the device
  // (Respondent::tunes_at_the_device): the presenter plays `stimulus` with the tuning keys
  // live and puts the door the keys ended on here.
  std::optional<DoorModel>* tuned = nullptr;
  Respondent* respondent = nullptr;  // with `tuned`: who tunes (Respondent::scripted_tuning_keys)
  double duration_s = 0.0;           // the presentation's length; 0: the presenter's own
  std::string label;                 // what the participant calls it ("1"); empty: `position`
  // Where the presenter says what it showed and played (null: nobody asks); left as it is
  // by a presenter that shows nothing.
  Presented* presented = nullptr;
};
// Plays one presentation and records it; throws (std::exception) on a device fault.
using Presenter = std::function<void(const PresentationCall&)>;

class Respondent {
 public:
  virtual ~Respondent() = default;
  // The answer as trials.csv spells it ("1", "2", "same", "r1 r2"); throws std::runtime_error
  // when none can be had (the answers ran out, a wrong scripted answer).
  virtual std::string answer(const PlanRow& row, const Stimulus& first, const Stimulus& second,
                             std::ostream& prompts) = 0;
  // The tuned door from `start` (called after the tune trial's first presentation when
  // tunes_at_the_device() is false).
  virtual DoorModel tune(const PlanRow& row, const DoorModel& start, std::ostream& prompts) = 0;
  // True: the tune trial's first presentation is the tuning itself (a person pressing keys
  // while the start plays); the Presenter is called with PresentationCall::tuned and tune()
  // is not called.
  virtual bool tunes_at_the_device() const { return false; }
  // A tune trial at the device: the keys pressed, from a script (the trial's line; `where`
  // is set to "SOURCE:LINE"), or nullopt when a person presses them live at the terminal.
  // Throws std::runtime_error when the script has ended; the default refuses (a respondent
  // that does not tune at the device).
  virtual std::optional<std::string> scripted_tuning_keys(int trial, std::string& where);
  // The attempt the run is in (column `attempt`), set before the first trial.
  virtual void set_attempt(int attempt) { (void)attempt; }
};

// The simulated participant of study/participant_model.h, drawn from `seed`; each trial's
// answer from its own substream (seed, attempt, trial), so a resumed run answers as an
// uninterrupted one would.
class SimulatedRespondent : public Respondent {
 public:
  SimulatedRespondent(std::uint64_t seed, const DoorModel& base, int attempt = 1,
                      const ParticipantModelOptions& options = {});
  std::string answer(const PlanRow& row, const Stimulus& first, const Stimulus& second,
                     std::ostream& prompts) override;
  DoorModel tune(const PlanRow& row, const DoorModel& start, std::ostream& prompts) override;
  const SimulatedParticipant& participant() const { return participant_; }
  void set_attempt(int attempt) override { attempt_ = attempt; }

 private:
  std::mt19937_64 stream(const PlanRow& row) const;
  SimulatedParticipant participant_;
  std::uint64_t seed_;
  int attempt_;
};

// A person: answer lines from `next_line` (stdin or a file). A wrong answer is asked again
// when `interactive`, else ends the run naming `source` and the line. With
// `tunes_at_the_device` the tune trials are the presenter's (the keys live during the first
// presentation; from a file, the trial's line holds the keys: app/campaign_command.cpp),
// else tune() refuses.
class LineRespondent : public Respondent {
 public:
  LineRespondent(std::function<std::optional<std::string>()> next_line, std::string source,
                 bool interactive, bool tunes_at_the_device = false);
  std::string answer(const PlanRow& row, const Stimulus& first, const Stimulus& second,
                     std::ostream& prompts) override;
  DoorModel tune(const PlanRow& row, const DoorModel& start, std::ostream& prompts) override;
  bool tunes_at_the_device() const override { return tunes_at_the_device_; }
  std::optional<std::string> scripted_tuning_keys(int trial, std::string& where) override;
  // The next line of the source (counted for line_number()), for a presenter that reads a
  // tune trial's keys from it.
  std::optional<std::string> next_line();
  int line_number() const { return line_; }
  const std::string& source() const { return source_; }
  bool interactive() const { return interactive_; }

 private:
  std::function<std::optional<std::string>()> next_line_;
  std::string source_;
  bool interactive_;
  bool tunes_at_the_device_;
  int line_ = 0;
};

// The answer `text` checked against `question` and spelled as trials.csv keeps it; throws
// std::invalid_argument saying what was expected, e.g.
// `expected 1, 2 or same (which felt better; same: no preference), got "3"`.
std::string normalized_answer(std::string_view question, std::string_view text);

// The stimuli of a trial: models built once per name and kept in the cache.
class StimulusMaker {
 public:
  explicit StimulusMaker(const Campaign& campaign);
  // `staircase_correct`: the answers so far in this row's block (a staircase or QUEST+ slot's
  // level, study/staircase.h, study/quest_plus.h).
  std::pair<Stimulus, Stimulus> make(const PlanRow& row,
                                     const std::vector<bool>& staircase_correct);
  Stimulus named(const std::string& name);
  const Campaign& campaign() const { return *campaign_; }
  const DoorModel& base() const { return base_; }

 private:
  // A QUEST+ block's level after `answers`: its posterior kept per block and updated by the
  // answers added since the last call (replayed from the prior when they do not extend the
  // kept ones, e.g. for the next participant); the same level as quest_plus_level.
  double quest_level(const Block& block, const std::vector<bool>& answers);
  struct QuestTrack {
    QuestPlus quest;
    std::vector<bool> answers;
    std::size_t next = 0;  // quest.next_level() after `answers`
  };
  const Campaign* campaign_;
  DoorModel base_;
  std::map<std::string, Stimulus> cache_;
  std::map<std::string, QuestTrack> quests_;
};

// The block of `row` (std::invalid_argument when the campaign has none of that name).
const Block& block_of(const Campaign& campaign, const PlanRow& row);
// Whether a stronger:PARAM answer named the comparison (the stimulus that is not PARAM*1).
bool names_comparison(const std::string& first, const std::string& second,
                      const std::string& answer, const std::string& parameter);

struct RunOptions {
  std::string participant;
  bool redo = false;
};

struct RunResult {
  int attempt = 1;
  int planned = 0;
  int answered_before = 0;  // in this attempt, before this run
  int answered_now = 0;
  bool finished() const { return answered_before + answered_now == planned; }
};

// The trials.csv header this run writes. A run that resumes a trials.csv whose header lacks
// some of them (written by an earlier doorbench) writes its rows in that file's header and
// says which columns it leaves out; merge fills a column a folder lacks with "" (not
// recorded).
const std::vector<std::string>& trials_columns();

// Runs (or resumes) `options.participant`. Throws std::runtime_error (device fault, answers
// ended, a trials.csv that does not match the plan, a finished participant without redo, a
// participant not in the plan) after every answer so far is safely in trials.csv.
RunResult run_participant(const CampaignFolder& folder, const RunOptions& options,
                          Respondent& respondent, const Presenter& presenter,
                          std::ostream& prompts);

// Joins campaign folders of one plan into `out` (which must not exist or be empty):
// campaign.toml, plan.csv and plan-id.txt once, trials.csv with every folder's rows, the
// sessions and tuned files (hard-linked where possible, else copied). Refused: folders of
// different plans or seeds (naming both), one participant with rows in two folders.
void merge_campaign_folders(const std::vector<std::filesystem::path>& dirs,
                            const std::filesystem::path& out);

}  // namespace doorbench::study
