#pragma once
// The global stage (analysis/fit/ only; fit_global.cpp, used by fitting.cpp; docs/fitting.md,
// "The global stage") and what it takes from the fit of one start (fitting.cpp). The functions
// run their fits on threads of their own (FitOptions::num_threads), joined before they return;
// their results do not depend on how many.
#include <Eigen/Dense>
#include <vector>

#include "analysis/fit/fit_problem.h"
#include "analysis/fit/fit_windows.h"
#include "analysis/fit/fitting.h"
#include "analysis/fit/internal/fit_folds.h"

namespace doorbench::fit_detail {

// What a fit leaves for the what-would-determine stage, which runs on the fit that is kept.
struct KeptFit {
  ParameterMap map;
  std::vector<double> x;  // the fitted free values, scaled
  FitWeights weights;
  Eigen::MatrixXd information;  // the window problem's H at x
};

// The fit of one start: set-up, equation-error stage, window fit, statistics and metrics on
// the fitted strokes (no held-out metrics). Throws std::invalid_argument for options or data
// it cannot fit, std::runtime_error when the solve fails, StopRequested when asked to stop.
FitResult fit_once(const DoorModel& start, const PreparedData& data, const FitOptions& options,
                   KeptFit& kept);

// The windows the fit's metrics are computed on.
WindowOptions metric_windows(const FitOptions& options, const DoorModel& model);

// The global stage after the first start's fit `result` (FitOptions::global_search): the other
// starts screened by their window RMSE on every stroke, the promising ones polished, further
// rounds of subset refits (FitOptions::global_rounds) and the hops; the optimum
// options.global_keep names kept in `result` and `kept`. `refits` receives the last round's
// subset refits. True when they were refitted from the kept optimum (the cross-validation may
// reuse them). Throws StopRequested when asked to stop.
bool global_stage(FitResult& result, const DoorModel& start, const PreparedData& data,
                  const FitOptions& options, KeptFit& kept, std::vector<FoldOutcome>& refits);

}  // namespace doorbench::fit_detail
