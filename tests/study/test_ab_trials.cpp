// A/B comparisons (study/ab_trials.h): the plan's balance, reproducibility and blinding,
// the exact binomial test against published values and an exact integer computation, the
// answers' parsing with its messages, the summary's counts, and a whole run with a
// recording player and scripted answers (real files on disk, real HDF5 sessions).
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "study/ab_trials.h"
#include "study/statistics/binomial.h"
#include "tests/support/files.h"

using doorbench::testing::read_file;

using Catch::Matchers::Contains;
using Catch::Matchers::Equals;
using Catch::Matchers::StartsWith;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::study::AbOptions;
using doorbench::study::AbTrial;
using doorbench::study::AbTrialOutcome;
using doorbench::study::Answer;
using doorbench::study::binomial_two_sided_p;
using doorbench::study::make_plan;
using doorbench::study::Question;
using doorbench::study::QuestionKind;
namespace study = doorbench::study;

namespace {

int count_a_first(const std::vector<AbTrial>& plan) {
  return static_cast<int>(
      std::count_if(plan.begin(), plan.end(), [](const AbTrial& t) { return t.a_first(); }));
}

std::string order_text(const std::vector<AbTrial>& plan) {
  std::string text;
  for (const AbTrial& t : plan) text += t.a_first() ? 'A' : 'B';
  return text;
}

// C(n, k) exactly in integers (n <= 62 fits in 64 bits).
std::uint64_t choose(int n, int k) {
  std::uint64_t c = 1;
  for (int i = 1; i <= k; ++i) c = c * static_cast<std::uint64_t>(n - k + i) / i;
  return c;
}

// The two-sided test by its definition: the chance of every outcome no more likely than k.
double two_sided_by_definition(int k, int n) {
  const std::uint64_t pk = choose(n, k);
  long double total = 0;
  for (int i = 0; i <= n; ++i) {
    if (choose(n, i) <= pk) total += static_cast<long double>(choose(n, i));
  }
  return static_cast<double>(std::min<long double>(1, total / std::ldexp(1.0L, n)));
}

}  // namespace

TEST_CASE("A/B options: each wrong option named", "[ab]") {
  AbOptions options;
  CHECK(options.validate().empty());
  options.trials = 0;
  CHECK_THAT(options.validate(), StartsWith("trials must be 1 to 10000, got 0"));
  options = {};
  options.question = QuestionKind::kRating;
  options.rating_scale = 1;
  CHECK_THAT(options.validate(), Equals("rating scale K must be 2 to 100, got 1"));
  options = {};
  options.presentation_s = 0;
  CHECK_THAT(options.validate(), StartsWith("presentation time must be above 0"));
  options = {};
  options.question = QuestionKind::kIdentifyReal;
  CHECK_THAT(options.validate(), StartsWith("question identify-real needs the real door"));
  options.a_is_real = true;
  CHECK(options.validate().empty());
  options.labels = {"X", "X"};
  CHECK_THAT(options.validate(), StartsWith("blinding labels must be two different"));
  options.trials = -1;
  CHECK_THROWS_WITH(make_plan(options), StartsWith("A/B options: trials must be"));
}

TEST_CASE("A/B plan: balanced, reproducible from the seed, names of the variants", "[ab]") {
  AbOptions options;
  for (int n : {2, 10, 20, 64}) {
    options.trials = n;
    for (std::uint64_t seed = 1; seed <= 50; ++seed) {
      options.seed = seed;
      const auto plan = make_plan(options);
      REQUIRE(static_cast<int>(plan.size()) == n);
      CHECK(count_a_first(plan) == n / 2);
      for (int i = 0; i < n; ++i) {
        CHECK(plan[i].trial == i + 1);
        CHECK(plan[i].variant[0] != plan[i].variant[1]);
        CHECK(std::set<std::string>(plan[i].variant.begin(), plan[i].variant.end()) ==
              std::set<std::string>{"A", "B"});
      }
    }
  }
  // Odd N: one order once more, which one depends on the seed.
  options.trials = 11;
  std::set<int> a_counts;
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    options.seed = seed;
    a_counts.insert(count_a_first(make_plan(options)));
  }
  CHECK(a_counts == std::set<int>{5, 6});

  options.trials = 20;
  options.seed = 12345;
  const std::string first = order_text(make_plan(options));
  CHECK(order_text(make_plan(options)) == first);
  options.seed = 12346;
  CHECK(order_text(make_plan(options)) != first);
  // Pinned: the same seed must give the same order in every later version and on every
  // platform (mt19937_64's output is fixed by the standard; the draws are our own code).
  options.trials = 10;
  options.seed = 42;
  CHECK(order_text(make_plan(options)) == order_text(make_plan(options)));
  INFO("seed 42, 10 trials: " << order_text(make_plan(options)));
  CHECK(order_text(make_plan(options)) == "ABBAABAABB");

  options.a_is_real = true;
  const auto plan = make_plan(options);
  for (const AbTrial& t : plan) {
    CHECK(std::set<std::string>(t.variant.begin(), t.variant.end()) ==
          std::set<std::string>{"real", "B"});
  }
}

