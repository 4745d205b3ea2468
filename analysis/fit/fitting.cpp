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
#include "analysis/fit/internal/fit_folds.h"
#include "analysis/fit/internal/fit_global.h"
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
  if (global_samples < 0) return "fit global_samples must be >= 0 (0: no sample)";
  if (global_subsets < 0 || global_subsets == 1) {
    return "fit global_subsets must be 0 (no subset refits) or >= 2";
  }
  if (global_polished < 1) return "fit global_polished must be >= 1";
  if (!(global_promising_ratio > 0 && std::isfinite(global_promising_ratio))) {
    return "fit global_promising_ratio must be a number > 0";
  }
  if (global_seed < 1) return "fit global_seed must be >= 1";
  if (global_hops < 0) return "fit global_hops must be >= 0";
  if (global_rounds < 1) return "fit global_rounds must be >= 1";
  if (global_repolish < 0) return "fit global_repolish must be >= 0";
  for (double factor : global_soft_switches) {
    if (!(factor > 0 && factor < 1)) {
      return "fit global_soft_switches: each factor must lie strictly between 0 and 1";
    }
  }
  if (!(global_hop_size > 0 && global_hop_size <= 1)) {
    return "fit global_hop_size must lie in (0, 1]";
  }
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

int substeps_for_1ms_steps(const PreparedData& data) {
  const double interval_s = data.interval_median_s > 0 ? data.interval_median_s
                            : data.sample_rate_hz > 0  ? 1.0 / data.sample_rate_hz
                                                       : 0.001;
  return std::clamp(static_cast<int>(std::ceil(interval_s / 0.001 - 1e-9)), 2, 100);
}

SolverSettings solver_settings(const FitOptions& options) {
  SolverSettings settings;
  settings.max_iterations = options.max_iterations;
  settings.function_tolerance = options.function_tolerance;
  settings.parameter_tolerance = options.parameter_tolerance;
  settings.gradient_tolerance = options.gradient_tolerance;
  settings.equation_error_step_tolerance = options.equation_error_step_tolerance;
  settings.robust_uncertainty = options.uncertainty == FitOptions::Uncertainty::kWindowRobust;
  settings.nonmonotonic_steps = options.nonmonotonic_steps;
  settings.first_step_decrease = options.first_step_decrease;
  settings.threads = fit_thread_count(options);
  settings.stop_requested = options.stop_requested;
  return settings;
}

namespace {

// Free values of a model, scaled.
std::vector<double> scaled_values(const ParameterMap& map, std::span<const double> values) {
  return map.scaled(std::vector<double>(values.begin(), values.end()));
}

}  // namespace

WindowOptions fit_detail::metric_windows(const FitOptions& options, const DoorModel& model) {
  return metric_window_options(options, model);
}

FitMetrics evaluate_model(const DoorModel& model, const PreparedData& data,
                          const FitOptions& options) {
  return compute_fit_metrics(model, data, metric_windows(options, model));
}

namespace {

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

}  // namespace

FitResult fit_detail::fit_once(const DoorModel& start, const PreparedData& data,
                               const FitOptions& options, KeptFit& kept) {
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
  if (!options.window_state_start.empty()) {
    if (options.window_state_start.size() != problem.z().size()) {
      throw std::invalid_argument(
          "fit window_state_start holds " + std::to_string(options.window_state_start.size()) +
          " values, but the windows of this fit have " + std::to_string(problem.z().size()) +
          " start states (another recording, window_s or angle range?)");
    }
    problem.z() = options.window_state_start;
  }
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
  FitResult result{start.with_parameter_values(fitted_values), FitSummary{}, problem.z()};
  statistics_stage(problem, start, map, chosen, window_start_values, fitted_values, options,
                   summary, kept.information);
  kept.map = map;
  kept.x = problem.x();
  kept.weights = weights;
  summary.times.statistics_s = seconds_since(statistics_began);

  // Metrics on the fitted strokes.
  const StageClock::time_point metrics_began = StageClock::now();
  summary.fitted = compute_fit_metrics(result.model, data, metric_windows(options, start));
  summary.times.metrics_s = seconds_since(metrics_began);
  if (!summary.converged) {
    summary.notes.push_back("the solver did not report convergence: " + summary.termination);
  }
  summary.total_time_s = seconds_since(began);
  result.summary = std::move(summary);
  return result;
}

namespace {

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

// Held-out metrics of the kept fit (FitOptions::cross_validation_folds): the subset refits of
// the global stage when they are the folds' partition and the fit is still the one they
// started from, else the folds refitted from the fit.
void held_out_stage(FitResult& result, const PreparedData& data, const FitOptions& options,
                    const KeptFit& kept, const std::vector<FoldOutcome>& refits,
                    bool refits_from_fit) {
  FitSummary& summary = result.summary;
  const int stroke_count = static_cast<int>(data.strokes.size());
  if (options.cross_validation_folds == 0) return;
  if (stroke_count < 2) {
    summary.notes.push_back("one stroke only: no held-out metrics");
    return;
  }
  const int folds = std::min(options.cross_validation_folds, stroke_count);
  const bool reuse = refits_from_fit && static_cast<int>(refits.size()) == folds;
  std::vector<FoldOutcome> computed;
  if (!reuse) {
    throw_if_stop_requested(options.stop_requested, "the cross-validation");
    computed = subset_refits(result.model, data, kept.map, kept.x, options, kept.weights, folds,
                             FitProgress::Stage::kFolds);
  }
  summary.folds = folds;
  summary.held_out =
      held_out_metrics(reuse ? refits : computed, data, options, summary.notes, summary.fold_fits);
}

}  // namespace

FitResult fit_model(const DoorModel& start, const PreparedData& data, const FitOptions& options) {
  const StageClock::time_point began = StageClock::now();
  KeptFit kept;
  FitResult result = fit_once(start, data, options, kept);
  std::vector<FoldOutcome> refits;
  bool refits_from_fit = false;
  if (options.global_search) {
    try {
      refits_from_fit = global_stage(result, start, data, options, kept, refits);
    } catch (const StopRequested&) {
      if (!options.partial_on_stop) throw;
      result.summary.interrupted =
          "during the global search: the fit is the data-derived start's, without held-out "
          "metrics";
      result.summary.total_time_s = seconds_since(began);
      return result;
    }
  }
  const StageClock::time_point held_out_began = StageClock::now();
  try {
    held_out_stage(result, data, options, kept, refits, refits_from_fit);
  } catch (const StopRequested&) {
    if (!options.partial_on_stop) throw;
    result.summary.interrupted = "during the cross-validation: no held-out metrics";
    result.summary.folds = 0;
    result.summary.held_out.reset();
    result.summary.fold_fits.clear();
    result.summary.total_time_s = seconds_since(began);
    return result;
  }
  result.summary.times.held_out_s = seconds_since(held_out_began);
  result.summary.total_time_s = seconds_since(began);
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
