#pragma once
// The questions a participant answers about a trial's two presentations, one type for `ab`,
// the campaign's plan, trials.csv and the statistics; and the one parser of an answer.
//
// trials.csv and plan.csv spell a question as
//   preference         which felt better: 1 or 2
//   preference-2ac     which felt better: 1, 2 or same (no preference)
//   identify-real      which was the real door: 1 or 2
//   stronger:PARAM     which felt stronger in PARAM: 1 or 2
//   rating:ATTRIBUTE:K each presentation rated on ATTRIBUTE from 1 to K: "R1 R2"
//   tune               the participant tuned the first presentation (the answer is a file)
// `ab` asks preference, identify-real or rating (no attribute, "rating" in its summaries).
// The words the participant answers with are "1" and "2" unless the caller names others.
// Thread safety: values and free functions without shared state.
#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace doorbench::study {

enum class QuestionKind { kPreference, kPreference2ac, kIdentifyReal, kStronger, kRating, kTune };
// preference | preference-2ac | identify-real | stronger | rating | tune
std::string_view to_string(QuestionKind kind);

using AnswerLabels = std::array<std::string, 2>;

struct Question {
  // A rating scale has 2 to kMaxRatingScale steps.
  static constexpr int kMaxRatingScale = 100;

  QuestionKind kind = QuestionKind::kPreference;
  std::string subject;  // stronger: the parameter; rating: the attribute (empty in `ab`)
  int scale = 7;        // rating: answers from 1 to scale

  // As trials.csv spells it (the table above); a rating without an attribute is "rating".
  std::string text() const;
  // nullopt when `text` is none of the table's spellings (a rating's K outside
  // 2..kMaxRatingScale included).
  static std::optional<Question> parse(std::string_view text);

  // A choice between the two presentations (preference, preference-2ac, identify-real,
  // stronger), as against ratings or a tuning.
  bool is_choice() const;
  bool is_preference() const {
    return kind == QuestionKind::kPreference || kind == QuestionKind::kPreference2ac;
  }
  // What the screen asks, e.g. "which felt better, 1 or 2? ".
  std::string prompt(const AnswerLabels& labels = {"1", "2"}) const;
  // What a valid answer is, e.g. `expected "1" or "2" (which felt better)`.
  std::string expectation(const AnswerLabels& labels = {"1", "2"}) const;
};

// Whether `text` (as trials.csv spells a question) asks a question of `kind`.
bool is_question(std::string_view text, QuestionKind kind);

// The kind `text` is spelled as by its name alone ("stronger:..." is kStronger, "rating" and
// "rating:..." are kRating), whether or not the rest is valid; nullopt for no kind's name. A
// reader of one kind's rows tells a malformed row of that kind (an error) from another
// kind's row (skipped) with it, and then parses the row with Question::parse.
std::optional<QuestionKind> spelled_kind(std::string_view text);

struct Answer {
  int choice = 0;               // 1 or 2 for a choice; 0: "same" (preference-2ac)
  std::array<int, 2> rating{};  // rating: presentations 1 and 2
  std::string text;             // as given, trimmed

  // As trials.csv keeps it: "1", "2", "same", or "R1 R2".
  std::string normalized(const Question& question) const;
};

// Parses one answer to `question` (a choice or a rating; a tune question has no typed
// answer). Throws std::invalid_argument saying what was expected and quoting the text, e.g.
// `expected "1" or "2" (which felt better), got "3"`, `rating 8 is outside 1..7: expected two
// ratings ...`, `no answer: expected "1" or "2" (which felt better)`.
Answer parse_answer(const Question& question, std::string_view text,
                    const AnswerLabels& labels = {"1", "2"});

}  // namespace doorbench::study
