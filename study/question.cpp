#include "study/question.h"

#include <algorithm>
#include <charconv>
#include <stdexcept>
#include <vector>

namespace doorbench::study {
namespace {

std::string_view trim(std::string_view text) {
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!text.empty() && space(text.front())) text.remove_prefix(1);
  while (!text.empty() && space(text.back())) text.remove_suffix(1);
  return text;
}

std::string in_quotes(std::string_view text) {
  return "\"" + std::string(text) + "\"";
}

// The whole number in `text` (digits only, at most 3), else nullopt.
std::optional<int> small_whole_number(std::string_view text) {
  if (text.empty() || text.size() > 3) return std::nullopt;
  int value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.front() == '-') {
    return std::nullopt;
  }
  return value;
}

std::vector<std::string> words_of(std::string_view text) {
  std::vector<std::string> words;
  std::string word;
  for (char c : text) {
    if (c == ' ' || c == '\t' || c == ',') {
      if (!word.empty()) words.push_back(word);
      word.clear();
    } else {
      word += c;
    }
  }
  if (!word.empty()) words.push_back(word);
  return words;
}

Answer parse_rating(const Question& question, std::string_view answer,
                    const std::string& expected) {
  Answer result;
  result.text = std::string(answer);
  const std::vector<std::string> words = words_of(answer);
  if (words.size() != 2) throw std::invalid_argument(expected + ", got " + in_quotes(answer));
  for (int i = 0; i < 2; ++i) {
    const std::optional<int> value = small_whole_number(words[i]);
    if (!value) {
      throw std::invalid_argument(in_quotes(words[i]) + " is not a whole number: " + expected +
                                  ", got " + in_quotes(answer));
    }
    if (*value < 1 || *value > question.scale) {
      throw std::invalid_argument("rating " + words[i] + " is outside 1.." +
                                  std::to_string(question.scale) + ": " + expected + ", got " +
                                  in_quotes(answer));
    }
    result.rating[i] = *value;
  }
  return result;
}

}  // namespace

std::string_view to_string(QuestionKind kind) {
  switch (kind) {
    case QuestionKind::kPreference:
      return "preference";
    case QuestionKind::kPreference2ac:
      return "preference-2ac";
    case QuestionKind::kIdentifyReal:
      return "identify-real";
    case QuestionKind::kStronger:
      return "stronger";
    case QuestionKind::kRating:
      return "rating";
    case QuestionKind::kTune:
      return "tune";
  }
  return "?";
}

std::string Question::text() const {
  switch (kind) {
    case QuestionKind::kStronger:
      return "stronger:" + subject;
    case QuestionKind::kRating:
      return subject.empty() ? "rating" : "rating:" + subject + ":" + std::to_string(scale);
    default:
      return std::string(to_string(kind));
  }
}

std::optional<Question> Question::parse(std::string_view text) {
  for (QuestionKind kind : {QuestionKind::kPreference, QuestionKind::kPreference2ac,
                            QuestionKind::kIdentifyReal, QuestionKind::kTune}) {
    if (text == to_string(kind)) return Question{kind, "", 7};
  }
  if (text.starts_with("stronger:") && text.size() > 9) {
    return Question{QuestionKind::kStronger, std::string(text.substr(9)), 7};
  }
  if (text.starts_with("rating:")) {
    const std::string_view rest = text.substr(7);
    const std::size_t colon = rest.rfind(':');
    if (colon == std::string_view::npos || colon == 0) return std::nullopt;
    const std::optional<int> scale = small_whole_number(rest.substr(colon + 1));
    if (!scale || *scale < 2 || *scale > kMaxRatingScale) return std::nullopt;
    return Question{QuestionKind::kRating, std::string(rest.substr(0, colon)), *scale};
  }
  return std::nullopt;
}

bool is_question(std::string_view text, QuestionKind kind) {
  const std::optional<Question> question = Question::parse(text);
  return question && question->kind == kind;
}

std::optional<QuestionKind> spelled_kind(std::string_view text) {
  for (QuestionKind kind : {QuestionKind::kPreference, QuestionKind::kPreference2ac,
                            QuestionKind::kIdentifyReal, QuestionKind::kTune}) {
    if (text == to_string(kind)) return kind;
  }
  if (text.starts_with("stronger:")) return QuestionKind::kStronger;
  if (text == "rating" || text.starts_with("rating:")) return QuestionKind::kRating;
  return std::nullopt;
}

bool Question::is_choice() const {
  return kind != QuestionKind::kRating && kind != QuestionKind::kTune;
}

std::string Question::prompt(const AnswerLabels& labels) const {
  const std::string either = labels[0] + " or " + labels[1];
  switch (kind) {
    case QuestionKind::kPreference:
      return "which felt better, " + either + "? ";
    case QuestionKind::kPreference2ac:
      return "which felt better, " + labels[0] + ", " + labels[1] + " or same? ";
    case QuestionKind::kIdentifyReal:
      return "which was the real door, " + either + "? ";
    case QuestionKind::kStronger:
      return "which felt stronger in " + subject + ", " + either + "? ";
    case QuestionKind::kRating: {
      const std::string k = std::to_string(scale);
      return "rate " + labels[0] + " and " + labels[1] + (subject.empty() ? "" : " on " + subject) +
             ", each 1 to " + k + " (e.g. \"" + k + " 1\"): ";
    }
    case QuestionKind::kTune:
      return "tune the door, then say done: ";
  }
  return "? ";
}

std::string Question::expectation(const AnswerLabels& labels) const {
  const std::string either = "expected " + in_quotes(labels[0]) + " or " + in_quotes(labels[1]);
  switch (kind) {
    case QuestionKind::kPreference:
      return either + " (which felt better)";
    case QuestionKind::kPreference2ac:
      return "expected " + in_quotes(labels[0]) + ", " + in_quotes(labels[1]) +
             " or \"same\" (which felt better; same: no preference)";
    case QuestionKind::kIdentifyReal:
      return either + " (which was the real door)";
    case QuestionKind::kStronger:
      return either + " (which felt stronger)";
    case QuestionKind::kRating:
      return "expected two ratings from 1 to " + std::to_string(scale) +
             ", one per presentation (e.g. \"" + std::to_string(scale) + " 1\")";
    case QuestionKind::kTune:
      return "expected no typed answer (a tune trial is tuned)";
  }
  return "";
}

std::string Answer::normalized(const Question& question) const {
  if (question.kind == QuestionKind::kRating) {
    return std::to_string(rating[0]) + " " + std::to_string(rating[1]);
  }
  return choice == 0 ? "same" : std::to_string(choice);
}

Answer parse_answer(const Question& question, std::string_view text, const AnswerLabels& labels) {
  const std::string_view answer = trim(text);
  const std::string expected = question.expectation(labels);
  if (question.kind == QuestionKind::kTune) throw std::invalid_argument(expected);
  if (answer.empty()) throw std::invalid_argument("no answer: " + expected);
  if (question.kind == QuestionKind::kRating) return parse_rating(question, answer, expected);
  Answer result;
  result.text = std::string(answer);
  if (answer == labels[0]) {
    result.choice = 1;
  } else if (answer == labels[1]) {
    result.choice = 2;
  } else if (question.kind == QuestionKind::kPreference2ac && answer == "same") {
    result.choice = 0;
  } else {
    throw std::invalid_argument(expected + ", got " + in_quotes(answer));
  }
  return result;
}

}  // namespace doorbench::study
