#include "station/station.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "core/clock.h"
#include "core/number_format.h"
#include "core/numbers.h"

namespace doorbench::station {

std::string StationReport::brief_report() const {
  std::string text = "station: " + std::to_string(frames) + " frames";
  if (frames > 1) {
    text += ", frame interval mean " + format_significant(frame_interval_mean_ms, 3) + " ms, max " +
            format_significant(frame_interval_max_ms, 3) + " ms";
  }
  text += ", " + std::string(to_string(stereo));
  if (!note.empty()) text += " (" + note + ")";
  if (!error.empty()) text += "; stopped: " + error;
  if (closed) text += "; its window was closed";
  return text;
}

Station::Station(const Scene& scene, const haptic::DoorSnapshotChannel& snapshot,
                 StationWindowOptions options)
    : Station(scene, std::move(options)) {
  snapshot_ = &snapshot;
}

Station::Station(const Scene& scene, StationWindowOptions options)
    : scene_(scene), options_(std::move(options)) {
  if (std::string problem = options_.validate(); !problem.empty()) {
    throw std::invalid_argument("station: " + problem);
  }
}

Station::~Station() {
  stop();
}

void Station::start() {
  if (thread_.joinable()) return;
  quit_.store(false);
  thread_ = std::thread([this] { run(); });
  std::unique_lock lock(mutex_);
  opened_.wait(lock, [this] { return open_done_; });
  if (!open_error_.empty()) {
    lock.unlock();
    thread_.join();
    throw std::runtime_error(open_error_);
  }
}

void Station::stop() {
  quit_.store(true);
  if (thread_.joinable()) thread_.join();
}

void Station::follow(const haptic::DoorSnapshotChannel* snapshot) {
  std::lock_guard lock(mutex_);
  snapshot_ = snapshot;
}

void Station::show(const Caption& caption) {
  std::lock_guard lock(mutex_);
  caption_ = caption;
}

void Station::show_scene(const Scene* scene) {
  std::lock_guard lock(mutex_);
  shown_scene_ = scene;
}

void Station::capture(const std::filesystem::path& png, double timeout_s) {
  std::unique_lock lock(mutex_);
  if (!running_) throw std::runtime_error("station: not drawing, no frame to capture");
  capture_png_ = png;
  capture_error_.clear();
  const std::uint64_t before = captures_done_;
  const bool done = captured_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                                       [&] { return captures_done_ != before || !running_; });
  capture_png_.clear();
  if (!done || captures_done_ == before) {
    throw std::runtime_error("station: no frame captured within " +
                             format_significant(timeout_s, 3) + " s");
  }
  if (!capture_error_.empty()) throw std::runtime_error(capture_error_);
}

void Station::pick(std::size_t choice, bool by_click) {
  std::lock_guard lock(mutex_);
  if (choice >= last_asked_.choices.size()) {
    throw std::invalid_argument("station: no choice " + std::to_string(choice + 1) +
                                " in the question asked");
  }
  if (!by_click) {
    injected_.push_back({InputEvent::Kind::kKey, GLFW_KEY_1 + int(choice), 0.0, 0.0});
    return;
  }
  QuestionPanel panel;
  panel.ask(last_asked_);
  const PanelRect button = panel.choice_rects(width_px_, height_px_).at(choice);
  injected_.push_back(
      {InputEvent::Kind::kClick, 0, button.x + 0.5 * button.width, button.y + 0.5 * button.height});
}

std::string Station::take_typed() {
  std::lock_guard lock(mutex_);
  std::string typed = std::move(typed_);
  typed_.clear();
  return typed;
}

std::pair<double, double> Station::window_size() const {
  std::lock_guard lock(mutex_);
  return {width_px_, height_px_};
}

bool Station::running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

void Station::ask(const Question& question) {
  if (std::string problem = question.validate(); !problem.empty()) {
    throw std::invalid_argument("station question: " + problem);
  }
  std::lock_guard lock(mutex_);
  asked_ = question;
  last_asked_ = question;
  answer_.reset();
}

std::optional<Answer> Station::take_answer() {
  std::lock_guard lock(mutex_);
  std::optional<Answer> answer = std::move(answer_);
  answer_.reset();
  return answer;
}

void Station::inject(const InputEvent& event) {
  std::lock_guard lock(mutex_);
  injected_.push_back(event);
}

StationReport Station::report() const {
  std::lock_guard lock(mutex_);
  return report_;
}

