#pragma once
// Fits a door model (sensory or physical, with any effects) to prepared strokes
// (docs/fitting.md). In the manner of Ceres: FitOptions with defaults and validate(), one
// call, and a FitSummary with a brief and a full text report.
//
//   doorbench::FitOptions options;              // windows of 0.2 s, default free set
//   doorbench::FitResult result = doorbench::fit_model(start_model, prepared, options);
//   std::cout << result.summary.full_report();
//   result.model;                                // the fitted, checked DoorModel
//
// The method (docs/fitting.md): the sensory latch read off the force–angle curves, an
// equation-error stage, then multiple shooting on short windows, each started from the
// state at its first sample (estimated, with the measured state as its prior), integrated
// by RK4 under the measured force, Jacobians by Ceres' Jets through the integration.
// Uncertainties from the Gauss–Newton system with the window states eliminated; every
// figure in the report is defined in docs/fitting.md.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fit_start.h"
#include "analysis/fit/fit_windows.h"
#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"
#include "core/stop_request.h"
#include "core/units.h"

namespace doorbench {

struct SolverSettings;  // analysis/fit/fit_problem.h

// Where a fit is, for a progress display (FitOptions::progress). Counts, no times: the
// caller measures time.
struct FitProgress {
  enum class Stage {
    // The window fit's solver iterations (the coarse pass's and the fine one's together):
    // `done` of at most `total` (max_iterations; a fit that converges stops earlier).
    kWindows,
    // The cross-validation folds refitted: `done` of `total`.
    kFolds,
    // The global stage's subset refits (`done` of `total`, in `round`).
    kSearch,
    // The global stage's basin hops polished (`done` of `total`, FitOptions::global_hops);
    // a hop's polish reports nothing of its own.
    kHops,
    // The global stage's other fits after the first, one after another (a promising start
    // polished, the best polished again, the data-derived start fitted with softer switches):
    // that fit's solver iterations as kWindows counts them, `what` naming the fit.
    kPolish,
  };
  Stage stage = Stage::kWindows;
  int done = 0;
  int total = 0;
  int round = 1;       // kSearch: the round of subset refits (FitOptions::global_rounds)
  std::string what{};  // kPolish: "polishing the start as given", "fitting the data-derived ..."
};

// The bench's noise levels (reference-door.json): the weights when neither the options
// nor the data give them.
inline constexpr double kBenchRateNoise_rad_s = 0.05 * kRadPerDeg;
inline constexpr double kBenchAngleNoise_rad = 0.01 * kRadPerDeg;

// A Gaussian prior on one parameter: the residual (value − center) / sigma joins the data's
// (which are in units of their noise). The inverse design (analysis/design/inverse_design.h) uses
// them to pull each parameter toward the AS-IS door.
struct ParameterPrior {
  std::string parameter;  // its name ("F0", "stribeck.d_s")
  double center = 0.0;    // in the parameter's unit
  double sigma = 1.0;     // > 0, in the parameter's unit
};

struct FitOptions {
  // --- Windows (multiple shooting) ---
  double window_s = 0.2;        // each window's length on the recording's clock
  int substeps_per_sample = 2;  // RK4 steps per sample interval
  // Solve with one RK4 step per sample first (half the cost), then refine with
  // substeps_per_sample from there.
  bool coarse_first = true;
  bool angle_residuals = true;  // residuals (θ_sim − θ_meas)/σ_θ beside (ω_sim − ω_meas)/σ_ω
  // Estimate each window's start state too, tied to the measured state by its noise level
  // (errors in variables; docs/fitting.md). false: start exactly from the measured state.
  bool estimate_window_states = true;
  // The estimated window start states to begin from (FitResult::window_states of a fit of the
  // same data with the same window_s and angle range), for a start that is another fit's
  // optimum: the window fit then begins at that optimum's cost. Empty: the measured states.
  // The global stage's other starts and the subset refits begin from the measured states
  // either way. fit_model throws std::invalid_argument when the count is not the problem's.
  std::vector<double> window_state_start;
  // σ_ω and σ_θ, the residuals' weights. 0: the data's noise levels (PreparedData), or the
  // bench's (kBench*) when the data has none.
  double rate_noise_rad_s = 0.0;
  double angle_noise_rad = 0.0;