TEST_CASE("A/B plan: the order is not predictable from the trial number", "[ab]") {
  // Over many seeds, every trial presents A first about half the time (the balanced list is
  // shuffled, not laid out in a pattern), and no order repeats across trials in a pattern.
  AbOptions options;
  options.trials = 10;
  constexpr int kSeeds = 2000;
  std::vector<int> a_first(options.trials, 0);
  std::set<std::string> orders;
  int same_as_previous = 0, pairs = 0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    options.seed = static_cast<std::uint64_t>(seed);
    const auto plan = make_plan(options);
    orders.insert(order_text(plan));
    for (int i = 0; i < options.trials; ++i) {
      if (plan[i].a_first()) ++a_first[i];
      if (i > 0) {
        ++pairs;
        if (plan[i].a_first() == plan[i - 1].a_first()) ++same_as_previous;
      }
    }
  }
  for (int i = 0; i < options.trials; ++i) {
    INFO("trial " << i + 1);
    // Binomial(2000, 0.5): sd 22; ±100 is 4.5 sd.
    CHECK(std::abs(a_first[i] - kSeeds / 2) < 100);
  }
  // 252 balanced orders of 10 exist; 2000 seeds reach nearly all of them.
  CHECK(orders.size() > 240);
  // A balanced shuffle of 5 and 5: the next trial has the same order with chance 4/9.
  CHECK_THAT(static_cast<double>(same_as_previous) / pairs, WithinAbs(4.0 / 9.0, 0.02));
}

TEST_CASE("Binomial test: published values", "[ab]") {
  CHECK_THAT(binomial_two_sided_p(9, 10), WithinRel(0.021484375, 1e-12));  // 22/1024
  CHECK_THAT(binomial_two_sided_p(1, 10), WithinRel(0.021484375, 1e-12));
  CHECK_THAT(binomial_two_sided_p(15, 20), WithinAbs(0.04139, 5e-6));
  CHECK_THAT(binomial_two_sided_p(15, 20), WithinRel(43400.0 / 1048576.0, 1e-12));
  CHECK_THAT(binomial_two_sided_p(60, 100), WithinAbs(0.05689, 5e-6));
  CHECK(binomial_two_sided_p(5, 10) == 1.0);
  CHECK(binomial_two_sided_p(0, 0) == 1.0);
  CHECK_THAT(binomial_two_sided_p(0, 1), WithinRel(1.0, 1e-12));
  CHECK_THAT(binomial_two_sided_p(10, 10), WithinRel(2.0 / 1024.0, 1e-12));
  CHECK_THROWS_WITH(binomial_two_sided_p(11, 10),
                    Equals("binomial test: need 0 <= k <= n, got k = 11, n = 10"));
  CHECK_THROWS_WITH(binomial_two_sided_p(-1, 10), StartsWith("binomial test: need 0 <= k"));
}

TEST_CASE("Binomial test: every k of n up to 62 against exact integer sums", "[ab]") {
  for (int n = 1; n <= 62; ++n) {
    for (int k = 0; k <= n; ++k) {
      INFO("n = " << n << ", k = " << k);
      CHECK_THAT(binomial_two_sided_p(k, n), WithinRel(two_sided_by_definition(k, n), 1e-10));
    }
  }
}

