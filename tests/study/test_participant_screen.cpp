// The participant's screen of study/participant_screen.h: the questions in words, answers
// given on a screen (a stand-in that records everything it is shown and picks what it is
// scripted to) reaching trials.csv and answers.csv exactly as typed answers do, and no
// variant's name, stimulus or parameter ever shown to the participant.
#include <catch2/catch.hpp>
#include <deque>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fixtures/temp_dir.h"
#include "study/ab_trials.h"
#include "study/campaign_file.h"
#include "study/campaign_plan.h"
#include "study/participant_screen.h"
#include "study/presenter.h"
#include "study/trials_table.h"
#include "tests/support/trials_rows.h"

using doorbench::testing::TempDir;
namespace study = doorbench::study;
namespace haptic = doorbench::haptic;

namespace {

// A screen that keeps every word it is shown, picks the choice scripted to it (as a station
// does with its scripted input) and counts the presentations that showed a door.
class RecordingScreen : public study::ParticipantScreen {
 public:
  study::Presented begin_presentation(const study::ScreenPresentation& shown,
                                      const haptic::DoorSnapshotChannel* door) override {
    CHECK_FALSE(showing_);
    showing_ = true;
    shown_text.push_back(shown.caption);
    for (const std::string& line : shown.key_help) shown_text.push_back(line);
    if (door != nullptr) ++doors_followed;
    const study::Staging& staging = shown.staging;
    staged_files.push_back(staging.scene_file.string() + "|" + staging.sounds_file.string());
    // As a station does: the variant's scene and sounds, else its own; silent for the real
    // door.
    study::Presented presented;
    presented.scene = staging.scene.empty() ? "own-scene" : staging.scene;
    presented.sounds = door == nullptr           ? "none"
                       : !staging.sounds.empty() ? staging.sounds
                       : !staging.scene.empty()  ? staging.scene
                                                 : "own-scene";
    return presented;
  }
  void end_presentation() override {
    CHECK(showing_);
    showing_ = false;
  }
  void ask(const study::ScreenQuestion& question) override {
    CHECK_FALSE(showing_);  // asked after the presentations, not during them
    asked.push_back(question);
    shown_text.push_back(question.prompt);
    for (const std::string& text : question.choices) shown_text.push_back(text);
    shown_text.push_back(question.low_anchor);
    shown_text.push_back(question.high_anchor);
    picked_.reset();
  }
  std::optional<std::size_t> take_choice() override {
    std::optional<std::size_t> picked = picked_;
    picked_.reset();
    return picked;
  }
  void script_choice(std::size_t choice, bool by_click) override {
    REQUIRE(choice < asked.back().choices.size());
    picked_ = choice;
    clicks += by_click ? 1 : 0;
  }
  std::string take_typed() override { return ""; }
  std::string fault() const override { return ""; }

  std::vector<study::ScreenQuestion> asked;
  std::vector<std::string> shown_text;
  std::vector<std::string> staged_files;  // "SCENE_FILE|SOUNDS_FILE" per presentation
  int doors_followed = 0, clicks = 0;

 private:
  bool showing_ = false;
  std::optional<std::size_t> picked_;
};

// The device stand-in: each presentation's playback starts (the screen follows its door
// snapshot) and ends at once.
study::PlayOnDevice instant_player() {
  return [](const doorbench::DoorModel&, const study::PlaySettings& settings) {
    const haptic::DoorSnapshotChannel door;
    if (settings.on_start) settings.on_start(door);
    if (settings.on_end) settings.on_end();
    return haptic::PlaybackSummary{};
  };
}

// Variant names no word on the screen could contain by chance.
constexpr const char* kCampaign = R"(
[campaign]
name = "screen"
seed = 11
simulated_presentation_s = 0.2
[variants]
refdoor_q7 = "base"
heavyvar_x2 = "heaviness*1.2"
latchvar_z9 = "latch_effort*0.7"
[participants]
count = 2
[[blocks]]
name = "tune"
type = "tune"
[[blocks]]
name = "pair"
type = "pair"
question = "preference-2ac"
[[blocks]]
name = "rating"
type = "rating"
attributes = ["heavy-light", "pleasant"]
scale = 5
pairs = [["refdoor_q7", "heavyvar_x2"]]
[[blocks]]
name = "jnd-j"
type = "jnd"
parameter = "J"
levels = [1.1, 1.3]
)";

