// Progress with the time left on the long verbs (app/progress.h): the
// estimate's arithmetic and words, the status line on a terminal and off it, and fit on a
// pseudo-terminal, into a file and with --quiet.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <regex>
#include <sstream>
#include <string>

#include "app/progress.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/run_on_terminal.h"

namespace {

using doorbench::FitProgress;
using doorbench::LoopProgress;
using doorbench::app::StatusLine;
using namespace std::chrono_literals;

}  // namespace

TEST_CASE("progress: durations in s, min and h", "[progress]") {
  using doorbench::app::format_duration;
  CHECK(format_duration(0.0) == "0 s");
  CHECK(format_duration(0.4) == "0 s");
  CHECK(format_duration(42.4) == "42 s");
  CHECK(format_duration(59.4) == "59 s");
  CHECK(format_duration(59.6) == "1 min 00 s");
  CHECK(format_duration(65.0) == "1 min 05 s");
  CHECK(format_duration(3599.4) == "59 min 59 s");
  CHECK(format_duration(3600.0) == "1 h 00 min");
  CHECK(format_duration(7380.0) == "2 h 03 min");
  CHECK(format_duration(-1.0) == "? s");
  CHECK(format_duration(std::nan("")) == "? s");
}

TEST_CASE("progress: the time left by linear extrapolation", "[progress]") {
  using doorbench::app::time_left_s;
  CHECK(time_left_s(1, 4, 10.0) == Approx(30.0));
  CHECK(time_left_s(3, 10, 12.0) == Approx(28.0));
  CHECK(time_left_s(0.5, 2, 3.0) == Approx(9.0));
  CHECK(time_left_s(4, 4, 10.0) == 0.0);
  CHECK(time_left_s(5, 4, 10.0) == 0.0);
  CHECK(std::isnan(time_left_s(0, 4, 10.0)));
  CHECK(std::isnan(time_left_s(1, 0, 10.0)));
}

TEST_CASE("progress: the time part of a progress line", "[progress]") {
  using doorbench::app::progress_time_text;
  CHECK(progress_time_text(0, 10, 3.0) == "3 s so far, time left not known yet");
  CHECK(progress_time_text(3, 10, 12.0) == "12 s so far, about 28 s left");
  CHECK(progress_time_text(12, 100, 3.0, true) == "3 s so far, at most about 22 s left");
  CHECK(progress_time_text(1, 100, 2.0) == "2 s so far, about 3 min 18 s left");
  CHECK(progress_time_text(10, 10, 40.0) == "done in 40 s");
}

TEST_CASE("progress: the fit's and the loop's lines", "[progress]") {
  using doorbench::app::fit_progress_text;
  using doorbench::app::loop_progress_text;
  CHECK(fit_progress_text({FitProgress::Stage::kWindows, 12, 100}, 3.0) ==
        "window fit: iteration 12 of at most 100, 3 s so far, at most about 22 s left");
  CHECK(fit_progress_text({FitProgress::Stage::kFolds, 2, 4}, 8.0) ==
        "cross-validation: 2 of 4 folds refitted, 8 s so far, about 8 s left");
  CHECK(fit_progress_text({FitProgress::Stage::kFolds, 0, 4}, 1.0) ==
        "cross-validation: 0 of 4 folds refitted, 1 s so far, time left not known yet");
  CHECK(fit_progress_text({FitProgress::Stage::kSearch, 1, 4}, 2.0) ==
        "global search: 1 of 4 subset refits, 2 s so far, about 6 s left");
  CHECK(fit_progress_text({FitProgress::Stage::kSearch, 1, 4, 2}, 2.0) ==
        "global search, round 2: 1 of 4 subset refits, 2 s so far, about 6 s left");
  CHECK(fit_progress_text({FitProgress::Stage::kHops, 3, 6}, 9.0) ==
        "global search: 3 of 6 basin hops polished, 9 s so far, about 9 s left");
  CHECK(fit_progress_text({FitProgress::Stage::kPolish, 12, 100, 1, "polishing the start as given"},
                          3.0) ==
        "global search: polishing the start as given: iteration 12 of at most 100, 3 s so far, "
        "at most about 22 s left");
  // The loop: per completed step.
  struct LoopCase {
    LoopProgress progress;
    double completed_s, current_s;
    const char* expected;
  };
  const LoopCase cases[] = {
      // Step 1 done in 20 s, step 2 under way for 5 s: 15 s more for it, 20 s for each of
      // steps 3 and 4.
      {{2, 4, 1, 2},
       20.0,
       5.0,
       "loop step 2 of at most 4: 1 of 2 refits done, 25 s so far, at most about 55 s left"},
      // Refits done within a step do not count (they run at once; the slowest ends it).
      {{1, 4, 2, 3},
       0.0,
       12.0,
       "loop step 1 of at most 4: 2 of 3 refits done, 12 s so far, time left known after step 1"},
      {{1, 4, 0, 3},
       0.0,
       0.0,
       "loop step 1 of at most 4: 0 of 3 refits done, 0 s so far, time left known after step 1"},
      // Step 2's refits all done at 40 s: 20 s a step, two more at most.
      {{2, 4, 2, 2},
       40.0,
       0.0,
       "loop step 2 of at most 4: 2 of 2 refits done, 40 s so far, at most about 40 s left"},
      // A step longer than the mean so far: only the steps after it are left.
      {{2, 4, 0, 2},
       10.0,
       30.0,
       "loop step 2 of at most 4: 0 of 2 refits done, 40 s so far, at most about 20 s left"},
      {{4, 4, 1, 1}, 80.0, 0.0, "loop step 4 of at most 4: 1 of 1 refits done, done in 1 min 20 s"},
  };
  for (const LoopCase& c : cases) {
    CHECK(loop_progress_text(c.progress, c.completed_s, c.current_s) == c.expected);
  }
}

