#include "study/ab_trials.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <ostream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "acquisition/session/session_csv.h"
#include "core/number_format.h"
#include "core/seeded_random.h"
#include "core/time_text.h"
#include "study/statistics/binomial.h"

namespace doorbench::study {
namespace {

constexpr int kMaxTrials = 10000;

std::string in_quotes(std::string_view text) {
  return std::string("\"").append(text).append("\"");
}

std::string two_digits(int trial) {
  std::string text = std::to_string(trial);
  if (text.size() < 2) text.insert(0, 2 - text.size(), '0');
  return text;
}

int position_of(const AbTrial& trial, const std::string& variant) {
  return trial.variant[0] == variant ? 0 : 1;
}

std::string format_p(double p) {
  std::ostringstream text;
  text << std::setprecision(4) << p;
  return text.str();
}

}  // namespace

std::string AbOptions::validate() const {
  if (trials < 1 || trials > kMaxTrials) {
    return "trials must be 1 to " + std::to_string(kMaxTrials) + ", got " + std::to_string(trials);
  }
  if (question != QuestionKind::kPreference && question != QuestionKind::kIdentifyReal &&
      question != QuestionKind::kRating) {
    return "an A/B run asks preference, identify-real or rating, not " +
           std::string(to_string(question));
  }
  if (question == QuestionKind::kRating &&
      (rating_scale < 2 || rating_scale > Question::kMaxRatingScale)) {
    return "rating scale K must be 2 to " + std::to_string(Question::kMaxRatingScale) + ", got " +
           std::to_string(rating_scale);
  }
  if (!std::isfinite(presentation_s) || presentation_s <= 0 || presentation_s > 3600) {
    return "presentation time must be above 0 and at most 3600 s, got " +
           format_number(presentation_s) + " s";
  }
  if (question == QuestionKind::kIdentifyReal && !a_is_real) {
    return "question identify-real needs the real door as one variant (A is not the real door)";
  }
  if (labels[0].empty() || labels[1].empty() || labels[0] == labels[1]) {
    return "blinding labels must be two different, non-empty words, got " + in_quotes(labels[0]) +
           " and " + in_quotes(labels[1]);
  }
  for (const std::string& label : labels) {
    if (label.find_first_of(" \t\r\n,") != std::string::npos) {
      return "blinding label " + in_quotes(label) + " must not hold spaces or commas";
    }
  }
  return "";
}

std::string AbOptions::ask(std::string_view text) {
  const std::string given(text);
  if (text == "preference" || text == "identify-real" || text == "rating") {
    question = text == "preference"      ? QuestionKind::kPreference
               : text == "identify-real" ? QuestionKind::kIdentifyReal
                                         : QuestionKind::kRating;
    return "";
  }
  if (!text.starts_with("rating:")) {
    return "--question must be preference, identify-real, rating or rating:K, not " + given;
  }
  const std::string_view scale = text.substr(7);
  const bool digits = !scale.empty() && scale.size() <= 3 &&
                      scale.find_first_not_of("0123456789") == std::string_view::npos;
  if (!digits) return "--question rating:K needs a whole number K, got " + given;
  question = QuestionKind::kRating;
  rating_scale = std::stoi(std::string(scale));
  return "";
}

std::vector<AbTrial> make_plan(const AbOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("A/B options: " + problem);
  }
  std::mt19937_64 random(options.seed);
  const int n = options.trials;
  // true: A first. Balanced list first, then shuffled (Fisher–Yates).
  std::vector<bool> a_first;
  a_first.reserve(n);
  for (int i = 0; i < n / 2; ++i) a_first.push_back(true);
  for (int i = 0; i < n / 2; ++i) a_first.push_back(false);
  if (n % 2 == 1) a_first.push_back(uniform_below(random, 2) == 0);
  for (int i = n - 1; i > 0; --i) {
    const auto j = static_cast<int>(uniform_below(random, static_cast<std::uint64_t>(i) + 1));
    const bool swap = a_first[i];
    a_first[i] = a_first[j];
    a_first[j] = swap;
  }
  std::vector<AbTrial> plan(n);
  const std::string a = options.variant_a();
  for (int i = 0; i < n; ++i) {
    plan[i].trial = i + 1;
    plan[i].variant =
        a_first[i] ? std::array<std::string, 2>{a, "B"} : std::array<std::string, 2>{"B", a};
  }
  return plan;
}