study::CampaignFolder planned_folder(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "campaign.in.toml") << kCampaign;
  const study::Campaign campaign = study::read_campaign(dir / "campaign.in.toml");
  study::write_campaign_folder(dir / "folder", campaign, study::make_plan(campaign, 11), false);
  return study::open_campaign_folder(dir / "folder");
}

}  // namespace

TEST_CASE("screen questions: the words, the choices and what each answers", "[screen]") {
  auto one = [](const std::string& text) {
    const std::vector<study::ScreenQuestion> asked =
        study::screen_questions(*study::Question::parse(text));
    REQUIRE(asked.size() == 1);
    return asked[0];
  };
  const study::ScreenQuestion two_ac = one("preference-2ac");
  CHECK(two_ac.prompt == "Which did you prefer?");
  CHECK(two_ac.choices == std::vector<std::string>{"1", "2", "no difference"});
  CHECK(two_ac.answers == std::vector<std::string>{"1", "2", "same"});
  CHECK(one("preference").choices == std::vector<std::string>{"1", "2"});
  CHECK(one("identify-real").prompt == "Which was the real door?");
  CHECK(one("stronger:J").prompt == "Which felt heavier?");
  CHECK(one("stronger:heaviness").prompt == "Which felt heavier?");
  CHECK(one("stronger:latch_effort").prompt == "Which was harder to unlatch?");
  CHECK(one("stronger:k_q").prompt == "Which felt stronger in k_q?");

  const auto rating =
      study::screen_questions(*study::Question::parse("rating:heavy-light:5"), {"left", "right"});
  REQUIRE(rating.size() == 2);
  CHECK(rating[0].prompt == "Rate left from 1 (light) to 5 (heavy)");
  CHECK(rating[1].prompt == "Rate right from 1 (light) to 5 (heavy)");
  CHECK(rating[0].choices == std::vector<std::string>{"1", "2", "3", "4", "5"});
  CHECK(rating[0].low_anchor == "light");
  CHECK(rating[0].high_anchor == "heavy");
  const auto pleasant = study::screen_questions(*study::Question::parse("rating:pleasant:7"));
  CHECK(pleasant[0].low_anchor == "not pleasant");
  CHECK(pleasant[0].high_anchor == "pleasant");
  CHECK(study::screen_questions({study::QuestionKind::kRating, "", 3})[0].prompt ==
        "Rate 1 from 1 (poor) to 3 (excellent)");

  CHECK_THROWS_WITH(study::screen_questions(*study::Question::parse("rating:pleasant:12")),
                    "the station asks ratings of 2 to 9 points (keys 1 to 9); this one has 12");
  CHECK_THROWS_WITH(study::screen_questions(*study::Question::parse("tune")),
                    "a tune trial is tuned with the keys, not asked");
  CHECK(study::screen_problem({{"P01", "r", 4, "rating:pleasant:12", "a", "b", 1}}) ==
        "trial 4 asks rating:pleasant:12: the station asks ratings of 2 to 9 points (keys 1 to "
        "9); this one has 12");
}