  // --- Parameters ---
  // Free parameters by name ("k_inf", "stribeck.d_s"). Empty: default_free_parameters().
  std::vector<std::string> free_parameters;
  // Taken out of the free set (handy with the default set).
  std::vector<std::string> fixed_parameters;
  // Sensory model: replace the start's free θ0…θ3, k_inf and k_lock with values read off
  // the force–angle curves near closed (analysis/fit/fit_start.h).
  bool latch_start_from_data = true;
  // Fit the equation of motion sample by sample first (analysis/fit/internal/fit_equation_error.h)
  // and start the windows from its result.
  bool equation_error_start = true;
  // Priors on free parameters (those on fixed parameters are ignored). They act in the
  // window fit and its statistics, not in the equation-error stage (only a start). None:
  // the fit is exactly the plain one.
  std::vector<ParameterPrior> priors;

  // --- The global stage (docs/fitting.md, "The global stage") ---
  // After the fit from the data-derived start (the latch read off, the equation-error stage),
  // other starts are tried: the start exactly as given, the refits without each subset of
  // `global_subsets` (stroke s in subset s mod k, refitted from the fit's optimum), and
  // `global_samples` points of a Sobol sequence over the free parameters' bounds (linear, or
  // logarithmic where the bounds span more than two decades: the stiffnesses). Each is
  // screened by its window RMSE on every stroke (from the measured states); those below
  // global_promising_ratio times the fit's are promising, and the best `global_polished` of
  // each kind (by RMSE; the subset refits first, then the start as given, then the sample)
  // are polished by Levenberg–Marquardt on every stroke. The optimum `global_keep`
  // names is the fit. Nothing of it depends on
  // cross_validation_folds: when the folds are the subsets' partition and the fit stays the
  // first, the cross-validation reuses the subset refits.
  // false: the one start polished.
  bool global_search = true;
  int global_samples = 32;  // sample points screened (0: none)
  // The subset refits' partition (0: none; else >= 2). 4, fit's default folds: `doorbench
  // fit` reuses them as its folds.
  int global_subsets = 4;
  int global_polished = 1;  // promising starts of each kind polished (>= 1)
  // A start is promising below this times the fit's window RMSE (> 0; above 1, starts that
  // screen worse than the fit can be polished too).
  double global_promising_ratio = 0.9;
  int global_seed = 1;  // the sample is the Sobol sequence from this point on (>= 1)
  // Basin hops after the polishes (0: none): each moves the best optimum so far by a random
  // step (normal, standard deviation global_hop_size of each free parameter's bounds, on the
  // sample's linear or log scale; seeded by global_seed) and polishes it; a hop that ends
  // lower by the global_keep measure becomes the best.
  int global_hops = 0;
  double global_hop_size = 0.1;  // in (0, 1]
  // Rounds of subset refits (>= 1). After the polishes, while the best optimum is a polish's
  // and each round lowers its global_keep measure by more than GlobalSearch::kSameOptimumCost
  // (relative), the subsets are refitted again from it, and those of the round that screen
  // below the best's window RMSE (ratio 1: a refit from an optimum lies near it) are polished,
  // at most global_polished. 1: the refits from the first fit only.
  int global_rounds = 3;
  // After the first polishes: when free parameters of the first optimum are undetermined or on
  // a bound, the door with those parameters back at their starts (read off the data, or as
  // given) and the others at the optimum, polished whatever it screens. Such parameters are
  // where a fit drifts along directions the data do not hold it in (stiffnesses traded off
  // along an undetermined direction, a term switched off at its bound); the door put back
  // screens worse than the optimum it came from, so the screen would never pass it. false:
  // not tried.
  bool global_reset = true;
  // After the rounds: the best optimum polished again from its own values, the window states
  // back at the measured ones, while each such polish lowers the best by more than
  // GlobalSearch::kSameOptimumCost (relative); at most this many polishes. The window cost's
  // floor is rugged: a polish that starts again from an optimum's values, with the measured
  // states (and the coarse pass, with sub-steps), often ends in a neighbouring optimum a
  // little lower. 0: not tried.
  int global_repolish = 3;
  // After the polishes again (global_repolish), last before the hops: the first start (as the
  // first fit took it: the latch read off, the equation-error stage) fitted with the model's
  // switches softer, its switch sharpness (DoorModel::switch_sharpness_index) times each factor,
  // without a global stage; its optimum with the model's own sharpness is polished when its
  // window RMSE on every stroke is below the best optimum's so far; when one becomes the
  // best, it is polished again as global_repolish says. Last, so that it never raises a fit. The
  // sensory model's switches (beta 3000: about 0.3 mrad) are narrower than the angle a door travels
  // in one integration step, so the window cost is rough in the latch angles; with softer switches
  // it is smoother, and such a fit can end in a basin no start with sharp switches reaches. Each
  // factor in (0, 1); empty, or a model with no switch sharpness: not tried.
  std::vector<double> global_soft_switches = {0.1, 1.0 / 3.0};
  // Which polished optimum is the fit: the lowest window cost (the fit's objective), or the
  // lowest window RMSE of the rate on every stroke from the measured states (the figure the
  // residual loop compares fits by; its fits keep that one).
  enum class GlobalKeep { kLowestCost, kLowestRateRmse };
  GlobalKeep global_keep = GlobalKeep::kLowestCost;