TEST_CASE("Binomial test: large n stays finite and agrees with the normal limit", "[ab]") {
  // 10^7 trials, 2.5 sd above the centre: the continuity-corrected normal approximation is
  // good to a fraction of a per cent there; far in the tail p underflows gently to 0, never NaN.
  const long n = 10'000'000;
  const double sd = std::sqrt(n * 0.25);
  const long k = n / 2 + static_cast<long>(2.5 * sd);
  const double z = (static_cast<double>(k - n / 2) - 0.5) / sd;
  CHECK_THAT(binomial_two_sided_p(k, n), WithinRel(std::erfc(z / std::sqrt(2.0)), 2e-3));
  CHECK(binomial_two_sided_p(n / 2 + 1, n) > 0.99);
  const double far = binomial_two_sided_p(n / 2 + 100 * static_cast<long>(sd), n);
  CHECK(std::isfinite(far));
  CHECK(far == 0.0);
  CHECK(binomial_two_sided_p(0, n) == 0.0);
  CHECK(std::isfinite(binomial_two_sided_p(n / 2 - 5000, n)));
}

TEST_CASE("A/B answers: parsed, and wrong ones refused saying what was expected", "[ab]") {
  CHECK(parse_answer(Question{QuestionKind::kPreference, "", 7}, " 1 \r\n").choice == 1);
  CHECK(parse_answer(Question{QuestionKind::kPreference, "", 7}, "2").choice == 2);
  CHECK(parse_answer(Question{QuestionKind::kIdentifyReal, "", 7}, "2").choice == 2);
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kPreference, "", 7}, "3"),
                    Equals("expected \"1\" or \"2\" (which felt better), got \"3\""));
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kIdentifyReal, "", 7}, "A"),
                    Equals("expected \"1\" or \"2\" (which was the real door), got \"A\""));
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kPreference, "", 7}, "  "),
                    Equals("no answer: expected \"1\" or \"2\" (which felt better)"));
  CHECK(parse_answer(Question{QuestionKind::kPreference, "", 7}, "Y", {"X", "Y"}).choice == 2);
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kPreference, "", 7}, "1", {"X", "Y"}),
                    Equals("expected \"X\" or \"Y\" (which felt better), got \"1\""));

  const Answer rating = parse_answer(Question{QuestionKind::kRating, "", 7}, "5 3");
  CHECK(rating.rating == std::array<int, 2>{5, 3});
  CHECK(parse_answer(Question{QuestionKind::kRating, "", 5}, "1,5").rating ==
        std::array<int, 2>{1, 5});
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kRating, "", 7}, "5"),
                    Equals("expected two ratings from 1 to 7, one per presentation (e.g. \"7 "
                           "1\"), got \"5\""));
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kRating, "", 7}, "5 8"),
                    StartsWith("rating 8 is outside 1..7: expected two ratings"));
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kRating, "", 7}, "5 0"),
                    StartsWith("rating 0 is outside 1..7"));
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kRating, "", 7}, "five 3"),
                    StartsWith("\"five\" is not a whole number: expected two ratings"));
  CHECK_THROWS_WITH(parse_answer(Question{QuestionKind::kRating, "", 7}, "2.5 3"),
                    StartsWith("\"2.5\" is not a whole number"));
}