TEST_CASE("campaign answers given on the screen equal the typed ones, and nothing names a variant",
          "[screen][campaign]") {
  TempDir dir("participant_screen");
  const study::CampaignFolder typed_folder = planned_folder(dir.path / "typed");
  const study::CampaignFolder screen_folder = planned_folder(dir.path / "screen");
  const std::vector<study::PlanRow> plan = typed_folder.plan.of("P01");
  study::PresenterOptions options;
  options.presentation_s = 0.2;
  std::ostringstream operator_lines;

  // The simulated participant answers typed (its answers straight into trials.csv)...
  const study::DevicePresenter typed_presenter(options, instant_player(), {}, operator_lines);
  study::SimulatedRespondent typed(7, study::base_model(typed_folder.campaign));
  const study::RunResult typed_result = study::run_participant(
      typed_folder, {"P01", false}, typed, typed_presenter.as_presenter(), operator_lines);
  REQUIRE(typed_result.finished());

  // ...and the same participant on the screen (its answers picked there).
  RecordingScreen screen;
  study::DevicePresenter screen_presenter(options, instant_player(), {}, operator_lines);
  screen_presenter.show_on(&screen);
  study::SimulatedRespondent simulated(7, study::base_model(screen_folder.campaign));
  study::ScreenRespondent on_screen(screen, &simulated);
  std::ostringstream progress;
  const study::RunResult screen_result = study::run_participant(
      screen_folder, {"P01", false}, on_screen, screen_presenter.as_presenter(), progress);
  REQUIRE(screen_result.finished());

  CHECK(
      doorbench::testing::trials_rows_without_time_and_staging(screen_folder.dir / "trials.csv") ==
      doorbench::testing::trials_rows_without_time_and_staging(typed_folder.dir / "trials.csv"));
  // What was shown and heard: the screen's own scene and sounds on it, nothing without it.
  for (const char* column : {"first_scene", "first_sounds", "second_scene", "second_sounds"}) {
    for (const std::string& value :
         doorbench::testing::trials_column(screen_folder.dir / "trials.csv", column))
      CHECK(value == "own-scene");
    for (const std::string& value :
         doorbench::testing::trials_column(typed_folder.dir / "trials.csv", column))
      CHECK(value == "none");
  }
  // Every presentation showed its door; a rating's second presentation was clicked.
  CHECK(screen.doors_followed == 2 * int(plan.size()));
  CHECK(screen.clicks > 0);

  // Blind: no variant name, stimulus or parameter in anything the screen showed or the
  // operator saw.
  std::vector<std::string> secret = {"refdoor_q7", "heavyvar_x2", "latchvar_z9",  "J*",
                                     "=",          "heaviness*",  "latch_effort*"};
  for (const study::PlanRow& row : plan) {
    if (!row.first.empty()) secret.push_back(row.first);
  }
  for (const std::string& text : screen.shown_text) {
    for (const std::string& name : secret) {
      INFO(text << " / " << name);
      CHECK(text.find(name) == std::string::npos);
    }
  }
  const std::string operator_text = progress.str();
  for (const std::string& name : secret) CHECK(operator_text.find(name) == std::string::npos);
  // The operator sees progress, not the question.
  CHECK(operator_text.find("trial 3: asked on the station, ") != std::string::npos);
  CHECK(operator_text.find("prefer") == std::string::npos);
  CHECK(operator_text.find("which felt") == std::string::npos);
}

TEST_CASE("ab answers given on the screen equal the typed ones", "[screen][ab]") {
  TempDir dir("participant_screen_ab");
  study::AbRunInputs inputs;
  inputs.options.trials = 6;
  inputs.options.seed = 5;
  REQUIRE(inputs.options.ask("rating:4").empty());
  inputs.options.labels = {"left", "right"};
  inputs.model_a = inputs.model_b = study::base_model(study::Campaign{});
  const std::vector<std::string> lines = {"4 1", "2 2", "1 3", "3 4", "2,1", "4 4"};
  auto source = [&lines](std::deque<std::string> left) {
    study::AnswerSource answers;
    answers.name = "answers.txt";
    answers.next_line = [left]() mutable -> std::optional<std::string> {
      if (left.empty()) return std::nullopt;
      std::string line = left.front();
      left.pop_front();
      return line;
    };
    return answers;
  };
  study::PresenterOptions options;
  std::ostringstream operator_lines;
  const study::DevicePresenter typed_presenter(options, instant_player(), {}, operator_lines);
  inputs.out_dir = dir.path / "typed";
  study::run_ab(inputs, typed_presenter.as_presenter(),
                source(std::deque<std::string>(lines.begin(), lines.end())), operator_lines);

  RecordingScreen screen;
  study::DevicePresenter screen_presenter(options, instant_player(), {}, operator_lines);
  screen_presenter.show_on(&screen);
  study::AnswerSource on_screen = source(std::deque<std::string>(lines.begin(), lines.end()));
  on_screen.screen = &screen;
  inputs.out_dir = dir.path / "screen";
  std::ostringstream progress;
  study::run_ab(inputs, screen_presenter.as_presenter(), on_screen, progress);

  auto answers_of = [](const std::filesystem::path& csv) {
    std::ifstream in(csv);
    std::vector<std::string> rows;
    for (std::string line; std::getline(in, line);) rows.push_back(line.substr(0, line.rfind(',')));
    return rows;
  };
  CHECK(answers_of(dir.path / "screen" / "answers.csv") ==
        answers_of(dir.path / "typed" / "answers.csv"));
  REQUIRE(screen.asked.size() == 12);  // two ratings a trial
  CHECK(screen.asked[0].prompt == "Rate left from 1 (poor) to 4 (excellent)");
  CHECK(screen.shown_text.front() == "Presentation left");
  CHECK(progress.str().find("rate") == std::string::npos);
  CHECK(progress.str().find("trial 6 of 6: asked on the station, ") != std::string::npos);
}

