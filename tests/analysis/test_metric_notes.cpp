// The report line that explains a FIT% near 100 beside a large max |omega error|: its
// numbers are the metrics' own, and FIT% follows from the two it names.
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

// FIT% below 0, or held out far below fitted: a warning that says what it means.
TEST_CASE("a negative or far lower held-out FIT% is warned about in words", "[fit][report]") {
  // omega one period of a sine (mean 0); the model's omega `scale` times it too small, so
  // FIT% = 100 (1 - scale).
  auto metrics_with = [](double scale) {
    FitMetrics metrics;
    for (int i = 0; i < 1000; ++i) {
      const double omega = std::sin(2.0 * 3.141592653589793 * i / 1000.0);
      metrics.window.add(omega, omega * (1.0 - scale), i * 0.01);
    }
    return metrics;
  };
  const FitMetrics good = metrics_with(0.05);  // FIT% 95
  const FitMetrics fair = metrics_with(0.6);   // FIT% 40
  const FitMetrics bad = metrics_with(1.25);   // FIT% -25
  REQUIRE(good.window.fit_percent() == Approx(95.0));
  REQUIRE(bad.window.fit_percent() == Approx(-25.0));
  CHECK(fit_percent_warnings(good, nullptr).empty());
  CHECK(fit_percent_warnings(good, &good).empty());
  CHECK(fit_percent_warnings(bad, nullptr) ==
        "warning: FIT% -25.0% is below 0: on the fitted strokes the model predicts omega worse "
        "than omega's mean (a constant) would; the fit is not usable as it is (check the "
        "strokes, the start values and the model's effects).\n");
  CHECK(fit_percent_warnings(good, &bad) ==
        "warning: held-out FIT% -25.0% is below 0: on strokes it was not fitted to, the model "
        "predicts omega worse than omega's mean would; it does not generalize.\n");
  CHECK(fit_percent_warnings(good, &fair) ==
        "warning: held-out FIT% 40.0% is 55.0 points below the fitted 95.0%: the model describes "
        "the strokes it was fitted to much better than new ones (overfitting, or held-out "
        "strokes of another kind).\n");
  // Within kHeldOutFitGap_points: no warning.
  const FitMetrics fair_held = metrics_with(0.75);  // FIT% 25: 15 points below
  CHECK(fit_percent_warnings(fair, &fair_held).empty());
}