  // For each free parameter left undetermined or on a bound: the kinds of stroke that would
  // determine it, from the information such strokes add, simulated with the fitted door
  // (FitSummary::determining; docs/fitting.md, "What would determine it"). Computed once, on
  // the fit that is returned, and only when some free parameter is undetermined or on a bound.
  bool what_would_determine = true;

  // --- Objective ---
  enum class Objective {
    kWindows,  // least squares on windows started from measured states
    // The study's objective, max |ω_meas − ω_sim| over whole strokes replayed open-loop,
    // approximated by the L_(2·max_objective_power) norm of the rate errors. It starts from
    // the window fit's result. Ill-posed on realistic data (door-models.md §6).
    kWholeStrokeMax,
  };
  Objective objective = Objective::kWindows;
  int max_objective_power = 4;  // the L8 norm

  // --- Uncertainty ---
  enum class Uncertainty {
    // The delete-one-window jackknife of the estimate (analysis/fit/fit_problem.h): robust to
    // errors correlated within a window (the force noise the simulation integrates, a start
    // state's error), which the classical one ignores and so understates 2 to 10 times.
    kWindowRobust,
    // (JᵀJ)⁻¹ · σ², σ² = SSR/(n − p): the residuals taken as independent.
    kClassical,
  };
  Uncertainty uncertainty = Uncertainty::kWindowRobust;
  // Also compute (JᵀJ)⁻¹ with ceres::Covariance over the whole problem and report the
  // largest difference from the fit's own (Schur-complement) computation.
  bool check_covariance_with_ceres = false;

  // --- Solver (Levenberg–Marquardt, ceres::Solver) ---
  int max_iterations = 100;
  double function_tolerance = 1e-6;
  double parameter_tolerance = 1e-8;
  double gradient_tolerance = 1e-10;
  // Also stop once the Gauss–Newton step predicts that no free parameter would move by
  // more than this many of its standard uncertainties (coarse_tolerance_factor times this
  // for the coarse pass).
  double uncertainty_tolerance = 0.1;
  // Before the first step, that rule also asks the step to predict a cost decrease of at most
  // 0.1 % of the cost (a start's misfit inflates σ, and the rule alone stops there at once).
  // The residual loop keeps it off: its decisions were measured without it, and on a 10 s,
  // 200 Hz recording its start fit ends lower in cost but higher in held-out RMSE with it
  // (docs/PERFORMANCE.md, "The first step's stopping rule").
  bool first_step_decrease = true;
  // The coarse pass's stopping rule against the fine pass's (> 0). Far from the data σ is
  // inflated and 10 stops the coarse pass at once, leaving the iterations to the fine pass
  // at twice the cost; the residual loop's refit starts use 1 (docs/residual-loop.md).
  double coarse_tolerance_factor = 10.0;
  // Let Levenberg–Marquardt accept steps that raise the cost for a while (Ceres'
  // use_nonmonotonic_steps) while the stopping rule above is on. They get through the window
  // cost's small-scale roughness to lower optima, but the stopping rule cannot see an
  // excursion that never comes back below its best, which then runs to max_iterations
  // (docs/fitting.md, "Solving and stopping"). false: every accepted step lowers the cost.
  bool nonmonotonic_steps = true;
  // The equation-error stage stops after two accepted steps that change no free parameter
  // by more than this fraction of its scale.
  double equation_error_step_tolerance = 1e-2;
  // Evaluation threads per solve (0: every hardware thread); the cross-validation folds also
  // run at once, up to this many, each with its own evaluation threads. The result does not
  // depend on it (docs/fitting.md, "Threads and determinism").
  int num_threads = 0;

