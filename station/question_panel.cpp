#include "station/question_panel.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <stdexcept>

namespace doorbench::station {

std::string Question::validate() const {
  if (prompt.empty()) return "a question needs its words (prompt)";
  if (choices.empty() || choices.size() > 9) {
    return "a question needs 1 to 9 choices (got " + std::to_string(choices.size()) + ")";
  }
  return "";
}

void QuestionPanel::ask(Question question) {
  if (std::string problem = question.validate(); !problem.empty()) {
    throw std::invalid_argument("station question: " + problem);
  }
  question_ = std::move(question);
}

PanelRect QuestionPanel::panel_rect(double width_px, double height_px) const {
  return {0.1 * width_px, 0.55 * height_px, 0.8 * width_px, 0.4 * height_px};
}

std::vector<PanelRect> QuestionPanel::choice_rects(double width_px, double height_px) const {
  std::vector<PanelRect> rects;
  if (!question_) return rects;
  const PanelRect panel = panel_rect(width_px, height_px);
  const double n = double(question_->choices.size());
  const double gap = 0.02 * panel.width;
  const double width = (panel.width - gap * (n + 1)) / n;
  const double height = std::min(0.3 * panel.height, 120.0);
  const double y = panel.y + panel.height - height - 0.15 * panel.height;
  for (std::size_t i = 0; i < question_->choices.size(); ++i) {
    rects.push_back({panel.x + gap + double(i) * (width + gap), y, width, height});
  }
  return rects;
}

std::optional<Answer> QuestionPanel::handle(const InputEvent& event, double width_px,
                                            double height_px) {
  if (!question_) return std::nullopt;
  int choice = -1;
  if (event.kind == InputEvent::Kind::kKey) {
    if (event.key >= GLFW_KEY_1 && event.key <= GLFW_KEY_9) choice = event.key - GLFW_KEY_1;
    if (event.key >= GLFW_KEY_KP_1 && event.key <= GLFW_KEY_KP_9) {
      choice = event.key - GLFW_KEY_KP_1;
    }
  } else if (event.kind == InputEvent::Kind::kClick) {
    const std::vector<PanelRect> rects = choice_rects(width_px, height_px);
    for (std::size_t i = 0; i < rects.size(); ++i) {
      if (rects[i].contains(event.x_px, event.y_px)) choice = int(i);
    }
  }
  if (choice < 0 || choice >= int(question_->choices.size())) return std::nullopt;
  Answer answer{choice, question_->choices[std::size_t(choice)], event.kind};
  question_.reset();
  return answer;
}

}  // namespace doorbench::station