AbSummary summarize(const AbOptions& options, const std::vector<AbTrialOutcome>& trials) {
  AbSummary summary;
  summary.question = options.question;
  summary.variant_a = options.variant_a();
  summary.trials_planned = options.trials;
  summary.seed = options.seed;
  summary.trials = trials;
  double sum_a = 0.0, sum_b = 0.0;
  for (const AbTrialOutcome& outcome : trials) {
    if (!outcome.answer) continue;
    ++summary.trials_answered;
    const Answer& answer = *outcome.answer;
    // Answers made by hand rather than by parse_answer: refuse what it would have refused.
    const bool choice_ok = answer.choice == 1 || answer.choice == 2;
    const bool ratings_ok = std::all_of(answer.rating.begin(), answer.rating.end(),
                                        [&](int r) { return r >= 1 && r <= options.rating_scale; });
    if (options.question == QuestionKind::kRating ? !ratings_ok : !choice_ok) {
      throw std::invalid_argument("A/B summary: trial " + std::to_string(outcome.plan.trial) +
                                  ": the answer " + in_quotes(answer.text) + " is not one of " +
                                  std::string(to_string(options.question)));
    }
    switch (options.question) {
      case QuestionKind::kPreference:
        if (outcome.plan.variant[answer.choice - 1] == "B") {
          ++summary.b_preferred;
        } else {
          ++summary.a_preferred;
        }
        break;
      case QuestionKind::kIdentifyReal:
        if (outcome.plan.variant[answer.choice - 1] == "real") {
          ++summary.real_identified;
        } else {
          ++summary.real_missed;
        }
        break;
      case QuestionKind::kRating: {
        const int a = answer.rating[position_of(outcome.plan, summary.variant_a)];
        const int b = answer.rating[position_of(outcome.plan, "B")];
        sum_a += a;
        sum_b += b;
        if (a > b) {
          ++summary.a_rated_higher;
        } else if (b > a) {
          ++summary.b_rated_higher;
        } else {
          ++summary.rating_ties;
        }
        break;
      }
      default:  // not an A/B question: AbOptions::validate() refuses it
        break;
    }
  }
  switch (options.question) {
    case QuestionKind::kPreference:
      summary.successes = summary.b_preferred;
      summary.test_trials = summary.trials_answered;
      summary.test_meaning = "B preferred over " + summary.variant_a;
      break;
    case QuestionKind::kIdentifyReal:
      summary.successes = summary.real_identified;
      summary.test_trials = summary.trials_answered;
      summary.test_meaning = "the real door identified";
      break;
    case QuestionKind::kRating:
      summary.successes = summary.b_rated_higher;
      summary.test_trials = summary.a_rated_higher + summary.b_rated_higher;
      summary.test_meaning = "B rated higher than " + summary.variant_a + " (ties left out)";
      if (summary.trials_answered > 0) {
        summary.mean_rating_a = sum_a / summary.trials_answered;
        summary.mean_rating_b = sum_b / summary.trials_answered;
      }
      break;
    default:  // not an A/B question: AbOptions::validate() refuses it
      break;
  }
  summary.p_value = binomial_two_sided_p(summary.successes, summary.test_trials);
  return summary;
}

std::string AbSummary::brief_report() const {
  std::ostringstream text;
  text << "A/B " << to_string(question) << ": " << variant_a << " vs " << variant_b << ", "
       << trials_answered << " of " << trials_planned << " trials answered (seed " << seed << ")\n";
  switch (question) {
    case QuestionKind::kPreference:
      text << "  preferred: " << variant_a << " " << a_preferred << ", B " << b_preferred << "\n";
      break;
    case QuestionKind::kIdentifyReal:
      text << "  real door identified: " << real_identified << " right, " << real_missed
           << " wrong\n";
      break;
    case QuestionKind::kRating:
      text << "  mean rating: " << variant_a << " " << format_p(mean_rating_a) << ", B "
           << format_p(mean_rating_b) << "; rated higher: " << variant_a << " " << a_rated_higher
           << ", B " << b_rated_higher << ", ties " << rating_ties << "\n";
      break;
    default:  // not an A/B question: AbOptions::validate() refuses it
      break;
  }
  text << "  exact binomial test (two-sided, chance 0.5): " << successes << " of " << test_trials
       << " " << test_meaning << ", p = " << format_p(p_value) << "\n";
  text << "  key (trial: first, second -> answer):";
  for (std::size_t i = 0; i < trials.size(); ++i) {
    const AbTrialOutcome& t = trials[i];
    text << (i % 5 == 0 ? "\n    " : "  ") << t.plan.trial << ": " << t.plan.variant[0] << ","
         << t.plan.variant[1] << " -> " << (t.answer ? t.answer->text : "-");
  }
  text << "\n";
  return text.str();
}