  // --- Report ---
  // Held-out metrics by k-fold cross-validation over strokes; 0: none; at least the
  // number of strokes: leave-one-stroke-out.
  int cross_validation_folds = 4;
  int held_out_max_iterations = 30;                // each fold's refit starts from the full fit
  double correlation_threshold = 0.9;              // |correlations| above are named
  double undetermined_relative_uncertainty = 1.0;  // u/|value| above: "undetermined"

  // Called as each stage begins (done 0), after each solver iteration of the window fit,
  // after each subset refit of the global stage and after each cross-validation fold (for a
  // refit from the thread that refitted it, never two at once); may be empty.
  // The equation-error stage, the statistics and the whole-stroke objective do not report.
  // Each polish of the global stage reports its window fit again from 0.
  std::function<void(const FitProgress&)> progress;
  // Asked after every solver iteration (of every solve: the equation-error stage, the window
  // fit, each subset refit, each polish, each fold) and between stages (core/stop_request.h);
  // when it returns true, fit_model throws StopRequested naming what was under way. May be
  // empty (never stop).
  StopHook stop_requested;
  // What a stop after the window fit's statistics leaves: false, StopRequested as during the
  // fit (what the residual loop and the inverse design need: a fit is whole or not at all);
  // true, the fit as it stands, marked in FitSummary::interrupted (the first start's fit
  // without held-out metrics when the global stage was cut, no held-out metrics when the
  // cross-validation was, no FitSummary::determining when its strokes' information was cut)
  // — what `doorbench fit` writes.
  bool partial_on_stop = false;

  // Empty when usable, else a one-line message naming the option.
  std::string validate() const;
};

// The default free set: every parameter except k_stop and c_stop (the end stops, which
// strokes that stay between the stops cannot tell apart), and for the sensory model beta and
// beta_f too (switch sharpness: nearly unidentifiable, and sharp switches make the cost
// rough).
std::vector<std::string> default_free_parameters(const DoorModel& model);

// The windows on which metrics are reported (and on which the residual loop examines the
// residual): the fit's window length and sub-steps, cut at the end stops.
WindowOptions metric_window_options(const FitOptions& options, const DoorModel& model);

struct FittedParameter {
  std::string name;
  std::string unit;
  bool free = false;
  double start = 0.0;           // the start (the start model's value, or read off the data)
  double equation_error = 0.0;  // after the equation-error stage: where the windows started
  double value = 0.0;
  // Standard uncertainty (the kind chosen in FitOptions); NaN for fixed parameters and
  // for parameters in a direction the data does not determine.
  double uncertainty = 0.0;
  double classical_uncertainty = 0.0;  // σ²-scaled covariance, for comparison
  double robust_uncertainty = 0.0;     // the window-robust (jackknife) one
  // How many windows the robust uncertainty effectively rests on (docs/fitting.md): below
  // about 10 it is itself rough.
  double effective_windows = 0.0;
  Bounds bounds;
  bool at_bound = false;
  bool determined = true;
  std::string start_origin;  // "start model", "read off the data", "clamped into bounds"
};

struct ParameterCorrelation {
  std::string first, second;
  double value = 0.0;
};

// One cross-validation fold's refit (held-out metrics): how it ended, and how well it did
// on the strokes it fitted and on those it left out.
struct FoldFit {
  std::vector<int> held_out_strokes;  // stroke ids
  bool converged = false;
  std::string termination;
  int iterations = 0;
  double fitted_rmse_rad_s = 0.0;     // window RMSE of ω on its own strokes
  double held_out_rmse_rad_s = 0.0;   // on the strokes it left out
  std::vector<std::string> at_bound;  // free parameters that ended on a bound
};

// What would determine a free parameter the fit leaves undetermined or on a bound
// (docs/fitting.md, "What would determine it"): kinds of stroke simulated with the fitted door,
// and the parameter's relative standard uncertainty (u / |value|, or u / 1 % of its bound width
// when the value is 0) with each kind's information added to the fit's: the classical
// uncertainty times the fit's window-robust / classical ratio for the parameter (the median
// ratio for one in an undetermined direction; 1 with classical uncertainties).
struct DeterminingStrokes {
  std::string parameter;
  bool undetermined = false;
  bool at_bound = false;
  double relative_now = 0.0;  // NaN: in a direction the data do not determine
  struct Kind {
    std::string kind;         // "slow openings and closings (about 0.1 rad/s)", ...
    std::string label;        // its short name, the report table's column: "slow", ...
    double relative = 0.0;    // NaN: still in an undetermined direction
    bool determines = false;  // finite and at most undetermined_relative_uncertainty
  };
  std::vector<Kind> kinds;
};

// One distinct optimum the global stage reached (FitSummary::global).
struct GlobalOptimum {
  double cost = 0.0;         // ½ Σ r² of the window problem (FitSummary::final_cost's kind)
  double fit_percent = 0.0;  // window FIT% on the fitted strokes
  std::vector<std::string> reached_from;  // the starts whose polish ended here
  std::vector<double> free_values;        // in the order of FitSummary::free_names
};

// What the global stage tried and found (docs/fitting.md, "The global stage").
struct GlobalSearch {
  bool ran = false;
  bool start_as_given = false;  // the start as given was screened (it differs from the first)
  int sample_points = 0;        // feasible points of the sample screened
  int subset_refits = 0;        // subset refits screened, every round's
  int partition = 0;            // their subsets
  int rounds = 0;               // rounds of subset refits (FitOptions::global_rounds)
  // Free parameters the reset start put back at their starts (FitOptions::global_reset); 0:
  // no reset start was polished.
  int reset_parameters = 0;
  // Polishes of the best optimum from its own values (FitOptions::global_repolish), and how
  // many of them ended lower than the best before them.
  int repolished = 0;
  int repolished_lower = 0;
  // Fits of the first start with softer switches (FitOptions::global_soft_switches), and how
  // many of their optima, with the model's own switches, were below the best's window RMSE
  // and so polished.
  int soft_starts = 0;
  int soft_polished = 0;
  int starts_tried = 0;  // the first start, every start screened, the reset start, the soft
                         // starts, the polishes again and the hops
  // Screened starts polished: the first screen's below global_promising_ratio times the fit's
  // RMSE, a later round's and the soft starts' below the best optimum's so far.
  int promising = 0;
  int polished = 0;    // polished on every stroke, the first start included
  int hops = 0;        // basin hops polished (FitOptions::global_hops)
  int hops_lower = 0;  // hops that ended lower than the best before them
  // Distinct optima, the best first: two polishes end at one optimum when their costs differ
  // by at most kSameOptimumCost (relative) and no free parameter by more than
  // kSameOptimumParameter of the larger magnitude.
  std::vector<GlobalOptimum> optima;
  static constexpr double kSameOptimumCost = 1e-3;
  static constexpr double kSameOptimumParameter = 0.02;
  int reached_best = 0;   // polishes that ended at the best optimum
  std::string best_from;  // the first start that reached it
  double time_s = 0.0;    // wall clock of the stage (subset refits, screening, polishes)

