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

}  // namespace doorbench