TEST_CASE("progress: on a terminal the status line is redrawn in place", "[progress]") {
  std::ostringstream out;
  const auto t0 = StatusLine::Clock::now();
  {
    StatusLine status(out, /*terminal=*/true);
    status.update("a", t0);
    CHECK(out.str() == "\ra\x1b[K");
    status.update("b", t0 + 50ms);  // held back: at most one redraw per 0.1 s
    CHECK(out.str() == "\ra\x1b[K");
    status.update("c", t0 + 150ms);
    CHECK(out.str() == "\ra\x1b[K\rc\x1b[K");
    status.line("stage two");
    CHECK(out.str() == "\ra\x1b[K\rc\x1b[K\r\x1b[Kstage two\n");
    out.str("");
    status.update("d", t0 + 160ms);  // the first after a line is drawn at once
    status.update("e", t0 + 170ms);
    CHECK(out.str() == "\rd\x1b[K");
  }
  // The destructor finishes: the held-back last text stays, with a newline.
  CHECK(out.str() == "\rd\x1b[K\re\x1b[K\n");
}

TEST_CASE("progress: on a terminal a status wider than it is cut so that it redraws in place",
          "[progress]") {
  std::ostringstream out;
  const auto t0 = StatusLine::Clock::now();
  {
    StatusLine status(out, /*terminal=*/true, 5.0, /*columns=*/8);
    status.update("0123456789", t0);
    CHECK(out.str() == "\r0123456\x1b[K");  // 7 characters: the cursor stays on the line
    out.str("");
    status.update("ab\u00b0cdefgh", t0 + 150ms);  // a 2-byte character counts as one
    CHECK(out.str() == "\rab\u00b0cdef\x1b[K");
    out.str("");
    status.update("short", t0 + 300ms);
    CHECK(out.str() == "\rshort\x1b[K");
    out.str("");
  }
  CHECK(out.str() == "\n");
}

TEST_CASE("progress: off a terminal the status is plain lines, a few", "[progress]") {
  std::ostringstream out;
  const auto t0 = StatusLine::Clock::now();
  StatusLine status(out, /*terminal=*/false, 5.0);
  status.update("a", t0);
  status.update("b", t0 + 1s);  // within 5 s of the previous line: held back
  status.update("c", t0 + 6s);
  CHECK(out.str() == "a\nc\n");
  status.update("d", t0 + 7s);
  status.update("e", t0 + 8s, /*new_stage=*/true);  // the previous stage's last, then it
  CHECK(out.str() == "a\nc\nd\ne\n");
  status.update("f", t0 + 9s);
  status.line("stage three");  // the held-back status first
  CHECK(out.str() == "a\nc\nd\ne\nf\nstage three\n");
  status.update("g", t0 + 10s);
  status.update("h", t0 + 11s);
  status.finish();
  status.finish();  // once only
  CHECK(out.str() == "a\nc\nd\ne\nf\nstage three\ng\nh\n");
  CHECK(out.str().find('\r') == std::string::npos);
}