std::string AbSummary::to_json() const {
  nlohmann::ordered_json json;
  json["question"] = std::string(to_string(question));
  json["variant_a"] = variant_a;
  json["variant_b"] = variant_b;
  json["seed"] = seed;
  json["trials_planned"] = trials_planned;
  json["trials_answered"] = trials_answered;
  switch (question) {
    case QuestionKind::kPreference:
      json["counts"] = {{"a_preferred", a_preferred}, {"b_preferred", b_preferred}};
      break;
    case QuestionKind::kIdentifyReal:
      json["counts"] = {{"real_identified", real_identified}, {"real_missed", real_missed}};
      break;
    case QuestionKind::kRating:
      json["counts"] = {{"mean_rating_a", mean_rating_a},
                        {"mean_rating_b", mean_rating_b},
                        {"a_rated_higher", a_rated_higher},
                        {"b_rated_higher", b_rated_higher},
                        {"ties", rating_ties}};
      break;
    default:  // not an A/B question: AbOptions::validate() refuses it
      break;
  }
  json["binomial_test"] = {
      {"successes", successes}, {"trials", test_trials}, {"success_means", test_meaning},
      {"chance", 0.5},          {"sided", "two"},        {"p_value", p_value}};
  nlohmann::ordered_json key = nlohmann::ordered_json::array();
  for (const AbTrialOutcome& t : trials) {
    nlohmann::ordered_json row;
    row["trial"] = t.plan.trial;
    row["first"] = t.plan.variant[0];
    row["second"] = t.plan.variant[1];
    row["answer"] = t.answer ? nlohmann::ordered_json(t.answer->text) : nlohmann::ordered_json();
    // The answer through the key: the variant chosen, or each variant's rating.
    if (t.answer && question == QuestionKind::kRating) {
      row["rating"] = {{t.plan.variant[0], t.answer->rating[0]},
                       {t.plan.variant[1], t.answer->rating[1]}};
    } else if (t.answer && (t.answer->choice == 1 || t.answer->choice == 2)) {
      row["chosen"] = t.plan.variant[t.answer->choice - 1];
    }
    row["sessions"] = {t.session_files[0], t.session_files[1]};
    row["answered_utc"] = t.answered_utc;
    key.push_back(row);
  }
  json["key"] = key;
  return json.dump(2) + "\n";
}

namespace {

// A trial's answer: on the participant's screen when `answers` has one (pressed there from
// the next line when scripted), else the next line (asked again when interactive). Throws
// std::runtime_error naming the source when the answers end ("the answers ended after ...")
// and, with its line, for a wrong scripted answer.
Answer next_answer(const AbTrial& trial, const AbRunInputs& inputs, const AnswerSource& answers,
                   int& line, double elapsed_s, std::ostream& prompts) {
  const AbOptions& options = inputs.options;
  auto ended = [&] {
    return std::runtime_error(answers.name + ": the answers ended after " +
                              std::to_string(trial.trial - 1) + " of " +
                              std::to_string(options.trials) + " trials (results so far in " +
                              inputs.out_dir.string() + ")");
  };
  auto wrong_line = [&](const std::invalid_argument& wrong) {
    return std::runtime_error(answers.name + ":" + std::to_string(line) + ": trial " +
                              std::to_string(trial.trial) + ": " + wrong.what());
  };
  if (answers.screen != nullptr) {
    prompts << "trial " << trial.trial << " of " << options.trials << ": asked on the station, "
            << static_cast<long>(elapsed_s) << " s into the run" << std::endl;
    std::optional<std::string> scripted;
    if (answers.next_line) {
      scripted = answers.next_line();
      ++line;
      if (!scripted) throw ended();
    }
    try {
      const std::string text =
          ask_on_screen(*answers.screen, options.asked(), options.labels, scripted);
      return parse_answer(options.asked(), text, options.labels);
    } catch (const std::invalid_argument& wrong) {
      throw wrong_line(wrong);
    }
  }
  const std::string prompt = options.asked().prompt(options.labels);
  for (;;) {
    prompts << prompt << std::flush;
    const std::optional<std::string> text = answers.next_line();
    ++line;
    // A terminal echoes what was typed; a script's answer is shown so the log reads whole.
    if (text && !answers.interactive) prompts << *text << "\n";
    if (!text) {
      prompts << "\n";
      throw ended();
    }
    try {
      return parse_answer(options.asked(), *text, options.labels);
    } catch (const std::invalid_argument& wrong) {
      if (!answers.interactive) throw wrong_line(wrong);
      prompts << wrong.what() << "; again please\n";
    }
  }
}

}  // namespace