void Station::frame_pacing(double& next_frame_s) const {
  // With a display that waits for its refresh, swap() already paces the frames; without (a
  // virtual display), sleep to the display's rate instead of drawing as fast as the CPU can.
  const double rate_hz = options_.max_frame_rate_hz > 0.0
                             ? std::min(refresh_hz_, options_.max_frame_rate_hz)
                             : refresh_hz_;
  const double period_s = 1.0 / rate_hz;
  const double now_s = monotonic_now_s();
  if (next_frame_s > now_s) {
    std::this_thread::sleep_for(std::chrono::duration<double>(next_frame_s - now_s));
  }
  next_frame_s = std::max(next_frame_s + period_s, monotonic_now_s());
}

namespace {

// A typed character as text ('\n' for either Enter key); nothing for other input or a
// character beyond ASCII (the tuning keys are ASCII).
void append_typed(const InputEvent& event, std::string& typed) {
  if (event.kind == InputEvent::Kind::kCharacter && event.key > 0 && event.key < 128) {
    typed.push_back(static_cast<char>(event.key));
  }
  if (event.kind == InputEvent::Kind::kKey &&
      (event.key == GLFW_KEY_ENTER || event.key == GLFW_KEY_KP_ENTER)) {
    typed.push_back('\n');
  }
}

}  // namespace

void Station::run() noexcept {
  // Before the window, so that the threads OpenGL starts for it inherit this thread's nice
  // value (raising it is always permitted).
  if (options_.nice > 0) ::setpriority(PRIO_PROCESS, ::gettid(), options_.nice);
  std::optional<StationWindow> window;
  try {
    window.emplace(scene_, options_);
  } catch (const std::exception& error) {
    std::lock_guard lock(mutex_);
    open_error_ = error.what();
    open_done_ = true;
    opened_.notify_all();
    return;
  }
  {
    std::lock_guard lock(mutex_);
    refresh_hz_ = window->refresh_hz();
    report_.stereo = window->stereo();
    report_.note = window->note();
    width_px_ = window->width_px();
    height_px_ = window->height_px();
    running_ = true;
    open_done_ = true;
  }
  opened_.notify_all();
  QuestionPanel panel;
  Caption caption;
  std::vector<InputEvent> events;
  double next_frame_s = monotonic_now_s(), last_frame_s = kNaN, interval_sum_ms = 0.0;
  try {
    while (!quit_.load(std::memory_order_acquire)) {
      if (window->close_requested()) {
        std::lock_guard lock(mutex_);
        report_.closed = true;
        break;
      }
      const double frame_s = monotonic_now_s();
      events.clear();
      window->poll(events);
      double theta_rad = 0.0;
      const Scene* scene = &scene_;
      std::filesystem::path capture_png;
      {
        std::lock_guard lock(mutex_);
        if (shown_scene_ != nullptr) scene = shown_scene_;
        if (scene->source != report_.scene) {
          if (report_.frames > 0) ++report_.scene_changes;
          report_.scene = scene->source;
        }
        capture_png = capture_png_;
        events.insert(events.end(), injected_.begin(), injected_.end());
        injected_.clear();
        if (asked_) panel.ask(std::move(*asked_));
        asked_.reset();
        caption = caption_;
        width_px_ = window->width_px();
        height_px_ = window->height_px();
        for (const InputEvent& event : events) {
          append_typed(event, typed_);
          if (std::optional<Answer> answer = panel.handle(event, width_px_, height_px_)) {
            answer_ = *answer;
          }
        }
        // Read under the lock: once follow() has returned, the channel it replaced is not read.
        if (snapshot_ != nullptr) theta_rad = snapshot_->read().theta_rad;
        if (!std::isnan(last_frame_s)) {
          const double interval_ms = 1e3 * (frame_s - last_frame_s);
          interval_sum_ms += interval_ms;
          report_.frame_interval_max_ms = std::max(report_.frame_interval_max_ms, interval_ms);
          report_.frame_interval_mean_ms = interval_sum_ms / double(report_.frames);
        }
        ++report_.frames;
      }
      last_frame_s = frame_s;
      window->draw(*scene, theta_rad, panel, caption);
      if (!capture_png.empty()) write_capture(*window, capture_png);
      window->swap();
      frame_pacing(next_frame_s);
    }
  } catch (const std::exception& error) {
    std::lock_guard lock(mutex_);
    report_.error = error.what();
  }
  std::lock_guard lock(mutex_);
  running_ = false;
  captured_.notify_all();
}

void Station::write_capture(const StationWindow& window, const std::filesystem::path& png) {
  std::string error;
  try {
    window.write_png(png);
  } catch (const std::exception& failure) {
    error = failure.what();
  }
  std::lock_guard lock(mutex_);
  capture_error_ = error;
  ++captures_done_;
  capture_png_.clear();
  captured_.notify_all();
}

}  // namespace doorbench::station
