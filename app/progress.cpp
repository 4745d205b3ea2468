#include "app/progress.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>

#include "core/number_format.h"

namespace doorbench::app {

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "? s";
  if (seconds < 3599.5) {
    const long whole = std::lround(seconds);
    if (whole < 60) return printf_text("%ld s", whole);
    return printf_text("%ld min %02ld s", whole / 60, whole % 60);
  }
  const long minutes = std::lround(seconds / 60.0);
  return printf_text("%ld h %02ld min", minutes / 60, minutes % 60);
}

double time_left_s(double done, double total, double elapsed_s) {
  if (!(done > 0) || !(total > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (done >= total) return 0.0;
  return elapsed_s * (total - done) / done;
}

std::string progress_time_text(double done, double total, double elapsed_s, bool total_is_bound) {
  if (total > 0 && done >= total) return "done in " + format_duration(elapsed_s);
  const std::string so_far = format_duration(elapsed_s) + " so far, ";
  const double left_s = time_left_s(done, total, elapsed_s);
  if (std::isnan(left_s)) return so_far + "time left not known yet";
  return so_far + (total_is_bound ? "at most about " : "about ") + format_duration(left_s) +
         " left";
}

bool stderr_is_terminal() {
  return ::isatty(STDERR_FILENO) != 0;
}

int stderr_terminal_columns() {
  winsize size{};
  if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &size) != 0) return 0;
  return size.ws_col;
}

StatusLine::StatusLine(std::ostream& out, bool terminal, double plain_interval_s, int columns)
    : out_(out), terminal_(terminal), plain_interval_s_(plain_interval_s), columns_(columns) {}

StatusLine::~StatusLine() {
  finish();
}

void StatusLine::draw() {
  // At most columns − 1 characters: the cursor stays on the line, and '\r' returns to its
  // start. Cut between UTF-8 characters (a continuation byte is 10xxxxxx).
  std::size_t length = text_.size();
  if (columns_ > 1) {
    std::size_t characters = 0;
    for (std::size_t i = 0; i < text_.size(); ++i) {
      if ((static_cast<unsigned char>(text_[i]) & 0xC0) == 0x80) continue;
      if (++characters == static_cast<std::size_t>(columns_)) {
        length = i;
        break;
      }
    }
  }
  out_ << '\r';
  out_.write(text_.data(), static_cast<std::streamsize>(length));
  out_ << "\x1b[K" << std::flush;
  on_screen_ = true;
  drawn_ = true;
}

void StatusLine::clear() {
  if (on_screen_) out_ << "\r\x1b[K";
  on_screen_ = false;
}

void StatusLine::update(const std::string& text, Clock::time_point now, bool new_stage) {
  const std::lock_guard lock(mutex_);
  if (!terminal_ && new_stage) {
    if (!text_.empty() && !drawn_) out_ << text_ << '\n';
    printed_plain_ = false;
  }
  text_ = text;
  drawn_ = false;
  if (terminal_) {
    if (!on_screen_ || now - last_draw_ >= std::chrono::milliseconds(100)) {
      draw();
      last_draw_ = now;
    }
    return;
  }
  if (!printed_plain_ || now - last_draw_ >= std::chrono::duration<double>(plain_interval_s_)) {
    out_ << text_ << '\n' << std::flush;
    printed_plain_ = true;
    drawn_ = true;
    last_draw_ = now;
  }
}

void StatusLine::line(const std::string& text) {
  const std::lock_guard lock(mutex_);
  if (terminal_) {
    clear();
  } else if (!text_.empty() && !drawn_) {
    out_ << text_ << '\n';  // the held-back status, so that the plain log ends each stage
  }
  out_ << text << '\n' << std::flush;
  text_.clear();
  drawn_ = false;
  printed_plain_ = false;
}

void StatusLine::finish() {
  const std::lock_guard lock(mutex_);
  if (!text_.empty()) {
    if (terminal_) {
      if (!drawn_) draw();
      out_ << '\n';
    } else if (!drawn_) {
      out_ << text_ << '\n';
    }
  }
  out_ << std::flush;
  text_.clear();
  on_screen_ = false;
  drawn_ = false;
}

