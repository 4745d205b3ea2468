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

}  // namespace doorbench
