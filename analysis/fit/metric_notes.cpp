#include "analysis/fit/metric_notes.h"

#include <algorithm>
#include <cmath>

#include "core/number_format.h"

namespace doorbench {

namespace {

std::string three_digits(double value) {
  return printf_text("%.3g", value);
}

}  // namespace

std::string fit_and_max_error_note(const FitMetrics& metrics) {
  const ErrorStats& w = metrics.window;
  const ErrorStats& r = metrics.replay;
  if (w.count == 0 || r.count == 0 || !std::isfinite(w.fit_percent())) return "";
  const double n = double(w.count);
  const double mean = w.sum_measured / n;
  const double spread = std::sqrt(std::max(0.0, w.sum_measured_squared / n - mean * mean));
  return "Why both: FIT% = 100 (1 - RMSE " + three_digits(w.rmse()) + " / spread of omega " +
         three_digits(spread) + " rad/s) is an average over " + std::to_string(w.count) +
         " samples; max |omega error| " + three_digits(r.max_abs_error) +
         " rad/s is the one worst sample of a stroke replayed open-loop (stroke " +
         std::to_string(metrics.worst_replay_stroke_id) + ", at " + three_digits(r.time_of_max_s) +
         " s).\n";
}

std::string fit_percent_warnings(const FitMetrics& fitted, const FitMetrics* held_out) {
  const double fit = fitted.window.fit_percent();
  const double held = held_out ? held_out->window.fit_percent() : std::nan("");
  std::string out;
  if (fit < 0.0) {
    out += printf_text(
        "warning: FIT%% %.1f%% is below 0: on the fitted strokes the model predicts omega worse "
        "than omega's mean (a constant) would; the fit is not usable as it is (check the "
        "strokes, the start values and the model's effects).\n",
        fit);
  }
  if (held < 0.0) {
    out += printf_text(
        "warning: held-out FIT%% %.1f%% is below 0: on strokes it was not fitted to, the model "
        "predicts omega worse than omega's mean would; it does not generalize.\n",
        held);
  } else if (std::isfinite(fit) && fit - held > kHeldOutFitGap_points) {
    out += printf_text(
        "warning: held-out FIT%% %.1f%% is %.1f points below the fitted %.1f%%: the model "
        "describes the strokes it was fitted to much better than new ones (overfitting, or "
        "held-out strokes of another kind).\n",
        held, fit - held, fit);
  }
  return out;
}

}  // namespace doorbench
