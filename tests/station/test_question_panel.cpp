// The station's questions: which input answers which choice (GLFW's key codes, clicks on the
// buttons' rectangles), what is refused, and the live station answering a scripted click and
// a scripted key under Xvfb.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include "fixtures/temp_dir.h"
#include "haptic/door_snapshot.h"
#include "station/question_panel.h"
#include "station/station.h"
#include "tests/support/viewer_pixels.h"

using namespace doorbench;
using station::InputEvent;

namespace {

station::Question preference() {
  station::Question question;
  question.prompt = "Which did you prefer?";
  question.choices = {"1", "2", "no difference"};
  return question;
}

InputEvent key(int code) {
  return {InputEvent::Kind::kKey, code, 0.0, 0.0};
}
InputEvent click(double x, double y) {
  return {InputEvent::Kind::kClick, 0, x, y};
}

// Waits up to 10 s for the station's answer.
std::optional<station::Answer> answer_of(station::Station& live) {
  for (int i = 0; i < 1000; ++i) {
    if (auto answer = live.take_answer()) return answer;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return std::nullopt;
}

}  // namespace

TEST_CASE("question panel: keys, keypad and clicks answer, nothing else does", "[station]") {
  station::QuestionPanel panel;
  CHECK_FALSE(panel.handle(key(GLFW_KEY_1), 800, 600));  // nothing asked
  panel.ask(preference());
  CHECK_FALSE(panel.handle(key(GLFW_KEY_4), 800, 600));  // no fourth choice
  CHECK_FALSE(panel.handle(key(GLFW_KEY_A), 800, 600));
  CHECK_FALSE(panel.handle(click(5, 5), 800, 600));  // not on a button
  const auto answer = panel.handle(key(GLFW_KEY_KP_3), 800, 600);
  REQUIRE(answer);
  CHECK(answer->choice == 2);
  CHECK(answer->text == "no difference");
  CHECK_FALSE(panel.asking());  // answered: gone

  panel.ask(preference());
  const auto rects = panel.choice_rects(1600, 900);
  REQUIRE(rects.size() == 3);
  for (std::size_t i = 1; i < rects.size(); ++i)
    CHECK(rects[i].x >= rects[i - 1].x + rects[i - 1].width);
  const auto clicked = panel.handle(
      click(rects[1].x + rects[1].width / 2, rects[1].y + rects[1].height / 2), 1600, 900);
  REQUIRE(clicked);
  CHECK(clicked->choice == 1);
  CHECK(clicked->by == InputEvent::Kind::kClick);

  station::Question empty;
  empty.prompt = "Rate it";
  CHECK_THROWS_WITH(panel.ask(empty), "station question: a question needs 1 to 9 choices (got 0)");
  empty.choices = {"1"};
  empty.prompt.clear();
  CHECK_THROWS_WITH(panel.ask(empty), "station question: a question needs its words (prompt)");
}

// Run by the test below under Xvfb: the live station asked twice, answered by a scripted
// click on the second button, then by the scripted key 3; the answers go to
// $DOORBENCH_TEST_DIR/answers.txt, and a screenshot of the question to question.png.
TEST_CASE("station answers by scripted input (child of the test below)", "[.][child]") {
  const char* dir = std::getenv("DOORBENCH_TEST_DIR");
  REQUIRE(dir != nullptr);
  const station::Scene scene = station::default_scene();
  haptic::DoorSnapshotChannel snapshot;
  station::StationWindowOptions options;
  options.fullscreen = false;
  options.width_px = 800;
  options.height_px = 600;
  station::Question rating;
  rating.prompt = "How heavy did the door feel?";
  rating.choices = {"1", "2", "3", "4", "5", "6", "7"};
  rating.low_anchor = "very light";
  rating.high_anchor = "very heavy";
  station::station_screenshot(scene, 0.3, std::filesystem::path(dir) / "question.png", options,
                              &rating);
  station::Station live(scene, snapshot, options);
  live.start();
  std::ofstream out(std::filesystem::path(dir) / "answers.txt");
  live.ask(preference());
  const auto rects = station::QuestionPanel().choice_rects(800, 600);  // nothing asked: none
  REQUIRE(rects.empty());
  station::QuestionPanel layout;
  layout.ask(preference());
  const auto button = layout.choice_rects(800, 600)[1];
  live.inject(click(button.x + button.width / 2, button.y + button.height / 2));
  const auto first = answer_of(live);
  REQUIRE(first);
  out << first->choice << " " << first->text << "\n";
  live.ask(preference());
  live.inject(key(GLFW_KEY_3));
  const auto second = answer_of(live);
  REQUIRE(second);
  out << second->choice << " " << second->text << "\n";
  live.stop();
  CHECK(live.report().frames > 0);
}

TEST_CASE("the live station answers a scripted click and key", "[station][xvfb]") {
  testing::TempDir dir("station_questions");
  const auto self = std::filesystem::read_symlink("/proc/self/exe");
  std::string err;
  const int status = testing::run_under_xvfb(
      "env DOORBENCH_TEST_DIR='" + dir.path.string() + "' '" + self.string() +
          "' 'station answers by scripted input (child of the test below)'",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  std::ifstream in(dir.path / "answers.txt");
  std::string first, second;
  std::getline(in, first);
  std::getline(in, second);
  CHECK(first == "1 2");
  CHECK(second == "2 no difference");
  const testing::Screenshot shot = testing::load_screenshot(dir.path / "question.png", false);
  CHECK(shot.width == 800);
}

// Run by the test below under Xvfb: a station that follows no playback, then one playback's
// snapshot and none again; picks by key and by click of the question last asked; characters
// typed and Enter as text; results to $DOORBENCH_TEST_DIR/trial.txt.
TEST_CASE("station follows playbacks and takes picks and typing (child of the test below)",
          "[.][child]") {
  const char* dir = std::getenv("DOORBENCH_TEST_DIR");
  REQUIRE(dir != nullptr);
  const station::Scene scene = station::default_scene();
  station::StationWindowOptions options;
  options.fullscreen = false;
  options.width_px = 640;
  options.height_px = 480;
  station::Station live(scene, options);
  live.start();
  std::ofstream out(std::filesystem::path(dir) / "trial.txt");
  {
    auto playback = std::make_unique<haptic::DoorSnapshotChannel>();
    playback->publish(0.001, 0.4, 0.0);
    live.show({"Presentation 1", {"+   heavier"}});
    live.follow(playback.get());
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    live.follow(nullptr);
    playback.reset();  // no longer read once follow() has returned
  }
  live.show({});
  live.ask(preference());
  live.pick(2, false);
  const auto by_key = answer_of(live);
  REQUIRE(by_key);
  out << by_key->choice << " " << by_key->text << "\n";
  live.ask(preference());
  live.pick(1, true);
  const auto by_click = answer_of(live);
  REQUIRE(by_click);
  out << by_click->choice << " " << int(by_click->by == InputEvent::Kind::kClick) << "\n";
  CHECK_THROWS_WITH(live.pick(3, false), "station: no choice 4 in the question asked");
  live.take_typed();
  live.inject({InputEvent::Kind::kCharacter, '+', 0.0, 0.0});
  live.inject({InputEvent::Kind::kCharacter, 'U', 0.0, 0.0});
  live.inject(key(GLFW_KEY_KP_ENTER));
  std::string typed;
  for (int i = 0; i < 1000 && typed.size() < 3; ++i) {
    typed += live.take_typed();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  out << typed;
  CHECK(live.running());
  live.stop();
  CHECK_FALSE(live.running());
  CHECK(live.report().frames > 3);
}

TEST_CASE("the live station follows playbacks, takes picks and typed keys", "[station][xvfb]") {
  testing::TempDir dir("station_follow");
  const auto self = std::filesystem::read_symlink("/proc/self/exe");
  std::string err;
  const int status = testing::run_under_xvfb(
      "env DOORBENCH_TEST_DIR='" + dir.path.string() + "' '" + self.string() +
          "' 'station follows playbacks and takes picks and typing (child of the test below)'",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  std::ifstream in(dir.path / "trial.txt");
  std::stringstream text;
  text << in.rdbuf();
  // By key: choice 3; by click: choice 2, a click; typed "+U" and the keypad's Enter.
  CHECK(text.str() == "2 no difference\n1 1\n+U\n");
}
