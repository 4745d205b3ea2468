#pragma once
// Plain-language notes that go beside the fit metrics in reports, so that two numbers that
// seem to disagree are read right.
//
// Pure functions: safe from any thread.
#include <string>

#include "analysis/fit/fit_metrics.h"

namespace doorbench {

// One line saying why a FIT% near 100 and a large max |omega error| are both true: FIT%
// compares the windows' RMSE with the spread of omega over every sample (an average), the
// largest error is one sample of one stroke replayed open-loop (where, when). Numbers from
// `metrics` (fitted.window for FIT%, fitted.replay for the largest error); "" when either
// is not defined (no samples, no successful replay).
std::string fit_and_max_error_note(const FitMetrics& metrics);

// A held-out window FIT% this many points below the fitted one is called far below.
constexpr double kHeldOutFitGap_points = 20.0;

// Warning lines (each "warning: ...\n") for a window FIT% that says the model is not usable
// as it is: a negative FIT% on the fitted strokes (the windows predict omega worse than its
// mean, a constant, would), a negative held-out FIT%, or a held-out FIT% more than
// kHeldOutFitGap_points below the fitted one (it describes the strokes it was fitted to,
// not new ones). "" when none applies or FIT% is not defined. `held_out` may be null.
std::string fit_percent_warnings(const FitMetrics& fitted, const FitMetrics* held_out);

}  // namespace doorbench
