#include "analysis/fit/fitting.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "analysis/fit/fit_problem.h"
#include "analysis/fit/internal/fit_determine.h"
#include "analysis/fit/internal/fit_setup.h"
#include "analysis/model/sensory_model.h"
#include "core/clock.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "core/parallel.h"

namespace doorbench {

using namespace fit_detail;

namespace {

// A robust uncertainty resting on fewer windows than this is flagged in the notes.
constexpr double kFewEffectiveWindows = 10.0;

bool finite_positive(double value) {
  return std::isfinite(value) && value > 0;
}

}  // namespace

std::string FitOptions::validate() const {
  if (!finite_positive(window_s)) return "fit window_s must be > 0";
  if (substeps_per_sample < 1 || substeps_per_sample > 100) {
    return "fit substeps_per_sample must be between 1 and 100";
  }
  if (!std::isfinite(rate_noise_rad_s) || rate_noise_rad_s < 0) {
    return "fit rate_noise_rad_s must be >= 0 (0: the data's)";
  }
  if (!std::isfinite(angle_noise_rad) || angle_noise_rad < 0) {
    return "fit angle_noise_rad must be >= 0 (0: the data's)";
  }
  if (max_objective_power < 1 || max_objective_power > 16) {
    return "fit max_objective_power must be between 1 and 16";
  }
  if (max_iterations < 1) return "fit max_iterations must be >= 1";
  if (!finite_positive(function_tolerance) || !finite_positive(parameter_tolerance) ||
      !finite_positive(gradient_tolerance) || !finite_positive(uncertainty_tolerance) ||
      !finite_positive(coarse_tolerance_factor) ||
      !finite_positive(equation_error_step_tolerance)) {
    return "fit function_tolerance, parameter_tolerance, gradient_tolerance, "
           "uncertainty_tolerance, coarse_tolerance_factor and equation_error_step_tolerance "
           "must be > 0";
  }
  if (num_threads < 0) return "fit num_threads must be >= 0 (0: every hardware thread)";
  if (cross_validation_folds < 0 || cross_validation_folds == 1) {
    return "fit cross_validation_folds must be 0 (none) or >= 2";
  }
  if (held_out_max_iterations < 1) return "fit held_out_max_iterations must be >= 1";
  if (!(correlation_threshold > 0 && correlation_threshold < 1)) {
    return "fit correlation_threshold must lie strictly between 0 and 1";
  }
  if (!finite_positive(undetermined_relative_uncertainty)) {
    return "fit undetermined_relative_uncertainty must be > 0";
  }
  for (const ParameterPrior& prior : priors) {
    if (!std::isfinite(prior.center) || !finite_positive(prior.sigma)) {
      return "fit priors: the prior on '" + prior.parameter +
             "' needs a finite center and a sigma > 0";
    }
  }
  return "";
}

int fit_thread_count(const FitOptions& options) {
  if (options.num_threads > 0) return options.num_threads;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

SolverSettings solver_settings(const FitOptions& options) {
  SolverSettings settings;
  settings.max_iterations = options.max_iterations;
  settings.function_tolerance = options.function_tolerance;
  settings.parameter_tolerance = options.parameter_tolerance;
  settings.gradient_tolerance = options.gradient_tolerance;
  settings.equation_error_step_tolerance = options.equation_error_step_tolerance;
  settings.robust_uncertainty = options.uncertainty == FitOptions::Uncertainty::kWindowRobust;
  settings.threads = fit_thread_count(options);
  settings.stop_requested = options.stop_requested;
  return settings;
}

namespace {

// Free values of a model, scaled.
std::vector<double> scaled_values(const ParameterMap& map, std::span<const double> values) {
  return map.scaled(std::vector<double>(values.begin(), values.end()));
}

WindowOptions metric_windows(const FitOptions& options, const DoorModel& model) {
  return metric_window_options(options, model);
}

ProblemKind window_fit_kind(const FitOptions& options, const DoorModel& model) {
  ProblemKind kind;
  kind.windows = metric_windows(options, model);
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
                                            const std::function<void(int)>& on_iteration = {}) {
  int used = 0;
  SolverSettings settings = solver_settings(options);
  if (on_iteration) {
    settings.on_iteration = [&on_iteration, &used](int iterations) {
      on_iteration(used + iterations);
    };
  }
  double initial_cost = kNaN;
  if (options.coarse_first && options.substeps_per_sample > 1) {
    ProblemKind coarse_kind = window_fit_kind(options, model);
    coarse_kind.windows.substeps_per_sample = 1;
    WindowProblem coarse(model, data, map, coarse_kind, weights, problem.x());
    coarse.z() = problem.z();
    const WindowProblem::Outcome outcome = coarse.solve(
        settings, max_iterations, options.coarse_tolerance_factor * options.uncertainty_tolerance);
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

// One cross-validation fold's refit: its strokes left out, refitted from the full fit.
struct FoldOutcome {
  bool refitted = false;  // false: no window, or the solver failed (note says which)
  std::string note;
  std::optional<DoorModel> model;
  FoldFit fit;
  std::vector<int> held;  // indices into data.strokes
  FitMetrics held_out;    // on the held strokes
};

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
  const WindowOptions windows = metric_windows(options, fitted);
  out.held_out = compute_fit_metrics(*out.model, data, windows, out.held);
  for (int s : out.held) out.fit.held_out_strokes.push_back(data.strokes[s].id);
  out.fit.converged = outcome.converged;
  out.fit.termination = outcome.termination;
  out.fit.iterations = outcome.iterations;
  out.fit.fitted_rmse_rad_s = compute_fit_metrics(*out.model, training, windows).window.rmse();
  out.fit.held_out_rmse_rad_s = out.held_out.window.rmse();
  out.fit.at_bound = at_bound_names(*out.model, map.free_index);
  return out;
}

// Held-out metrics: stroke s is in fold s mod k; each fold is refitted from the full fit
// without its strokes, and its strokes are measured with that refit. The folds are
// independent and each deterministic, so they run at once (up to fit_thread_count) and are
// gathered in fold order: the result is the same as one after another.
FitMetrics cross_validate(const DoorModel& fitted, const PreparedData& data,
                          const ParameterMap& map, const std::vector<double>& x,
                          const FitOptions& options, const FitWeights& weights, int folds,
                          std::vector<std::string>& notes, std::vector<DoorModel>& fold_models,
                          std::vector<FoldFit>& fold_fits) {
  const int stroke_count = static_cast<int>(data.strokes.size());
  ParameterMap fold_map = map;
  fold_map.base_values.assign(fitted.parameter_values().begin(), fitted.parameter_values().end());
  std::vector<FoldOutcome> outcomes(static_cast<std::size_t>(folds));
  std::mutex progress_mutex;
  int folds_done = 0;
  if (options.progress) options.progress({FitProgress::Stage::kFolds, 0, folds});
  parallel_for(folds, fit_thread_count(options), [&](int fold) {
    outcomes[static_cast<std::size_t>(fold)] =
        refit_fold(fitted, data, fold_map, x, options, weights, folds, fold);
    if (options.progress) {
      const std::lock_guard lock(progress_mutex);
      options.progress({FitProgress::Stage::kFolds, ++folds_done, folds});
    }
  });
  std::vector<StrokeFitMetrics> per_stroke(stroke_count);
  std::vector<char> have(stroke_count, 0);
  for (FoldOutcome& outcome : outcomes) {
    if (!outcome.note.empty()) notes.push_back(outcome.note);
    if (!outcome.refitted) continue;
    fold_models.push_back(std::move(*outcome.model));
    fold_fits.push_back(std::move(outcome.fit));
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

}  // namespace

FitMetrics evaluate_model(const DoorModel& model, const PreparedData& data,
                          const FitOptions& options) {
  return compute_fit_metrics(model, data, metric_windows(options, model));
}

namespace {

// A fold must fit every stroke at least this much better (RMSE ratio) to restart from it.
constexpr double kFoldRestartGain = 0.9;

// "stroke 3 (closing), the window from ... (largest |force| there ...)": where a simulation
// was not finite.
std::string describe_window(const WindowProblem& problem, const PreparedData& data, int w) {
  const FitWindow& window = problem.windows()[static_cast<std::size_t>(w)];
  const Stroke& stroke = data.strokes[static_cast<std::size_t>(window.stroke)];
  const auto first = static_cast<std::size_t>(window.first);
  const auto last = first + static_cast<std::size_t>(window.count) - 1;
  double largest_force_N = 0.0;
  for (std::size_t i = first; i <= last; ++i) {
    largest_force_N = std::max(largest_force_N, std::abs(stroke.force_N[i]));
  }
  char text[200];
  std::snprintf(text, sizeof text,
                "stroke %d (%s), the window from %.3f s to %.3f s (largest |force| there %.4g N)",
                stroke.id, stroke.direction == StrokeDirection::kOpening ? "opening" : "closing",
                stroke.time_s[first], stroke.time_s[last], largest_force_N);
  return std::string(text);
}

// Refuses a window problem without enough data or whose start does not simulate.
void check_problem(const WindowProblem& problem, const PreparedData& data, const ParameterMap& map,
                   FitSummary& summary) {
  summary.windows = problem.windows().size();
  summary.window_state_parameters = static_cast<int>(problem.z().size());
  summary.residuals = static_cast<std::size_t>(problem.residual_count());
  if (summary.windows == 0) throw std::invalid_argument("fit: no stroke has 2 samples or more");
  if (static_cast<int>(summary.residuals) <= map.free_count() + summary.window_state_parameters) {
    throw std::invalid_argument("fit: fewer residuals (" + std::to_string(summary.residuals) +
                                ") than parameters to estimate (" +
                                std::to_string(map.free_count() + summary.window_state_parameters) +
                                ")");
  }
  // A fit never runs on non-finite residuals: a start whose simulation blows up is refused
  // with the window that did (the data there, or the start values, are to be checked).
  if (const int w = problem.first_non_finite_window(); w >= 0) {
    throw std::runtime_error("fit: the start model's simulation is not finite in " +
                             describe_window(problem, data, w) +
                             "; check that window's data and the start parameters");
  }
}

// The equation-error stage: moves the problem's x to its result when that simulates.
void equation_error_stage(WindowProblem& problem, const DoorModel& start_model,
                          const PreparedData& data, const ParameterMap& map,
                          const FitOptions& options, const std::vector<double>& x_start,
                          FitSummary& summary) {
  const EquationErrorOutcome equation_error =
      solve_equation_error(start_model, data, map, solver_settings(options), x_start);
  summary.equation_error_iterations = equation_error.iterations;
  summary.equation_error_termination = equation_error.termination;
  if (equation_error.usable) {
    problem.x() = equation_error.x;
    if (const int w = problem.first_non_finite_window(); w >= 0) {
      problem.x() = x_start;  // its result blows up where the start did not
      summary.notes.push_back("the equation-error result's simulation is not finite in " +
                              describe_window(problem, data, w) +
                              "; the windows started from the start values");
    }
  } else {
    summary.notes.push_back("the equation-error stage failed (" + equation_error.termination +
                            "); the windows started from the start values");
  }
}

// The window fit, and the study's objective from there when asked.
void window_stage(WindowProblem& problem, const DoorModel& start, const DoorModel& start_model,
                  const PreparedData& data, const ParameterMap& map, const FitOptions& options,
                  const FitWeights& weights, FitSummary& summary) {
  std::function<void(int)> on_iteration;
  if (options.progress) {
    options.progress({FitProgress::Stage::kWindows, 0, options.max_iterations});
    on_iteration = [&options](int iterations) {
      options.progress({FitProgress::Stage::kWindows, iterations, options.max_iterations});
    };
  }
  const WindowProblem::Outcome outcome = solve_coarse_to_fine(
      problem, start_model, data, map, options, weights, options.max_iterations, on_iteration);
  if (!outcome.usable) throw std::runtime_error("fit: the solver failed: " + outcome.termination);
  summary.converged = outcome.converged;
  summary.termination = outcome.termination;
  summary.iterations = outcome.iterations;
  summary.initial_cost = outcome.initial_cost;
  summary.final_cost = outcome.final_cost;
  if (options.objective == FitOptions::Objective::kWholeStrokeMax) {
    ProblemKind whole;
    whole.windows = metric_windows(options, start);
    whole.windows.whole_strokes = true;
    whole.windows.cut_angles_rad.clear();  // the study replays strokes whole, impacts included
    whole.residual_power = options.max_objective_power;
    FitWeights rate_only = weights;  // the study's objective is about ω alone
    rate_only.angle_residuals = false;
    WindowProblem refine(start_model, data, map, whole, rate_only, problem.x());
    // The predicted-step rule assumes least squares: Ceres' own tests only.
    const WindowProblem::Outcome refined =
        refine.solve(solver_settings(options), options.max_iterations, 0.0);
    const std::string norm = "L" + std::to_string(2 * options.max_objective_power);
    if (refined.usable) {
      problem.x() = refine.x();
      summary.converged = refined.converged;
      summary.termination = "whole strokes, " + norm + " norm: " + refined.termination;
      summary.iterations += refined.iterations;
    } else {
      summary.notes.push_back("the whole-stroke objective failed (" + refined.termination +
                              "); the result is the window fit's");
    }
    summary.notes.push_back("the objective was the study's (whole strokes replayed, " + norm +
                            " norm of the rate error approximating its maximum); uncertainties "
                            "are the window least-squares problem's at that result");
  }
}

// The statistics of the window problem at the result: covariances, uncertainties, which
// parameters are determined, strong correlations.
void statistics_stage(WindowProblem& problem, const DoorModel& start, const ParameterMap& map,
                      const StartValues& starts, const std::vector<double>& window_start_values,
                      const std::vector<double>& fitted_values, const FitOptions& options,
                      FitSummary& summary, Eigen::MatrixXd& information) {
  const int parameter_count = start.parameter_count();
  const std::vector<double>& values = starts.values;
  const std::vector<std::string>& origin = starts.origin;
  const auto bounds = start.parameter_bounds();
  // Statistics of the window problem at the result: (JᵀJ)⁻¹ from the reduced system, the
  // classical σ² (JᵀJ)⁻¹ and the window-robust (JᵀJ)⁻¹ (Σ g_w g_wᵀ) (JᵀJ)⁻¹ · W/(W − p).
  ReducedSystem system;
  if (!problem.reduce(/*cached_only=*/false, system)) {
    throw std::runtime_error("fit: a window failed to evaluate at the result");
  }
  const int p = map.free_count();
  information = system.information;
  const InformationInverse inverse = invert_information(system.information);
  summary.residual_variance = system.residual_variance();
  summary.covariance_rank = inverse.rank;
  const Eigen::MatrixXd classical = summary.residual_variance * inverse.inverse;
  const RobustCovariance robust_result = robust_covariance(system, inverse.inverse);
  const Eigen::MatrixXd& robust = robust_result.covariance;
  summary.ceres_covariance_difference = kNaN;
  if (options.check_covariance_with_ceres) {
    summary.ceres_covariance_difference =
        compare_with_ceres_covariance(problem, inverse.inverse, fit_thread_count(options));
    if (std::isnan(summary.ceres_covariance_difference)) {
      summary.notes.push_back("ceres::Covariance could not compute the covariance to compare");
    }
  }
  const bool use_robust = options.uncertainty == FitOptions::Uncertainty::kWindowRobust;
  const Eigen::MatrixXd& chosen = use_robust ? robust : classical;
  summary.covariance.assign(static_cast<std::size_t>(p) * p, 0.0);
  for (int r = 0; r < p; ++r) {
    for (int c = 0; c < p; ++c) {
      summary.covariance[static_cast<std::size_t>(r) * p + c] =
          chosen(r, c) * map.scale[r] * map.scale[c];
    }
  }
  for (int i = 0; i < parameter_count; ++i) {
    FittedParameter parameter;
    parameter.name = start.parameter_name(i);
    parameter.unit = std::string(start.parameter_unit(i));
    parameter.start = values[i];
    parameter.equation_error = window_start_values[i];
    parameter.value = fitted_values[i];
    parameter.bounds = bounds[i];
    parameter.start_origin = origin[i];
    parameter.uncertainty = parameter.classical_uncertainty = parameter.robust_uncertainty = kNaN;
    summary.parameters.push_back(parameter);
  }
  for (int k = 0; k < p; ++k) {
    FittedParameter& parameter = summary.parameters[map.free_index[k]];
    parameter.free = true;
    parameter.classical_uncertainty = std::sqrt(std::max(0.0, classical(k, k))) * map.scale[k];
    parameter.robust_uncertainty = std::sqrt(std::max(0.0, robust(k, k))) * map.scale[k];
    parameter.uncertainty =
        use_robust ? parameter.robust_uncertainty : parameter.classical_uncertainty;
    parameter.effective_windows = robust_result.effective_windows(k);
    const double width = parameter.bounds.upper - parameter.bounds.lower;
    parameter.at_bound = std::abs(parameter.value - parameter.bounds.lower) <= 1e-6 * width ||
                         std::abs(parameter.bounds.upper - parameter.value) <= 1e-6 * width;
    if (inverse.undetermined[k]) {
      parameter.determined = false;
      parameter.uncertainty = parameter.classical_uncertainty = parameter.robust_uncertainty = kNaN;
    } else if (!(parameter.uncertainty <=
                 options.undetermined_relative_uncertainty * std::abs(parameter.value))) {
      parameter.determined = false;
    }
    if (!parameter.determined) summary.undetermined.push_back(parameter.name);
    if (parameter.at_bound) {
      summary.notes.push_back(parameter.name +
                              " ended on a bound: its uncertainty ignores the bound");
    }
  }
  if (!summary.undetermined.empty()) {
    const Eigen::Map<const Eigen::VectorXd> x(problem.x().data(), p);
    for (int k :
         identifiable_subset(system, x, use_robust, options.undetermined_relative_uncertainty)) {
      summary.identifiable.push_back(summary.free_names[k]);
    }
  }
  std::string few_windows;
  for (int k = 0; k < p && use_robust; ++k) {
    const FittedParameter& parameter = summary.parameters[map.free_index[k]];
    if (parameter.determined && parameter.effective_windows < kFewEffectiveWindows) {
      few_windows += (few_windows.empty() ? "" : ", ") + parameter.name;
    }
  }
  if (!few_windows.empty()) {
    summary.notes.push_back("the robust uncertainties of " + few_windows + " rest on fewer than " +
                            std::to_string(static_cast<int>(kFewEffectiveWindows)) +
                            " windows (n_eff): each is itself uncertain, like a t-distribution's "
                            "scale with n_eff - 1 degrees of freedom");
  }
  for (int r = 0; r < p; ++r) {
    for (int c = r + 1; c < p; ++c) {
      if (inverse.undetermined[r] || inverse.undetermined[c]) continue;
      const double denominator = std::sqrt(chosen(r, r) * chosen(c, c));
      if (!(denominator > 0)) continue;
      const double correlation = chosen(r, c) / denominator;
      if (std::abs(correlation) > options.correlation_threshold) {
        summary.strong_correlations.push_back(
            {summary.free_names[r], summary.free_names[c], correlation});
      }
    }
  }
  std::sort(summary.strong_correlations.begin(), summary.strong_correlations.end(),
            [](const ParameterCorrelation& a, const ParameterCorrelation& b) {
              return std::abs(a.value) > std::abs(b.value);
            });
}

// What a fit leaves for the what-would-determine stage, which runs on the fit that is kept.
struct KeptFit {
  ParameterMap map;
  std::vector<double> x;  // the fitted free values, scaled
  FitWeights weights;
  Eigen::MatrixXd information;  // the window problem's H at x
};

FitResult fit_once(const DoorModel& start, const PreparedData& data, const FitOptions& options,
                   std::vector<DoorModel>& fold_models, KeptFit& kept) {
  const StageClock::time_point began = StageClock::now();
  if (const std::string message = options.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
  check_data(data, start);
  FitSummary summary;
  summary.model_kind = start.kind();
  summary.source = data.source;
  summary.options = options;
  summary.strokes = data.strokes.size();
  FitWeights weights = resolve_weights(options, data, summary.notes);
  summary.rate_noise_rad_s = weights.rate_noise_rad_s;
  summary.angle_noise_rad = weights.angle_noise_rad;

  const StartValues chosen = start_values(start, data, options, weights, summary);
  const DoorModel start_model = checked_start_model(start, chosen.values);
  const ParameterMap map = make_map(start, chosen, options, weights, summary);

  // The window problem (built first: it tells whether there is enough data).
  const StageClock::time_point solve_began = StageClock::now();
  const std::vector<double> x_start = scaled_values(map, start_model.parameter_values());
  WindowProblem problem(start_model, data, map, window_fit_kind(options, start), weights, x_start);
  check_problem(problem, data, map, summary);
  summary.times.start_s = seconds_since(began);

  if (options.equation_error_start) {
    equation_error_stage(problem, start_model, data, map, options, x_start, summary);
  }
  const std::vector<double> window_start_values = map.values(problem.x().data());
  summary.times.equation_error_s = seconds_since(solve_began);
  window_stage(problem, start, start_model, data, map, options, weights, summary);
  summary.solve_time_s = seconds_since(solve_began);
  summary.times.windows_s = summary.solve_time_s - summary.times.equation_error_s;

  throw_if_stop_requested(options.stop_requested, "the fit's statistics");
  const StageClock::time_point statistics_began = StageClock::now();
  const std::vector<double> fitted_values = map.values(problem.x().data());
  FitResult result{start.with_parameter_values(fitted_values), FitSummary{}};
  statistics_stage(problem, start, map, chosen, window_start_values, fitted_values, options,
                   summary, kept.information);
  kept.map = map;
  kept.x = problem.x();
  kept.weights = weights;
  summary.times.statistics_s = seconds_since(statistics_began);

  // Metrics: on the fitted strokes, then held out.
  const StageClock::time_point metrics_began = StageClock::now();
  summary.fitted = compute_fit_metrics(result.model, data, metric_windows(options, start));
  summary.times.metrics_s = seconds_since(metrics_began);
  const StageClock::time_point held_out_began = StageClock::now();
  const int stroke_count = static_cast<int>(data.strokes.size());
  if (options.cross_validation_folds > 0 && stroke_count >= 2) {
    try {
      throw_if_stop_requested(options.stop_requested, "the cross-validation");
      summary.folds = std::min(options.cross_validation_folds, stroke_count);
      summary.held_out =
          cross_validate(result.model, data, map, problem.x(), options, weights, summary.folds,
                         summary.notes, fold_models, summary.fold_fits);
    } catch (const StopRequested&) {
      if (!options.partial_on_stop) throw;
      summary.interrupted = "during the cross-validation: no held-out metrics";
      summary.folds = 0;
      summary.fold_fits.clear();
      fold_models.clear();
    }
  } else if (options.cross_validation_folds > 0) {
    summary.notes.push_back("one stroke only: no held-out metrics");
  }
  summary.times.held_out_s = seconds_since(held_out_began);
  if (!summary.converged) {
    summary.notes.push_back("the solver did not report convergence: " + summary.termination);
  }
  summary.total_time_s = seconds_since(began);
  result.summary = std::move(summary);
  return result;
}

// What would determine each free parameter of the kept fit left undetermined or on a bound
// (FitSummary::determining); nothing to do when every one is determined and inside its bounds.
void determining_stage(FitResult& result, const PreparedData& data, const FitOptions& options,
                       const KeptFit& kept) {
  FitSummary& summary = result.summary;
  const bool robust = options.uncertainty == FitOptions::Uncertainty::kWindowRobust;
  std::vector<int> positions;
  std::vector<double> inflation, ratios;
  for (int k = 0; k < kept.map.free_count(); ++k) {
    const FittedParameter& parameter =
        summary.parameters[static_cast<std::size_t>(kept.map.free_index[k])];
    const double ratio = parameter.robust_uncertainty / parameter.classical_uncertainty;
    inflation.push_back(robust && std::isfinite(ratio) && ratio > 0 ? ratio : kNaN);
    if (std::isfinite(inflation.back())) ratios.push_back(inflation.back());
    if (!parameter.determined || parameter.at_bound) positions.push_back(k);
  }
  if (positions.empty()) return;
  // A parameter without a ratio of its own (in an undetermined direction) takes the median.
  std::sort(ratios.begin(), ratios.end());
  const double median = !robust || ratios.empty() ? 1.0 : ratios[ratios.size() / 2];
  std::vector<double> chosen;
  for (int k : positions) {
    const double ratio = inflation[static_cast<std::size_t>(k)];
    chosen.push_back(std::isfinite(ratio) ? ratio : median);
  }
  const ProblemKind kind = window_fit_kind(options, result.model);
  const DeterminingInput input{
      result.model, data,         kept.map,         kept.x,
      kind,         kept.weights, kept.information, summary.residual_variance};
  summary.determining = what_would_determine(input, options, positions, chosen);
  for (std::size_t r = 0; r < summary.determining.size(); ++r) {
    const FittedParameter& parameter = summary.parameters[static_cast<std::size_t>(
        kept.map.free_index[static_cast<std::size_t>(positions[r])])];
    summary.determining[r].undetermined = !parameter.determined;
    summary.determining[r].at_bound = parameter.at_bound;
  }
}

// The restart stage: each fold's model and the start on all strokes; `result` becomes a
// restart from the best when one fits every stroke clearly better (fit_model).
void restart_if_better(FitResult& result, const DoorModel& start, const PreparedData& data,
                       const FitOptions& options, const std::vector<DoorModel>& fold_models,
                       StageClock::time_point began, KeptFit& kept) {
  // Each cross-validation fold is refitted from the full fit on fewer strokes. When one of
  // them fits *all* the strokes clearly better than the full fit does, the full fit stopped
  // in a local minimum (an output-error cost is not convex: a window can settle on the
  // wrong side of a latch barrier). Restart once from the best such fold.
  //
  // The start model as given is tried the same way: start values read off the data (the
  // latch's, on a recording that never enters it) or the equation-error stage can lead the
  // fit to a minimum far worse than where it was started (docs/fitting.md, "Solving and
  // stopping", has the recordings where it did).
  const double fitted_rmse = result.summary.fitted.window.rmse();
  // Each fold's model and the start on all strokes, at once (independent and deterministic),
  // then in order.
  const std::size_t folds = fold_models.size();
  std::vector<double> candidate_rmse(folds + 1);
  parallel_for(static_cast<int>(folds + 1), fit_thread_count(options), [&](int k) {
    const DoorModel& model = static_cast<std::size_t>(k) < folds ? fold_models[k] : start;
    candidate_rmse[k] = evaluate_model(model, data, options).window.rmse();
  });
  const DoorModel* best = nullptr;
  double best_rmse = kFoldRestartGain * fitted_rmse;
  for (std::size_t k = 0; k < folds; ++k) {
    if (candidate_rmse[k] < best_rmse) {
      best_rmse = candidate_rmse[k];
      best = &fold_models[k];
    }
  }
  // The start only when no fold offers a restart: a fold's basin, reached from the fit,
  // is the better guess (the bench door's gravity refit, tests/analysis/test_loop_on_bench.cpp,
  // rests on one).
  if (best == nullptr && candidate_rmse[folds] < best_rmse) {
    best_rmse = candidate_rmse[folds];
    best = &start;
  }
  if (best == nullptr) return;
  const bool from_start = best == &start;
  FitOptions restart = options;
  restart.latch_start_from_data = false;  // start exactly at the fold's (or given) values
  restart.equation_error_start = false;
  std::vector<DoorModel> unused;
  KeptFit second_kept;
  FitResult second = fit_once(*best, data, restart, unused, second_kept);
  if (!(second.summary.fitted.window.rmse() < fitted_rmse)) {
    result.summary.notes.push_back(
        from_start ? "the start model fitted all strokes better than the fit; a restart from "
                     "it did not improve"
                   : "a cross-validation fold fitted all strokes better; a restart from it did "
                     "not improve");
    return;
  }
  // Report the parameters' starts as the user gave them, and how the result was reached.
  for (std::size_t i = 0;
       i < second.summary.parameters.size() && i < result.summary.parameters.size(); ++i) {
    second.summary.parameters[i].start = result.summary.parameters[i].start;
    second.summary.parameters[i].start_origin = result.summary.parameters[i].start_origin;
    second.summary.parameters[i].equation_error = result.summary.parameters[i].equation_error;
  }
  second.summary.latch_start = result.summary.latch_start;
  second.summary.iterations += result.summary.iterations;
  second.summary.initial_cost = result.summary.initial_cost;
  second.summary.options = options;
  second.summary.notes.insert(
      second.summary.notes.begin(),
      "the full fit stopped in a local minimum (window RMSE " + printf_text("%.4g", fitted_rmse) +
          (from_start ? " rad/s); the start model as given fitted every stroke better ("
                      : " rad/s); a cross-validation fold's solution fitted every stroke "
                        "better (") +
          printf_text("%.4g", best_rmse) + " rad/s), and the fit was restarted from it");
  second.summary.total_time_s = seconds_since(began);
  result = std::move(second);
  kept = std::move(second_kept);
}

}  // namespace

FitResult fit_model(const DoorModel& start, const PreparedData& data, const FitOptions& options) {
  const StageClock::time_point began = StageClock::now();
  std::vector<DoorModel> fold_models;
  KeptFit kept;
  FitResult result = fit_once(start, data, options, fold_models, kept);
  if (!result.summary.interrupted.empty()) return result;
  try {
    restart_if_better(result, start, data, options, fold_models, began, kept);
  } catch (const StopRequested&) {
    if (!options.partial_on_stop) throw;
    result.summary.interrupted =
        "during the restart from a better start: the fit was not restarted";
    return result;
  }
  if (!options.what_would_determine) return result;
  const StageClock::time_point determining_began = StageClock::now();
  try {
    determining_stage(result, data, options, kept);
  } catch (const StopRequested&) {
    if (!options.partial_on_stop) throw;
    result.summary.determining.clear();
    result.summary.interrupted =
        "during what would determine the parameters: no such strokes proposed";
  }
  result.summary.times.determining_s = seconds_since(determining_began);
  result.summary.total_time_s = seconds_since(began);
  return result;
}

WindowOptions metric_window_options(const FitOptions& options, const DoorModel& model) {
  WindowOptions windows;
  windows.window_s = options.window_s;
  windows.substeps_per_sample = options.substeps_per_sample;
  windows.cut_angles_rad = {0.0, model.geometry().theta_max_rad};
  return windows;
}

}  // namespace doorbench
