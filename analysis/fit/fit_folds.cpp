// The window fit's solve and the refits without a subset of the strokes
// (internal/fit_folds.h; docs/fitting.md, "Held out" and "The global stage").
#include "analysis/fit/internal/fit_folds.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "core/numbers.h"
#include "core/parallel.h"

namespace doorbench::fit_detail {

ProblemKind window_fit_kind(const FitOptions& options, const DoorModel& model) {
  ProblemKind kind;
  kind.windows = metric_window_options(options, model);
  kind.windows.disjoint = options.estimate_window_states;
  kind.estimate_start_states = options.estimate_window_states;
  return kind;
}

// The window fit from the problem's x and z: coarse (one RK4 step per sample) then fine.
// Leaves the result in `problem` (whose kind is the fine one).
WindowProblem::Outcome solve_coarse_to_fine(WindowProblem& problem, const DoorModel& model,
                                            const PreparedData& data, const ParameterMap& map,
                                            const FitOptions& options, const FitWeights& weights,
                                            int max_iterations,
                                            const std::function<void(int)>& on_iteration) {
  int used = 0;
  SolverSettings settings = solver_settings(options);
  if (on_iteration) {
    settings.on_iteration = [&on_iteration, &used](int iterations) {
      on_iteration(used + iterations);
    };
  }
  double initial_cost = kNaN;
  // The coarse stage leaves the fine one at least one of the iterations, so that both together
  // take at most max_iterations.
  if (options.coarse_first && options.substeps_per_sample > 1 && max_iterations > 1) {
    ProblemKind coarse_kind = window_fit_kind(options, model);
    coarse_kind.windows.substeps_per_sample = 1;
    WindowProblem coarse(model, data, map, coarse_kind, weights, problem.x());
    coarse.z() = problem.z();
    const WindowProblem::Outcome outcome =
        coarse.solve(settings, max_iterations - 1,
                     options.coarse_tolerance_factor * options.uncertainty_tolerance);
    used = outcome.iterations;
    initial_cost = outcome.initial_cost;
    if (outcome.usable) {
      problem.x() = coarse.x();
      problem.z() = coarse.z();
    }
  }
  WindowProblem::Outcome outcome =
      problem.solve(settings, std::max(1, max_iterations - used), options.uncertainty_tolerance);
  outcome.iterations += used;
  if (used > 0) outcome.initial_cost = initial_cost;
  return outcome;
}

namespace {

PreparedData training_data(const PreparedData& data, int folds, int fold, std::vector<int>& held) {
  PreparedData training;
  training.source = data.source;
  training.handle_radius_m = data.handle_radius_m;
  training.sample_rate_hz = data.sample_rate_hz;
  training.rate_noise_rad_s = data.rate_noise_rad_s;
  training.angle_noise_rad = data.angle_noise_rad;
  const int stroke_count = static_cast<int>(data.strokes.size());
  for (int s = 0; s < stroke_count; ++s) {
    if (s % folds == fold) {
      if (data.strokes[s].size() >= 2) held.push_back(s);
    } else {
      training.strokes.push_back(data.strokes[s]);
    }
  }
  return training;
}

std::vector<std::string> at_bound_names(const DoorModel& model,
                                        const std::vector<int>& free_index) {
  std::vector<std::string> names;
  const auto bounds = model.parameter_bounds();
  for (int index : free_index) {
    const double value = model.parameter_values()[index];
    const double width = bounds[index].upper - bounds[index].lower;
    if (std::abs(value - bounds[index].lower) <= 1e-6 * width ||
        std::abs(bounds[index].upper - value) <= 1e-6 * width) {
      names.push_back(model.parameter_name(index));
    }
  }
  return names;
}

FoldOutcome refit_fold(const DoorModel& fitted, const PreparedData& data, const ParameterMap& map,
                       const std::vector<double>& x, const FitOptions& options,
                       const FitWeights& weights, int folds, int fold) {
  FoldOutcome out;
  const PreparedData training = training_data(data, folds, fold, out.held);
  WindowProblem problem(fitted, training, map, window_fit_kind(options, fitted), weights, x);
  if (problem.windows().empty()) return out;
  // Coarse pass first, window states from the measured states: see docs/fitting.md
  // ("Held out") for why the folds do not start from the full fit's window states.
  const WindowProblem::Outcome outcome = solve_coarse_to_fine(
      problem, fitted, training, map, options, weights, options.held_out_max_iterations);
  if (!outcome.usable) {
    out.note =
        "cross-validation fold " + std::to_string(fold + 1) + " failed: " + outcome.termination;
    return out;
  }
  out.refitted = true;
  out.model = fitted.with_parameter_values(map.values(problem.x().data()));
  const WindowOptions windows = metric_window_options(options, fitted);
  out.held_out = compute_fit_metrics(*out.model, data, windows, out.held);
  for (int s : out.held) out.fit.held_out_strokes.push_back(data.strokes[s].id);
  out.fit.converged = outcome.converged;
  out.fit.termination = outcome.termination;
  out.fit.iterations = outcome.iterations;
  out.fit.fitted_rmse_rad_s = compute_window_errors(*out.model, training, windows).rmse();
  out.fit.held_out_rmse_rad_s = out.held_out.window.rmse();
  out.fit.at_bound = at_bound_names(*out.model, map.free_index);
  return out;
}

}  // namespace

// The refits without each subset of `subsets` (stroke s in subset s mod subsets), each from
// the fitted optimum x: the cross-validation's folds and the global stage's subset refits
// alike. They are independent and each deterministic, so they run at once (up to
// fit_thread_count) and are kept in subset order: the result is the same as one after
// another. Reported as `stage`.
std::vector<FoldOutcome> subset_refits(const DoorModel& fitted, const PreparedData& data,
                                       const ParameterMap& map, const std::vector<double>& x,
                                       const FitOptions& options, const FitWeights& weights,
                                       int subsets, FitProgress::Stage stage) {
  ParameterMap fold_map = map;
  fold_map.base_values.assign(fitted.parameter_values().begin(), fitted.parameter_values().end());
  std::vector<FoldOutcome> outcomes(static_cast<std::size_t>(subsets));
  std::mutex progress_mutex;
  int done = 0;
  if (options.progress) options.progress({stage, 0, subsets});
  parallel_for(subsets, fit_thread_count(options), [&](int subset) {
    outcomes[static_cast<std::size_t>(subset)] =
        refit_fold(fitted, data, fold_map, x, options, weights, subsets, subset);
    if (options.progress) {
      const std::lock_guard lock(progress_mutex);
      options.progress({stage, ++done, subsets});
    }
  });
  return outcomes;
}

// Held-out metrics from the fold refits: each stroke measured with the refit that left it
// out (subset_refits with stroke s in fold s mod k).
FitMetrics held_out_metrics(const std::vector<FoldOutcome>& outcomes, const PreparedData& data,
                            const FitOptions& options, std::vector<std::string>& notes,
                            std::vector<FoldFit>& fold_fits) {
  const int stroke_count = static_cast<int>(data.strokes.size());
  std::vector<StrokeFitMetrics> per_stroke(stroke_count);
  std::vector<char> have(stroke_count, 0);
  for (const FoldOutcome& outcome : outcomes) {
    if (!outcome.note.empty()) notes.push_back(outcome.note);
    if (!outcome.refitted) continue;
    fold_fits.push_back(outcome.fit);
    for (std::size_t i = 0; i < outcome.held.size() && i < outcome.held_out.strokes.size(); ++i) {
      per_stroke[outcome.held[i]] = outcome.held_out.strokes[i];
      have[outcome.held[i]] = 1;
    }
  }
  int unconverged = 0;
  for (const FoldFit& fold_fit : fold_fits) unconverged += fold_fit.converged ? 0 : 1;
  if (unconverged > 0) {
    notes.push_back(std::to_string(unconverged) + " of " + std::to_string(fold_fits.size()) +
                    " cross-validation folds stopped at held_out_max_iterations (" +
                    std::to_string(options.held_out_max_iterations) +
                    ") before converging: the held-out figures are where they stopped");
  }
  FitMetrics held_out;
  for (int s = 0; s < stroke_count; ++s) {
    if (have[s]) held_out.add(per_stroke[s]);
  }
  return held_out;
}

}  // namespace doorbench::fit_detail