  // The report's lines: "Global search: ..." and one per distinct optimum (with the free
  // parameters that differ from the best's; `names` in the order of free_values). "" when the
  // stage did not run.
  std::string report(const std::vector<std::string>& names) const;
};

struct FitSummary {
  ModelKind model_kind = ModelKind::kSensory;
  std::string source;
  FitOptions options;
  double rate_noise_rad_s = 0.0;  // the weights used
  double angle_noise_rad = 0.0;

  // Problem size.
  std::size_t strokes = 0;
  std::size_t windows = 0;
  std::size_t residuals = 0;
  int free_parameters = 0;
  int window_state_parameters = 0;  // 2 per window when their start states are estimated

  // Solver.
  int equation_error_iterations = 0;
  std::string equation_error_termination;
  bool converged = false;   // the window fit converged (Ceres' tests or the stopping rule)
  std::string termination;  // why it stopped
  int iterations = 0;
  double initial_cost = 0.0;  // ½ Σ r² at the start and at the end (window objective)
  double final_cost = 0.0;
  double solve_time_s = 0.0;  // the local solve(s): equation error, windows, whole strokes
  double total_time_s = 0.0;  // everything, cross-validation included
  // Where the time went (wall clock, s).
  struct Times {
    double start_s = 0.0;           // checks, latch read-off, problem set-up
    double equation_error_s = 0.0;  // the equation-error stage
    double windows_s = 0.0;         // the window fit (and the whole-stroke one, if asked)
    double statistics_s = 0.0;      // covariances
    double metrics_s = 0.0;         // metrics on the fitted strokes (replays included)
    double search_s = 0.0;          // the global stage after the first start's fit
    double held_out_s = 0.0;        // cross-validation
    double determining_s = 0.0;     // what would determine the undetermined (when computed)
  } times;

