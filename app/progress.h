#pragma once
// Progress with an estimate of the time left, for the long verbs (fit, loop, spec; issue
// 21): pure formatting of a count done of a total and the time it took, and a status line
// on stderr that is redrawn in place on a terminal and written as plain lines (at most one
// every few seconds) when stderr is a file or a pipe. --quiet silences it as it does every
// stderr line (main.cpp swaps std::cerr's buffer for one that drops).
//
// The estimate is a linear extrapolation: the time so far times what is left over what is
// done. A total that is a bound (a solver's max_iterations, a loop's max_steps: the work may
// stop earlier) makes the estimate a bound too, and the text says "at most".
#include <chrono>
#include <functional>
#include <iosfwd>
#include <mutex>
#include <string>

#include "analysis/fit/fitting.h"
#include "analysis/loop/residual_loop.h"

namespace doorbench::app {

// "0 s", "42 s", "1 min 05 s", "2 h 03 min": whole seconds (rounded) below an hour, whole
// minutes (rounded) from an hour on. Negative or not finite: "? s".
std::string format_duration(double seconds);

// Seconds left by linear extrapolation, elapsed_s · (total − done) / done; NaN when
// nothing is done yet (done <= 0) or total <= 0; 0 when done >= total.
double time_left_s(double done, double total, double elapsed_s);

// The time part of a progress line:
//   done <= 0:        "3 s so far, time left not known yet"
//   done >= total:    "done in 40 s"
//   else:             "12 s so far, about 28 s left" ("at most about 28 s left" when
//                     `total_is_bound`)
std::string progress_time_text(double done, double total, double elapsed_s,
                               bool total_is_bound = false);

// Whether stderr is a terminal (isatty).
bool stderr_is_terminal();

// The width of the terminal on stderr in columns (TIOCGWINSZ); 0 when not known.
int stderr_terminal_columns();

// A status line that updates. On a terminal each update redraws it in place ("\r", the text,
// ANSI erase to the end of the line), at most every 0.1 s; off a terminal an update is a
// plain line when it is the first since the last permanent line or plain_interval_s has
// passed since the previous one. Permanent lines (line()) go between updates. All calls
// may come from several threads (a mutex orders them); not for real-time paths.
class StatusLine {
 public:
  using Clock = std::chrono::steady_clock;
  // `columns`: the terminal's width; a longer text is cut to columns − 1 characters on
  // screen, since a line that wraps cannot be redrawn in place (0: never cut).
  StatusLine(std::ostream& out, bool terminal, double plain_interval_s = 5.0, int columns = 0);
  ~StatusLine();
  StatusLine(const StatusLine&) = delete;
  StatusLine& operator=(const StatusLine&) = delete;

  // `new_stage`: the text begins a stage (a fit's folds after its iterations, a loop's next
  // step); off a terminal it is written at once, after the previous stage's last text if
  // that was held back, so that the plain log shows where each stage ended.
  void update(const std::string& text, bool new_stage = false) {
    update(text, Clock::now(), new_stage);
  }
  void update(const std::string& text, Clock::time_point now, bool new_stage = false);
  // A line that stays (a stage, a verdict): the status line is cleared and the line written;
  // the next update draws the status again (its old text would be stale).
  void line(const std::string& text);
  // Ends the status: on a terminal its last text stays, with a newline; off a terminal the
  // last update is written if it was held back. Called by the destructor.
  void finish();

 private:
  void draw();
  void clear();

  std::ostream& out_;
  const bool terminal_;
  const double plain_interval_s_;
  const int columns_;
  std::mutex mutex_;
  std::string text_;            // the latest update
  bool drawn_ = false;          // terminal: text_ is on screen; plain: text_ was written
  bool on_screen_ = false;      // terminal: a status line is on the last line
  bool printed_plain_ = false;  // plain: a status line since the last permanent line
  Clock::time_point last_draw_{};
};

// A fit's stage for the status line, `elapsed_s` since the stage began:
//   "window fit: iteration 12 of at most 100, 3 s so far, at most about 22 s left"
//   "cross-validation: 2 of 4 folds refitted, 8 s so far, about 8 s left"
//   "global search: polishing the start as given: iteration 12 of at most 100, 3 s so far, at
//   most about 22 s left"
std::string fit_progress_text(const FitProgress& progress, double elapsed_s);

// A loop's steps for the status line. `completed_s`: from the first step's start (its refits
// known) to the end of the last step whose refits are all done (0 while step 1 runs);
// `current_s`: since then. The refits of a step run at once and the step ends with the
// slowest, so refits done say little about the time: the estimate is per step, the mean of the
// completed steps for what the current step has left and for each further one up to
// max_steps. The loop may stop earlier (a bound: "at most about"); a later step can take
// longer than the mean of those before (more effects, costlier refits).
//   "loop step 2 of at most 4: 1 of 2 refits done, 25 s so far, at most about 55 s left"
//   "loop step 1 of at most 4: 1 of 3 refits done, 9 s so far, time left known after step 1"
std::string loop_progress_text(const LoopProgress& progress, double completed_s, double current_s);

// FitOptions::progress drawing fit_progress_text on `status`, each stage timed from its
// report of 0 done. `status` must outlive the fit.
std::function<void(const FitProgress&)> fit_progress_display(StatusLine& status);

// A count's progress drawn on `status`: "WHAT: DONE of TOTAL UNIT, " and progress_time_text,
// timed from the last report with done == 0 (which begins a stage). `status` must outlive it.
// For MonteCarloOptions::progress (spec's "tolerance Monte Carlo", "samples").
std::function<void(int done, int total)> count_progress_display(StatusLine& status,
                                                                std::string what, std::string unit);

// LoopOptions::step_progress drawing loop_progress_text on `status`, the steps timed from the
// first report. `status` must outlive the loop.
std::function<void(const LoopProgress&)> loop_progress_display(StatusLine& status);

}  // namespace doorbench::app
