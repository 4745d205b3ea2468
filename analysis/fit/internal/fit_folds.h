#pragma once
// The window fit's solve and the refits without a subset of the strokes (analysis/fit/ only;
// fit_folds.cpp, used by fitting.cpp): the cross-validation's folds and the global stage's
// subset refits are the same computation. Pure functions of their arguments; subset_refits
// runs its refits on threads of its own (FitOptions::num_threads), joined before it returns,
// and its result does not depend on how many.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/fit/fit_problem.h"
#include "analysis/fit/fitting.h"

namespace doorbench::fit_detail {

// The window problem of a fit: its windows (cut at the end stops), disjoint with estimated
// start states when the options estimate them.
ProblemKind window_fit_kind(const FitOptions& options, const DoorModel& model);

// The window fit from the problem's x and z: coarse (one RK4 step per sample) then fine.
// Leaves the result in `problem` (whose kind is the fine one); `on_iteration` gets the
// iterations of both passes together.
WindowProblem::Outcome solve_coarse_to_fine(WindowProblem& problem, const DoorModel& model,
                                            const PreparedData& data, const ParameterMap& map,
                                            const FitOptions& options, const FitWeights& weights,
                                            int max_iterations,
                                            const std::function<void(int)>& on_iteration = {});

// One subset's refit: its strokes left out, the rest refitted from the fit's optimum (window
// states from the measured ones, coarse pass first, at most held_out_max_iterations), and
// measured on the strokes it left out with its own parameters.
struct FoldOutcome {
  bool refitted = false;  // false: no window, or the solver failed (note says which)
  std::string note;
  std::optional<DoorModel> model;
  FoldFit fit;
  std::vector<int> held;  // indices into data.strokes
  FitMetrics held_out;    // on the held strokes
};

// The refits without each subset of `subsets` (stroke s in subset s mod subsets), each from
// the fitted optimum x (scaled free values of `map`), in subset order; progress reported as
// `stage` when the options report.
std::vector<FoldOutcome> subset_refits(const DoorModel& fitted, const PreparedData& data,
                                       const ParameterMap& map, const std::vector<double>& x,
                                       const FitOptions& options, const FitWeights& weights,
                                       int subsets, FitProgress::Stage stage);

// Held-out metrics from the fold refits: each stroke measured with the refit that left it
// out. Appends the refits' notes and one FoldFit per refit.
FitMetrics held_out_metrics(const std::vector<FoldOutcome>& outcomes, const PreparedData& data,
                            const FitOptions& options, std::vector<std::string>& notes,
                            std::vector<FoldFit>& fold_fits);

}  // namespace doorbench::fit_detail