AbSummary run_ab(const AbRunInputs& inputs, const Presenter& presenter, const AnswerSource& answers,
                 std::ostream& prompts) {
  const AbOptions& options = inputs.options;
  const std::vector<AbTrial> plan = make_plan(options);
  namespace fs = std::filesystem;
  const fs::path answers_path = inputs.out_dir / "answers.csv";
  for (const char* name : {"answers.csv", "ab-summary.json", "ab-summary.txt"}) {
    if (fs::exists(inputs.out_dir / name)) {
      throw std::runtime_error((inputs.out_dir / name).string() +
                               ": already there; A/B results are never overwritten (use another "
                               "--out folder)");
    }
  }
  std::error_code error;
  fs::create_directories(inputs.out_dir, error);
  if (error) {
    throw std::runtime_error(inputs.out_dir.string() +
                             ": cannot create folder: " + error.message());
  }
  std::ofstream csv(answers_path);
  if (!csv) throw std::runtime_error(answers_path.string() + ": cannot create");
  csv << "trial,answer,first_session,second_session,answered_utc\n" << std::flush;

  const std::map<std::string, Stimulus> stimuli = {
      {options.variant_a(), Stimulus{options.variant_a(), inputs.model_a, "", inputs.params_a, {}}},
      {"B", Stimulus{"B", inputs.model_b, "", inputs.params_b, {}}}};
  std::vector<AbTrialOutcome> outcomes;
  auto finish = [&] {
    AbSummary summary = summarize(options, outcomes);
    for (const auto& [name, text] :
         {std::pair<std::string, std::string>{"ab-summary.json", summary.to_json()},
          std::pair<std::string, std::string>{"ab-summary.txt", summary.brief_report()}}) {
      std::ofstream file(inputs.out_dir / name);
      file << text;
      if (!file) throw std::runtime_error((inputs.out_dir / name).string() + ": cannot write");
    }
    return summary;
  };

  int line = 0;
  const auto started = std::chrono::steady_clock::now();
  for (const AbTrial& trial : plan) {
    AbTrialOutcome outcome;
    outcome.plan = trial;
    for (int position = 1; position <= 2; ++position) {
      const std::string file =
          "trial-" + two_digits(trial.trial) + "-" + std::to_string(position) + ".h5";
      outcome.session_files[position - 1] = file;
      PresentationCall call;
      call.trial = trial.trial;
      call.position = position;
      call.stimulus = &stimuli.at(trial.variant[position - 1]);
      call.session_path = inputs.out_dir / file;
      call.duration_s = options.presentation_s;
      call.label = options.labels[position - 1];
      prompts << "trial " << trial.trial << " of " << options.trials << ": presentation "
              << options.labels[position - 1] << std::endl;
      try {
        presenter(call);
      } catch (const std::exception& failure) {
        // The device or the recording failed: keep what was answered, say where it stopped.
        outcomes.push_back(outcome);
        finish();
        throw std::runtime_error("trial " + std::to_string(trial.trial) + ", presentation " +
                                 options.labels[position - 1] + ": " + failure.what() +
                                 " (results so far in " + inputs.out_dir.string() + ")");
      }
    }
    try {
      const double elapsed_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      outcome.answer = next_answer(trial, inputs, answers, line, elapsed_s, prompts);
    } catch (const std::exception&) {
      outcomes.push_back(outcome);
      finish();
      throw;
    }
    outcome.answered_utc = utc_now_iso8601();
    std::string answer_field = outcome.answer->text;
    if (answer_field.find_first_of(",\"") != std::string::npos) {
      answer_field = std::to_string(outcome.answer->rating[0]) + " " +
                     std::to_string(outcome.answer->rating[1]);
    }
    csv << trial.trial << "," << answer_field << "," << outcome.session_files[0] << ","
        << outcome.session_files[1] << "," << outcome.answered_utc << "\n"
        << std::flush;
    if (!csv) throw std::runtime_error(answers_path.string() + ": cannot write");
    outcomes.push_back(outcome);
  }
  return finish();
}

}  // namespace doorbench::study
