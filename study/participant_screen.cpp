#include "study/participant_screen.h"

#include <ostream>
#include <stdexcept>
#include <thread>

#include "study/tuning_keys.h"

namespace doorbench::study {
namespace {

// The words of "which felt stronger in PARAM?" for the sensations the tuning keys move (and
// the inertia, which is felt as weight); other parameters are named as they are.
std::string stronger_prompt(const std::string& parameter) {
  if (parameter == "heaviness" || parameter == "J") return "Which felt heavier?";
  if (parameter == "latch_effort") return "Which was harder to unlatch?";
  if (parameter == "closing_effort") return "Which was harder to close?";
  if (parameter == "smoothness") return "Which felt rougher?";
  if (parameter == "snap") return "Which had more snap?";
  return "Which felt stronger in " + parameter + "?";
}

// A rating attribute's ends: "heavy-light" is rated from light (1) to heavy (K), the first
// word being the high end (docs/campaign.md); one word is rated from "not WORD" to WORD; no
// attribute (`ab`) from poor to excellent.
std::pair<std::string, std::string> rating_anchors(const std::string& attribute) {
  if (attribute.empty()) return {"poor", "excellent"};
  const std::size_t dash = attribute.find('-');
  if (dash != std::string::npos && dash > 0 && dash + 1 < attribute.size()) {
    return {attribute.substr(dash + 1), attribute.substr(0, dash)};
  }
  return {"not " + attribute, attribute};
}

ScreenQuestion choice_between(std::string prompt, const AnswerLabels& labels) {
  return {std::move(prompt), {labels[0], labels[1]}, {labels[0], labels[1]}, "", ""};
}

// The choice index the screen shows for `answer` to the screen question `at` of `question`.
std::size_t choice_index(const Question& question, const Answer& answer, std::size_t at) {
  if (question.kind == QuestionKind::kRating) return std::size_t(answer.rating[at] - 1);
  return answer.choice == 0 ? 2 : std::size_t(answer.choice - 1);
}

}  // namespace

std::vector<ScreenQuestion> screen_questions(const Question& question, const AnswerLabels& labels) {
  switch (question.kind) {
    case QuestionKind::kPreference:
      return {choice_between("Which did you prefer?", labels)};
    case QuestionKind::kPreference2ac: {
      ScreenQuestion asked = choice_between("Which did you prefer?", labels);
      asked.choices.push_back("no difference");
      asked.answers.push_back("same");
      return {asked};
    }
    case QuestionKind::kIdentifyReal:
      return {choice_between("Which was the real door?", labels)};
    case QuestionKind::kStronger:
      return {choice_between(stronger_prompt(question.subject), labels)};
    case QuestionKind::kRating: {
      if (question.scale < 2 || question.scale > 9) {
        throw std::invalid_argument(
            "the station asks ratings of 2 to 9 points (keys 1 to 9); this one has " +
            std::to_string(question.scale));
      }
      const auto [low, high] = rating_anchors(question.subject);
      std::vector<ScreenQuestion> asked;
      for (const std::string& label : labels) {
        ScreenQuestion rating;
        rating.prompt = "Rate " + label + " from 1 (" + low + ") to " +
                        std::to_string(question.scale) + " (" + high + ")";
        for (int point = 1; point <= question.scale; ++point) {
          rating.choices.push_back(std::to_string(point));
          rating.answers.push_back(std::to_string(point));
        }
        rating.low_anchor = low;
        rating.high_anchor = high;
        asked.push_back(rating);
      }
      return asked;
    }
    case QuestionKind::kTune:
      break;
  }
  throw std::invalid_argument("a tune trial is tuned with the keys, not asked");
}

ScreenPresentation tuning_screen() {
  ScreenPresentation shown;
  shown.caption = "Tune the door with the keys, then press Enter";
  for (const TuningKey& key : tuning_keys()) {
    shown.key_help.push_back(std::string(1, key.key) + "   " + std::string(key.action));
  }
  shown.key_help.push_back(std::string(1, kResetKey) + "   back to the start");
  return shown;
}

ScreenPresentation screen_presentation(std::string caption, const Stimulus& stimulus) {
  ScreenPresentation shown;
  shown.caption = std::move(caption);
  shown.staging = stimulus.staging;
  return shown;
}

std::string screen_problem(const std::vector<PlanRow>& rows) {
  for (const PlanRow& row : rows) {
    const std::optional<Question> question = Question::parse(row.question);
    if (!question || question->kind == QuestionKind::kTune) continue;
    try {
      screen_questions(*question);
    } catch (const std::invalid_argument& problem) {
      return "trial " + std::to_string(row.trial) + " asks " + row.question + ": " + problem.what();
    }
  }
  return "";
}

std::string ask_on_screen(ParticipantScreen& screen, const Question& question,
                          const AnswerLabels& labels,
                          const std::optional<std::string>& scripted_text) {
  const std::vector<ScreenQuestion> asked = screen_questions(question, labels);
  std::optional<Answer> scripted;
  if (scripted_text) scripted = parse_answer(question, *scripted_text, labels);
  std::string text;
  for (std::size_t at = 0; at < asked.size(); ++at) {
    screen.ask(asked[at]);
    if (scripted) screen.script_choice(choice_index(question, *scripted, at), at > 0);
    std::optional<std::size_t> picked;
    while (!(picked = screen.take_choice())) {
      if (const std::string fault = screen.fault(); !fault.empty()) {
        throw std::runtime_error("no answer from the station: " + fault);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (*picked >= asked[at].answers.size()) {
      throw std::logic_error("the station picked a choice the question does not have");
    }
    text += (text.empty() ? "" : " ") + asked[at].answers[*picked];
  }
  return text;
}

ScreenRespondent::ScreenRespondent(ParticipantScreen& screen, Respondent* scripted)
    : screen_(&screen), scripted_(scripted), started_(std::chrono::steady_clock::now()) {}

std::string ScreenRespondent::answer(const PlanRow& row, const Stimulus& first,
                                     const Stimulus& second, std::ostream& prompts) {
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  prompts << "trial " << row.trial << ": asked on the station, " << static_cast<long>(elapsed_s)
          << " s into the run" << std::endl;
  const std::optional<Question> question = Question::parse(row.question);
  if (!question) throw std::invalid_argument("unknown question \"" + row.question + "\"");
  std::optional<std::string> scripted;
  if (scripted_ != nullptr) {
    // The script's own prompts would show the question: they go nowhere.
    std::ostream nowhere(nullptr);
    scripted = scripted_->answer(row, first, second, nowhere);
  }
  return normalized_answer(row.question, ask_on_screen(*screen_, *question, {"1", "2"}, scripted));
}

DoorModel ScreenRespondent::tune(const PlanRow& row, const DoorModel& start,
                                 std::ostream& prompts) {
  if (scripted_ == nullptr) {
    throw std::logic_error("trial " + std::to_string(row.trial) +
                           ": a person at the station tunes during the presentation");
  }
  (void)prompts;
  std::ostream nowhere(nullptr);
  return scripted_->tune(row, start, nowhere);
}

bool ScreenRespondent::tunes_at_the_device() const {
  return scripted_ == nullptr || scripted_->tunes_at_the_device();
}

std::optional<std::string> ScreenRespondent::scripted_tuning_keys(int trial, std::string& where) {
  if (scripted_ == nullptr) return std::nullopt;
  return scripted_->scripted_tuning_keys(trial, where);
}

void ScreenRespondent::set_attempt(int attempt) {
  if (scripted_ != nullptr) scripted_->set_attempt(attempt);
}

}  // namespace doorbench::study