std::string fit_progress_text(const FitProgress& progress, double elapsed_s) {
  if (progress.stage == FitProgress::Stage::kWindows) {
    return printf_text("window fit: iteration %d of at most %d, ", progress.done, progress.total) +
           progress_time_text(progress.done, progress.total, elapsed_s, true);
  }
  if (progress.stage == FitProgress::Stage::kHops) {
    return printf_text("global search: %d of %d basin hops polished, ", progress.done,
                       progress.total) +
           progress_time_text(progress.done, progress.total, elapsed_s);
  }
  if (progress.stage == FitProgress::Stage::kPolish) {
    return "global search: " + progress.what +
           printf_text(": iteration %d of at most %d, ", progress.done, progress.total) +
           progress_time_text(progress.done, progress.total, elapsed_s, true);
  }
  if (progress.stage == FitProgress::Stage::kSearch) {
    const std::string round =
        progress.round > 1 ? printf_text(", round %d", progress.round) : std::string();
    return printf_text("global search%s: %d of %d subset refits, ", round.c_str(), progress.done,
                       progress.total) +
           progress_time_text(progress.done, progress.total, elapsed_s);
  }
  return printf_text("cross-validation: %d of %d folds refitted, ", progress.done, progress.total) +
         progress_time_text(progress.done, progress.total, elapsed_s);
}

std::string loop_progress_text(const LoopProgress& progress, double completed_s, double current_s) {
  const int completed = progress.step - 1 + (progress.refits_done >= progress.refits ? 1 : 0);
  const std::string head =
      printf_text("loop step %d of at most %d: %d of %d refits done, ", progress.step,
                  progress.max_steps, progress.refits_done, progress.refits);
  const double so_far_s = completed_s + current_s;
  if (completed >= progress.max_steps) return head + "done in " + format_duration(so_far_s);
  if (completed <= 0) {
    return head + format_duration(so_far_s) + " so far, time left known after step 1";
  }
  const double per_step_s = completed_s / completed;
  const double left_s = std::max(per_step_s - current_s, 0.0) +
                        per_step_s * double(progress.max_steps - completed - 1);
  return head + format_duration(so_far_s) + " so far, at most about " + format_duration(left_s) +
         " left";
}

std::function<void(const LoopProgress&)> loop_progress_display(StatusLine& status) {
  struct Clocks {
    std::optional<StatusLine::Clock::time_point> began;
    StatusLine::Clock::time_point last_step_end;
  };
  auto clocks = std::make_shared<Clocks>();
  return [&status, clocks](const LoopProgress& progress) {
    const auto now = StatusLine::Clock::now();
    if (!clocks->began) clocks->began = clocks->last_step_end = now;
    if (progress.refits_done >= progress.refits) clocks->last_step_end = now;
    const auto seconds = [](auto d) { return std::chrono::duration<double>(d).count(); };
    status.update(loop_progress_text(progress, seconds(clocks->last_step_end - *clocks->began),
                                     seconds(now - clocks->last_step_end)),
                  now, progress.refits_done == 0);
  };
}

namespace {

// Draws text(elapsed_s) on `status`, the time taken from the report that began the stage.
class StageClock {
 public:
  explicit StageClock(StatusLine& status) : status_(status) {}
  template <typename Text>
  void report(bool begins_stage, Text&& text) {
    const auto now = StatusLine::Clock::now();
    if (begins_stage) began_ = now;
    status_.update(text(std::chrono::duration<double>(now - began_).count()), now, begins_stage);
  }

 private:
  StatusLine& status_;
  StatusLine::Clock::time_point began_ = StatusLine::Clock::now();
};

}  // namespace

std::function<void(const FitProgress&)> fit_progress_display(StatusLine& status) {
  auto clock = std::make_shared<StageClock>(status);
  return [clock](const FitProgress& progress) {
    clock->report(progress.done == 0,
                  [&](double elapsed_s) { return fit_progress_text(progress, elapsed_s); });
  };
}

std::function<void(int done, int total)> count_progress_display(StatusLine& status,
                                                                std::string what,
                                                                std::string unit) {
  auto clock = std::make_shared<StageClock>(status);
  return [clock, what = std::move(what), unit = std::move(unit)](int done, int total) {
    clock->report(done == 0, [&](double elapsed_s) {
      return what + ": " + std::to_string(done) + " of " + std::to_string(total) + " " + unit +
             ", " + progress_time_text(done, total, elapsed_s);
    });
  };
}

}  // namespace doorbench::app
