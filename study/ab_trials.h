#pragma once
// Blinded A/B comparisons (docs/ab-testing.md): variant A against variant B on the device,
// or the real door on the bench against a virtual one. Each trial presents both, in an order
// drawn from a seed and balanced over the run; the participant and the operator's screen see
// only "1" and "2". The key that maps them to the variants stays in the results.
//
// This part is the plan, the answers and the statistics, plus the run's bookkeeping around
// a PresentationPlayer, which plays one presentation and records it as a session (the render
// loop's playback on a device, or a simulated stand-in).
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/session/session_file.h"
#include "analysis/model/door_model.h"
#include "study/campaign_run.h"
#include "study/participant_screen.h"
#include "study/question.h"

namespace doorbench::study {

struct AbOptions {
  int trials = 10;
  QuestionKind question = QuestionKind::kPreference;  // preference, identify-real or rating
  int rating_scale = 7;                               // K: ratings 1..K (rating only)
  std::uint64_t seed = 1;
  double presentation_s = 10.0;  // how long each presentation plays
  bool a_is_real = false;        // A is the real door on the bench (identify-real needs it)
  // What the participant and the screen are told for the first and second presentation.
  std::array<std::string, 2> labels{"1", "2"};

  // Empty when usable, else one line naming the option.
  std::string validate() const;
  // Sets the question from its --question text: "preference", "identify-real", "rating"
  // (K = 7) or "rating:K". Returns "" or what is wrong ("--question must be preference,
  // identify-real, rating or rating:K, not X", "--question rating:K needs a whole number K,
  // got X"); the options stay as they were then.
  std::string ask(std::string_view text);
  // The question each trial asks (rating: on 1..rating_scale, no attribute).
  Question asked() const { return Question{question, "", rating_scale}; }
  // "real" when A is the real door, else "A"; B is always "B".
  std::string variant_a() const { return a_is_real ? "real" : "A"; }
};

// One trial: which variant is presented first (position 1) and second (position 2).
struct AbTrial {
  int trial = 0;  // 1-based
  std::array<std::string, 2> variant;
  bool a_first() const { return variant[0] != "B"; }
};

// N trials, each order N/2 times (N even; one order once more when N is odd, chosen by the
// seed), in a shuffled order: the same seed gives the same plan on any platform (the
// generator is std::mt19937_64, whose output the standard fixes, and the bounded draws are
// done here, not by a library distribution). Throws std::invalid_argument on bad options.
std::vector<AbTrial> make_plan(const AbOptions& options);

struct AbTrialOutcome {
  AbTrial plan;
  std::optional<Answer> answer;  // nullopt: not answered (the run stopped)
  std::array<std::string, 2> session_files;
  std::string answered_utc;
};

struct AbSummary {
  QuestionKind question = QuestionKind::kPreference;
  std::string variant_a = "A", variant_b = "B";
  int trials_planned = 0;
  int trials_answered = 0;
  std::uint64_t seed = 0;
  // preference: A and B preferred; identify-real: identified correctly or not.
  int a_preferred = 0, b_preferred = 0;
  int real_identified = 0, real_missed = 0;
  // rating: the mean of each variant's ratings, and which was rated higher (ties apart).
  double mean_rating_a = 0.0, mean_rating_b = 0.0;
  int a_rated_higher = 0, b_rated_higher = 0, rating_ties = 0;
  // The binomial test: `successes` of `test_trials` against chance 0.5.
  long successes = 0, test_trials = 0;
  double p_value = 1.0;
  std::string test_meaning;            // what a success is
  std::vector<AbTrialOutcome> trials;  // with the unblinding key

  std::string brief_report() const;  // counts, p-value, key, several lines
  std::string to_json() const;
};

AbSummary summarize(const AbOptions& options, const std::vector<AbTrialOutcome>& trials);

// --- Running a comparison ----------------------------------------------------------------

// Where answers come from: the next line, or nullopt at the end of the input.
struct AnswerSource {
  std::function<std::optional<std::string>()> next_line;
  std::string name;          // "stdin" or the answers file, for messages
  bool interactive = false;  // a wrong answer is asked again instead of ending the run
  // The participant's screen (null: none): each trial's question is asked there, not on
  // `prompts` (which then shows progress only), and answered there; with `next_line` too,
  // each line is pressed on the screen as the participant would (a scripted run).
  ParticipantScreen* screen = nullptr;
};

struct AbRunInputs {
  AbOptions options;
  std::string params_a;  // the rig file when A is the real door
  std::string params_b;
  // The variants' models (A's is empty when A is the real door), played by the presenter.
  std::optional<DoorModel> model_a, model_b;
  std::filesystem::path out_dir;
};

// Runs the plan: for each trial both presentations through `presenter` (sessions
// trial-NN-1.h5 and trial-NN-2.h5 in out_dir), then the answer, appended to answers.csv at
// once (blind: trial, answer, sessions, time). At the end, or when the answers run out,
// ab-summary.json and ab-summary.txt (with the key). Prompts go to `prompts`. Throws
// std::runtime_error naming the file and line for a wrong scripted answer, the trial and
// presentation when the player throws (in both cases the results so far are written
// first), and for an output folder that already holds results.
AbSummary run_ab(const AbRunInputs& inputs, const Presenter& presenter, const AnswerSource& answers,
                 std::ostream& prompts);

}  // namespace doorbench::study
