// The report line that explains a FIT% near 100 beside a large max |omega error| (issue 21,
// item 8): its numbers are the metrics' own, and FIT% follows from the two it names.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "analysis/fit/metric_notes.h"

using namespace doorbench;

TEST_CASE("the FIT%/max-error note names the average and the one worst sample", "[fit][report]") {
  FitMetrics metrics;
  // Windows: omega a sine of amplitude 2 rad/s, a small error everywhere.
  for (int i = 0; i < 1000; ++i) {
    const double t = i * 0.01;
    const double omega = 2.0 * std::sin(t);
    metrics.window.add(omega, omega - 0.01, t);
  }
  // Replay: one sample 2.15 rad/s off at 7.5 s.
  metrics.replay.add(1.0, 1.0, 7.0);
  metrics.replay.add(1.0, -1.15, 7.5);
  metrics.worst_replay_stroke_id = 4;
  const double fit = metrics.window.fit_percent();
  REQUIRE(fit > 99.0);
  const std::string note = fit_and_max_error_note(metrics);
  INFO(note);
  const double spread = std::sqrt(metrics.window.sum_measured_squared / 1000.0 -
                                  std::pow(metrics.window.sum_measured / 1000.0, 2));
  char expected[400];
  std::snprintf(expected, sizeof expected,
                "Why both: FIT%% = 100 (1 - RMSE 0.01 / spread of omega %.3g rad/s) is an average "
                "over 1000 samples; max |omega error| 2.15 rad/s is the one worst sample of a "
                "stroke replayed open-loop (stroke 4, at 7.5 s).\n",
                spread);
  CHECK(note == expected);
  // FIT% is what the note's two numbers give.
  CHECK(fit == Approx(100.0 * (1.0 - 0.01 / spread)).epsilon(1e-9));
  // Without a replay there is nothing to explain.
  metrics.replay = {};
  CHECK(fit_and_max_error_note(metrics).empty());
}