TEST_CASE("a presentation is staged on the screen in its variant's scene and sound set",
          "[screen][campaign]") {
  TempDir dir("participant_screen_staged");
  std::filesystem::create_directories(dir.path / "scenes");
  std::ofstream(dir.path / "scenes" / "oak.toml") << "";
  std::ofstream(dir.path / "soft.toml") << "";
  std::ofstream(dir.path / "staged.toml") << R"(
[campaign]
name = "staged"
seed = 3
[variants]
oak = { door = "base", scene = "scenes/oak.toml", sounds = "soft.toml" }
bare = { door = "heaviness*1.2", scene = "scenes/oak.toml" }
plain = "latch_effort*0.7"
[participants]
count = 1
[[blocks]]
name = "pair"
type = "pair"
)";
  const study::Campaign campaign = study::read_campaign(dir.path / "staged.toml");
  study::write_campaign_folder(dir.path / "folder", campaign, study::make_plan(campaign, 3), false);
  const study::CampaignFolder folder = study::open_campaign_folder(dir.path / "folder");
  RecordingScreen screen;
  study::PresenterOptions options;
  options.presentation_s = 0.2;
  std::ostringstream lines;
  study::DevicePresenter presenter(options, instant_player(), {}, lines);
  presenter.show_on(&screen);
  study::SimulatedRespondent simulated(5, study::base_model(folder.campaign));
  study::ScreenRespondent on_screen(screen, &simulated);
  REQUIRE(study::run_participant(folder, {"P01", false}, on_screen, presenter.as_presenter(), lines)
              .finished());
  const study::TrialsTable table = study::read_trials_table(dir.path / "folder" / "trials.csv");
  REQUIRE(table.rows.size() == 6);
  const std::string oak_file = (dir.path / "scenes" / "oak.toml").string();
  const std::string soft_file = (dir.path / "soft.toml").string();
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    for (const std::string position : {"first", "second"}) {
      const std::string& variant = table.value(r, position);
      INFO("row " << r + 1 << " " << position << ": " << variant);
      // The screen was handed the files; trials.csv holds what it said it showed and played.
      const std::string files = screen.staged_files[2 * r + (position == "first" ? 0 : 1)];
      if (variant == "oak") {
        CHECK(files == oak_file + "|" + soft_file);
        CHECK(table.value(r, position + "_scene") == "scenes/oak.toml");
        CHECK(table.value(r, position + "_sounds") == "soft.toml");
      } else if (variant == "bare") {
        CHECK(files == oak_file + "|");
        CHECK(table.value(r, position + "_scene") == "scenes/oak.toml");
        CHECK(table.value(r, position + "_sounds") == "scenes/oak.toml");
      } else {
        CHECK(files == "|");
        CHECK(table.value(r, position + "_scene") == "own-scene");
        CHECK(table.value(r, position + "_sounds") == "own-scene");
      }
    }
  }
  // Still blind: no file's name among the words shown.
  for (const std::string& text : screen.shown_text) CHECK(text.find("oak") == std::string::npos);
}
