#pragma once
// What would determine a parameter the data leave undetermined or on a bound (analysis/fit/
// only; fit_determine.cpp, used by fitting.cpp; docs/fitting.md, "What would determine it").
// Strokes of a few kinds are simulated with the fitted door (slow openings and closings, a
// full-range opening and closing, a latch crossing, impulses at given angles left to coast),
// their windows' information on the free parameters (JᵀJ, window states eliminated) is added
// to the fit's, and each parameter's classical standard uncertainty with that kind added is
// compared with its own now. Pure function of its arguments; runs on the caller's thread
// with the fit's evaluation threads. Throws StopRequested when options.stop_requested asks,
// between kinds.
#include <Eigen/Core>
#include <vector>

#include "analysis/fit/fit_problem.h"
#include "analysis/fit/fitting.h"

namespace doorbench::fit_detail {

// What the fit that was kept hands the computation.
struct DeterminingInput {
  const DoorModel& fitted;             // the fitted door, which simulates the candidate strokes
  const PreparedData& data;            // the recording: its sample interval is the strokes'
  const ParameterMap& map;             // the fit's free parameters
  const std::vector<double>& x;        // their fitted values, scaled
  const ProblemKind& kind;             // the window problem the fit solved
  const FitWeights& weights;           // its weights (priors included in `information` already)
  const Eigen::MatrixXd& information;  // the fit's H at x (solver units)
  double residual_variance;            // its σ² (1 when not finite and positive)
};

// For each free parameter k of `positions` (indices into x, in increasing order): a row of
// FitSummary::determining (parameter, relative_now and kinds; `undetermined` and `at_bound`
// are left to the caller). Each classical uncertainty is multiplied by `inflation[r]` (the
// fit's window-robust over classical ratio for that parameter), so that "now" is the fit's own
// u/|value|. A kind is `determines` when its relative uncertainty is finite and at most
// options.undetermined_relative_uncertainty. A kind whose strokes the door cannot simulate,
// or which give no window, is left out of every row.
std::vector<DeterminingStrokes> what_would_determine(const DeterminingInput& input,
                                                     const FitOptions& options,
                                                     const std::vector<int>& positions,
                                                     const std::vector<double>& inflation);

}  // namespace doorbench::fit_detail