  // Statistics at the result (window objective).
  // σ² = SSR / (n − p), in units of the weights; p counts the window states too.
  double residual_variance = 0.0;
  int covariance_rank = 0;  // of the free parameters' covariance
  // With check_covariance_with_ceres: the largest |difference| between ceres::Covariance and
  // the fit's (JᵀJ)⁻¹, element by element, relative to √(C_ii C_jj). NaN when not checked.
  double ceres_covariance_difference = 0.0;
  std::vector<FittedParameter> parameters;  // every parameter, in the model's order
  // Covariance of the free parameters (in their units, FitOptions' kind), row-major,
  // in the order of free_names.
  std::vector<std::string> free_names;
  std::vector<double> covariance;
  std::vector<ParameterCorrelation> strong_correlations;
  std::vector<std::string> undetermined;  // parameters the data cannot determine
  // When some are undetermined: the free parameters the data would determine with the
  // others held (identifiable_subset at the optimum, in the order of free_names); a fit of
  // just these (doorbench fit --free auto) is the proposal. Empty when all are determined.
  std::vector<std::string> identifiable;

  LatchReadOff latch_start;  // the sensory latch read off the data (when asked)
  GlobalSearch global;       // the global stage (FitOptions::global_search)
  // For each free parameter left undetermined or on a bound, in the order of free_names
  // (FitOptions::what_would_determine); empty when none is, or when not asked.
  std::vector<DeterminingStrokes> determining;

  FitMetrics fitted;                   // on the strokes fitted (all of them)
  std::optional<FitMetrics> held_out;  // each stroke by the fit that left it out
  int folds = 0;
  std::vector<FoldFit> fold_fits;  // one per fold refitted

  std::vector<std::string> notes;  // anything the reader should know
  // "" for a whole fit; else when a stop request came and what it cut
  // (FitOptions::partial_on_stop), e.g. "during the cross-validation: no held-out metrics".
  std::string interrupted;

  std::string brief_report() const;  // a few lines
  // The outcome in a few lines, the first of brief_report's: what was fitted and whether it
  // converged, the window RMSE and FIT% fitted and held out, the study objective, a FIT% below 0
  // or far below the fitted one held out as a warning, and the undetermined parameters.
  std::string headline() const;
  // With undetermined parameters, the proposal: "Identifiable free set (...): J c d1; held:
  // k s (doorbench fit --free auto fits this set)."; "" when all are determined.
  std::string identifiable_line() const;
  std::string full_report() const;  // parameters, correlations, metrics per stroke, solver
  // "What would determine them: ...", a line per kind of stroke naming its column, and a table:
  // a row per row of `determining`, its u/|value| now and with each kind, and the kinds that
  // determine it; "" when none.
  std::string determining_lines() const;
};

struct FitResult {
  DoorModel model;  // the fitted model; every constraint holds
  FitSummary summary;
  // The window fit's estimated start states at the result, θ and ω of each window in turn in
  // solver units (FitOptions::window_state_start takes them); empty when not estimated.
  std::vector<double> window_states;
};

// Fits `start` (its values are the start, its bounds the search range) to `data`. Throws
// std::invalid_argument for unusable options (the validate() message), unknown parameter
// names, a start that breaks a constraint, or data without usable strokes or whose handle
// radius differs from the model's; std::runtime_error when the solver cannot evaluate the
// start at all.
FitResult fit_model(const DoorModel& start, const PreparedData& data,
                    const FitOptions& options = {});

// What the least-squares solvers (analysis/fit/fit_problem.h) take of `options`: tolerances,
// iteration limit, the kind of uncertainty of the stopping rule, and the threads
// (num_threads, 0: every hardware thread).
SolverSettings solver_settings(const FitOptions& options);
int fit_thread_count(const FitOptions& options);

// RK4 sub-steps per sample for a fit of `data` (FitOptions::substeps_per_sample as `doorbench
// fit` and `loop` choose it): steps of at most 1 ms over the data's median interval (else its
// nominal rate, else 1 ms), and at least 2 per sample (the fit's default, kept at 500 Hz and
// above), at most 100. At 50 Hz: 20, or 21 when the median interval is a little over 20 ms.
int substeps_for_1ms_steps(const PreparedData& data);

// The metrics of any model on `data` with the options' windows (the residual loop's
// "error before and after").
FitMetrics evaluate_model(const DoorModel& model, const PreparedData& data,
                          const FitOptions& options = {});

}  // namespace doorbench
