#pragma once
// The station's question and its answer (no OpenGL here): what the participant is asked
// after a trial, the choices as buttons laid out on the window, and which input answers it.
// Input comes as InputEvents carrying GLFW's key codes and window coordinates, whether from
// the window's callbacks or scripted by a test, so the same path is exercised either way.
//
// Keys: 1..9 on the main row or the keypad pick the choice of that number (the first is 1);
// a click or touch on a choice's button picks it. Nothing else answers (characters typed,
// kCharacter, are text for a tuning, not answers).
//
// Not thread-safe: the station's thread owns it (Station::ask and Station::take_answer are
// the other threads' way in).
#include <optional>
#include <string>
#include <vector>

namespace doorbench::station {

struct Question {
  std::string prompt;                   // "Which did you prefer?"
  std::vector<std::string> choices;     // "1", "2", "no difference"; a scale's points
  std::string low_anchor, high_anchor;  // a rating scale's words at its ends, or empty
  std::vector<std::string> key_help;    // a tune trial's keys: "+  heavier", ...
  std::string validate() const;         // "" or one line: 1 to 9 choices, a prompt
};

struct InputEvent {
  enum class Kind { kKey, kClick, kCharacter };
  Kind kind = Kind::kKey;
  int key = 0;                    // GLFW_KEY_* (kKey); the Unicode code point (kCharacter)
  double x_px = 0.0, y_px = 0.0;  // window coordinates, y downwards (kClick)
};

// What the station shows over the door outside a question: a title ("Presentation 1") and
// lines under it (a tune trial's keys and what each does).
struct Caption {
  std::string title;
  std::vector<std::string> lines;
  bool empty() const { return title.empty() && lines.empty(); }
};

struct Answer {
  int choice = -1;   // index into Question::choices
  std::string text;  // the choice's words
  InputEvent::Kind by = InputEvent::Kind::kKey;
};

struct PanelRect {
  double x = 0, y = 0, width = 0, height = 0;  // window pixels, y downwards
  bool contains(double px, double py) const {
    return px >= x && px < x + width && py >= y && py < y + height;
  }
};

class QuestionPanel {
 public:
  // Shows `question` (replacing any); throws std::invalid_argument when it is not valid.
  void ask(Question question);
  void clear() { question_.reset(); }
  bool asking() const { return question_.has_value(); }
  const Question& question() const { return *question_; }

  // The panel's box and each choice's button in a window of the given size: a row of
  // buttons across the lower third.
  PanelRect panel_rect(double width_px, double height_px) const;
  std::vector<PanelRect> choice_rects(double width_px, double height_px) const;

  // The answer this event gives, if any; the question is then cleared.
  std::optional<Answer> handle(const InputEvent& event, double width_px, double height_px);

 private:
  std::optional<Question> question_;
};

}  // namespace doorbench::station