TEST_CASE("fit shows its progress with the time left: on a terminal, in a file, --quiet",
          "[progress][cli]") {
  const doorbench::testing::TempDir dir("progress_cli");
  // 40 s at 1 kHz: a fit of a few seconds, so that the status line is redrawn.
  const std::string csv = doorbench::testing::simulate_open_close_csv(dir, "run.csv", 40, 1000);
  REQUIRE_FALSE(csv.empty());

  SECTION("on a terminal: one status line, redrawn, with the time left") {
    int status = -1;
    const std::string output = doorbench::testing::run_doorbench_terminal_output(
        "fit '" + csv + "' --hops 2 --out '" + (dir / "t").string() + "'", status);
    INFO(output);
    REQUIRE(status == 0);
    CHECK(output.find("fitting the sensory model (with 4-fold cross-validation)") !=
          std::string::npos);
    // Redrawn in place: carriage return, the text, erase to the end of the line.
    const std::regex redrawn(
        "\rwindow fit: iteration [1-9][0-9]* of at most 100, [0-9]+ s so far, at most about "
        "[0-9]+ (s|min [0-9]+ s) left\x1b\\[K");
    CHECK(std::regex_search(output, redrawn));
    // The global stage's subset refits (4 subsets of 2 strokes: 2), which the 4-fold
    // cross-validation then reuses as its folds, and its basin hops (--hops 2), the fit's last
    // stage with a status (the line is redrawn at most every 100 ms: the subset refits' last count
    // may be passed over).
    CHECK(std::regex_search(output, std::regex("\rglobal search: [12] of 2 subset refits, ")));
    CHECK(output.find("\rglobal search: 2 of 2 basin hops polished, done in ") !=
          std::string::npos);
    CHECK(output.find("cross-validation:") == std::string::npos);
  }
  SECTION("into a file: plain lines") {
    const auto run = doorbench::testing::run_doorbench_shell(
        "fit '" + csv + "' --hops 2 --out '" + (dir / "f").string() + "'", dir);
    INFO(run.err);
    REQUIRE(run.status == 0);
    CHECK(run.err.find('\r') == std::string::npos);
    CHECK(run.err.find('\x1b') == std::string::npos);
    CHECK(run.err.find("\nwindow fit: iteration 0 of at most 100, 0 s so far, time left not "
                       "known yet\n") != std::string::npos);
    // Where the window fit ended, before the global stage's subset refits began.
    const std::regex windows_end(
        "\nwindow fit: iteration [1-9][0-9]* of at most 100, [0-9]+ s so far, at most about "
        "[^\n]* left\nglobal search: 0 of 2 subset refits, ");
    CHECK(std::regex_search(run.err, windows_end));
    CHECK(run.err.find("\nglobal search: 2 of 2 subset refits, done in ") != std::string::npos);
    // The stage's other fits, each named as it begins: the best polished again (at least once),
    // the two fits with softer switches.
    for (const char* fit : {"polish 1 of the best optimum from its own values",
                            "fitting the data-derived start with switches 10 times softer",
                            "fitting the data-derived start with switches 3 times softer"}) {
      INFO(fit);
      CHECK(run.err.find("\nglobal search: " + std::string(fit) +
                         ": iteration 0 of at most 100, ") != std::string::npos);
    }
    CHECK(run.err.find("\nglobal search: 0 of 2 basin hops polished, ") != std::string::npos);
    CHECK(run.err.find("\nglobal search: 2 of 2 basin hops polished, done in ") !=
          std::string::npos);
  }
  SECTION("--quiet: nothing on stderr") {
    const auto run = doorbench::testing::run_doorbench_shell(
        "fit --quiet '" + csv + "' --out '" + (dir / "q").string() + "'", dir);
    CHECK(run.status == 0);
    CHECK(run.err.empty());
    CHECK(run.out.find("Fit of the sensory model") != std::string::npos);
  }
}