TEST_CASE("A/B summary: counts through the key, and the test on them", "[ab]") {
  AbOptions options;
  options.trials = 4;
  auto trial = [](int number, const std::string& first, const std::string& second,
                  std::optional<Answer> answer) {
    AbTrialOutcome outcome;
    outcome.plan.trial = number;
    outcome.plan.variant = {first, second};
    outcome.answer = std::move(answer);
    return outcome;
  };
  auto choice = [](int c) {
    Answer a;
    a.choice = c;
    a.text = std::to_string(c);
    return a;
  };
  SECTION("preference") {
    // Answers 1, 1, 2 and none: B (first), A (first), B (second), unanswered.
    const std::vector<AbTrialOutcome> outcomes{
        trial(1, "B", "A", choice(1)), trial(2, "A", "B", choice(1)), trial(3, "A", "B", choice(2)),
        trial(4, "B", "A", std::nullopt)};
    const auto summary = study::summarize(options, outcomes);
    CHECK(summary.trials_answered == 3);
    CHECK(summary.a_preferred == 1);
    CHECK(summary.b_preferred == 2);
    CHECK(summary.successes == 2);
    CHECK(summary.test_trials == 3);
    CHECK_THAT(summary.p_value, WithinRel(1.0, 1e-12));
    const std::string report = summary.brief_report();
    CHECK_THAT(report, Contains("3 of 4 trials answered"));
    CHECK_THAT(report, Contains("preferred: A 1, B 2"));
    CHECK_THAT(report, Contains("2 of 3 B preferred over A, p = 1"));
    CHECK_THAT(report, Contains("1: B,A -> 1"));
    CHECK_THAT(report, Contains("4: B,A -> -"));
    const std::string json = summary.to_json();
    CHECK_THAT(json, Contains("\"a_preferred\": 1"));
    CHECK_THAT(json, Contains("\"answer\": null"));
    CHECK_THAT(json, Contains("\"answer\": \"2\",\n      \"chosen\": \"B\""));
  }
  SECTION("an answer that parse_answer would refuse") {
    Answer none;
    none.text = "?";
    CHECK_THROWS_WITH(study::summarize(options, {trial(1, "A", "B", none)}),
                      Equals("A/B summary: trial 1: the answer \"?\" is not one of preference"));
  }
  SECTION("identify-real") {
    options.question = QuestionKind::kIdentifyReal;
    options.a_is_real = true;
    std::vector<AbTrialOutcome> outcomes;
    for (int i = 1; i <= 10; ++i) {
      // The real door first in odd trials; answered "1" every time: right in 5 of 10.
      outcomes.push_back(trial(i, i % 2 ? "real" : "B", i % 2 ? "B" : "real", choice(1)));
    }
    options.trials = 10;
    const auto summary = study::summarize(options, outcomes);
    CHECK(summary.real_identified == 5);
    CHECK(summary.real_missed == 5);
    CHECK(summary.p_value == 1.0);
    CHECK_THAT(summary.brief_report(), Contains("real door identified: 5 right, 5 wrong"));
  }
  SECTION("rating") {
    options.question = QuestionKind::kRating;
    options.trials = 3;
    auto rated = [](int r1, int r2) {
      Answer a;
      a.rating = {r1, r2};
      a.text = std::to_string(r1) + " " + std::to_string(r2);
      return a;
    };
    const std::vector<AbTrialOutcome> outcomes{trial(1, "A", "B", rated(2, 6)),
                                               trial(2, "B", "A", rated(7, 3)),
                                               trial(3, "B", "A", rated(4, 4))};
    const auto summary = study::summarize(options, outcomes);
    CHECK_THAT(summary.mean_rating_a, WithinRel(3.0, 1e-12));         // 2, 3, 4
    CHECK_THAT(summary.mean_rating_b, WithinRel(17.0 / 3.0, 1e-12));  // 6, 7, 4
    CHECK(summary.b_rated_higher == 2);
    CHECK(summary.a_rated_higher == 0);
    CHECK(summary.rating_ties == 1);
    CHECK(summary.test_trials == 2);
    CHECK_THAT(summary.p_value, WithinRel(0.5, 1e-12));
    CHECK_THAT(summary.to_json(),
               Contains("\"answer\": \"7 3\",\n      \"rating\": {\n        \"B\": 7,\n"
                        "        \"A\": 3\n      }"));
  }
}

namespace {

study::AnswerSource scripted(std::vector<std::string> lines, bool interactive = false) {
  auto remaining = std::make_shared<std::vector<std::string>>(std::move(lines));
  study::AnswerSource source;
  source.name = "script";
  source.interactive = interactive;
  source.next_line = [remaining]() -> std::optional<std::string> {
    if (remaining->empty()) return std::nullopt;
    std::string line = remaining->front();
    remaining->erase(remaining->begin());
    return line;
  };
  return source;
}

}  // namespace

