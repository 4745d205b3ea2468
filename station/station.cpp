#include "station/station.h"

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
  return text;
}

Station::Station(const Scene& scene, const haptic::DoorSnapshotChannel& snapshot,
                 StationWindowOptions options)
    : scene_(scene), snapshot_(snapshot), options_(std::move(options)) {
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

void Station::ask(const Question& question) {
  if (std::string problem = question.validate(); !problem.empty()) {
    throw std::invalid_argument("station question: " + problem);
  }
  std::lock_guard lock(mutex_);
  asked_ = question;
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
  const double period_s = 1.0 / refresh_hz_;
  const double now_s = monotonic_now_s();
  if (next_frame_s > now_s) {
    std::this_thread::sleep_for(std::chrono::duration<double>(next_frame_s - now_s));
  }
  next_frame_s = std::max(next_frame_s + period_s, monotonic_now_s());
}

void Station::run() noexcept {
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
    open_done_ = true;
  }
  opened_.notify_all();
  QuestionPanel panel;
  std::vector<InputEvent> events;
  double next_frame_s = monotonic_now_s(), last_frame_s = kNaN, interval_sum_ms = 0.0;
  try {
    while (!quit_.load(std::memory_order_acquire) && !window->close_requested()) {
      const double frame_s = monotonic_now_s();
      events.clear();
      window->poll(events);
      {
        std::lock_guard lock(mutex_);
        events.insert(events.end(), injected_.begin(), injected_.end());
        injected_.clear();
        if (asked_) panel.ask(std::move(*asked_));
        asked_.reset();
        for (const InputEvent& event : events) {
          const double w = window->width_px(), h = window->height_px();
          if (std::optional<Answer> answer = panel.handle(event, w, h)) answer_ = *answer;
        }
        if (!std::isnan(last_frame_s)) {
          const double interval_ms = 1e3 * (frame_s - last_frame_s);
          interval_sum_ms += interval_ms;
          report_.frame_interval_max_ms = std::max(report_.frame_interval_max_ms, interval_ms);
          report_.frame_interval_mean_ms = interval_sum_ms / double(report_.frames);
        }
        ++report_.frames;
      }
      last_frame_s = frame_s;
      window->draw(snapshot_.read().theta_rad, panel);
      window->swap();
      frame_pacing(next_frame_s);
    }
  } catch (const std::exception& error) {
    std::lock_guard lock(mutex_);
    report_.error = error.what();
  }
}

}  // namespace doorbench::station