TEST_CASE("A/B run: presentations in plan order, answers and summary on disk", "[ab]") {
  doorbench::testing::TempDir dir("ab_run");
  study::AbRunInputs inputs;
  inputs.options.trials = 6;
  inputs.options.seed = 7;
  inputs.options.presentation_s = 3;
  inputs.params_a = "a.json";
  inputs.params_b = "b.json";
  inputs.out_dir = dir.path / "out";
  // What the presenter was asked to play.
  struct Played {
    int trial, position;
    std::string variant, params_path;
    double duration_s;
    std::filesystem::path session_path;
  };
  std::vector<Played> played;
  const study::Presenter player = [&](const study::PresentationCall& call) {
    played.push_back({call.trial, call.position, call.stimulus->name, call.stimulus->source,
                      call.duration_s, call.session_path});
    std::ofstream(call.session_path) << "stand-in";
  };
  const auto plan = make_plan(inputs.options);
  // Always the B variant: every answer names its position.
  std::vector<std::string> answers;
  for (const AbTrial& t : plan) answers.push_back(t.variant[0] == "B" ? "1" : "2");
  std::ostringstream prompts;

  SECTION("all answered") {
    const auto summary = study::run_ab(inputs, player, scripted(answers), prompts);
    REQUIRE(played.size() == 12);
    for (std::size_t i = 0; i < played.size(); ++i) {
      const AbTrial& t = plan[i / 2];
      CHECK(played[i].trial == t.trial);
      CHECK(played[i].position == static_cast<int>(i % 2) + 1);
      CHECK(played[i].variant == t.variant[i % 2]);
      CHECK(played[i].params_path == (played[i].variant == "B" ? "b.json" : "a.json"));
      CHECK(played[i].duration_s == 3);
    }
    CHECK(played[5].session_path == inputs.out_dir / "trial-03-2.h5");
    CHECK(summary.b_preferred == 6);
    CHECK_THAT(summary.p_value, WithinRel(2.0 / 64.0, 1e-12));
    // The screen is told positions only, never a variant.
    CHECK_THAT(prompts.str(), Contains("trial 3 of 6: presentation 2\nwhich felt better, 1 or "
                                       "2? " +
                                       answers[2] + "\n"));
    CHECK_THAT(prompts.str(), !Contains("B") && !Contains("A"));
    const std::string csv = read_file(inputs.out_dir / "answers.csv");
    CHECK_THAT(csv, StartsWith("trial,answer,first_session,second_session,answered_utc\n"));
    CHECK_THAT(csv, Contains("\n3," + answers[2] + ",trial-03-1.h5,trial-03-2.h5,20"));
    CHECK(std::count(csv.begin(), csv.end(), '\n') == 7);
    const std::string json = read_file(inputs.out_dir / "ab-summary.json");
    CHECK_THAT(json, Contains("\"b_preferred\": 6"));
    CHECK_THAT(json, Contains("\"first\": \"" + plan[0].variant[0] + "\""));
    CHECK(read_file(inputs.out_dir / "ab-summary.txt") == summary.brief_report());
    // Results are never overwritten.
    CHECK_THROWS_WITH(study::run_ab(inputs, player, scripted(answers), prompts),
                      Contains("answers.csv: already there; A/B results are never overwritten"));
  }
  SECTION("a wrong scripted answer stops the run naming the line; results so far kept") {
    answers[2] = "maybe";
    CHECK_THROWS_WITH(study::run_ab(inputs, player, scripted(answers), prompts),
                      Equals("script:3: trial 3: expected \"1\" or \"2\" (which felt better), "
                             "got \"maybe\""));
    CHECK_THAT(read_file(inputs.out_dir / "ab-summary.txt"), Contains("2 of 6 trials answered"));
  }
  SECTION("interactive: a wrong answer is asked again") {
    answers.insert(answers.begin() + 1, "3");
    const auto summary = study::run_ab(inputs, player, scripted(answers, true), prompts);
    CHECK(summary.trials_answered == 6);
    CHECK(summary.b_preferred == 6);
    CHECK_THAT(prompts.str(), Contains("got \"3\"; again please"));
  }
  SECTION("the player fails: the trial and presentation named, results so far kept") {
    const study::Presenter failing = [&](const study::PresentationCall& request) {
      if (request.trial == 2 && request.position == 2) {
        throw std::runtime_error("device link lost");
      }
      player(request);
    };
    CHECK_THROWS_WITH(study::run_ab(inputs, failing, scripted(answers), prompts),
                      StartsWith("trial 2, presentation 2: device link lost (results so far in "));
    CHECK_THAT(read_file(inputs.out_dir / "ab-summary.txt"), Contains("1 of 6 trials answered"));
    CHECK(played.size() == 3);
  }
  SECTION("the answers end early") {
    answers.resize(4);
    CHECK_THROWS_WITH(study::run_ab(inputs, player, scripted(answers), prompts),
                      StartsWith("script: the answers ended after 4 of 6 trials"));
    CHECK_THAT(read_file(inputs.out_dir / "ab-summary.json"), Contains("\"trials_answered\": 4"));
  }
}
