#pragma once
// The residual loop (door-models.md §4; docs/residual-loop.md): fit a door model, look at
// what it leaves unexplained, trace that to an effect of the catalogue (analysis/model/effects.h)
// the model lacks, add it, refit, and keep it only when the error on held-out strokes falls
// by more than a stated threshold AND the information criterion (BIC) falls. Repeat until
// no candidate qualifies. In the manner of Ceres: LoopOptions with defaults and validate(),
// one call, and a LoopResult with a brief and a full text report.
//
//   doorbench::LoopOptions options;                 // folds, thresholds, candidates
//   options.progress = [](const std::string& line) { std::cerr << line << '\n'; };
//   doorbench::LoopResult loop = doorbench::run_residual_loop(start_model, prepared, options);
//   std::cout << loop.full_report();
//   loop.final_fit.model;                            // the last accepted model, fitted
//
// Thread safety: free functions without shared state; the `progress` callback is called on
// the caller's thread, `step_progress` also from a refit's thread (never two at once). With
// LoopOptions::parallel_refits the loop runs fit_model, and the second look's refinements,
// on threads of its own, joined before the step's verdicts.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "analysis/model/door_model.h"
#include "analysis/model/effects.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench {

// Where the loop is, for a progress display (LoopOptions::step_progress). Counts, no times.
struct LoopProgress {
  int step = 1;         // the step under way, from 1
  int max_steps = 1;    // LoopOptions::max_steps: the loop may stop before
  int refits_done = 0;  // this step's refits finished ...
  int refits = 0;       // ... of this many (known once the step's residual is examined)
};

struct LoopOptions {
  // Every fit of the loop: the start model's and each candidate's (where a refit starts:
  // refit_start). cross_validation_folds must be >= 2, since the loop compares held-out
  // errors. Avoid 2: stroke s is in fold s mod k, so with openings and closings alternating
  // each fold would be fitted on one direction alone (docs/residual-loop.md, "Limits").
  // The loop compares fits by their rate RMSE: of the global stage's optima its fits keep the
  // lowest RMSE. Its global_subsets is ignored: the loop's fits take their subset refits on
  // the folds, which the cross-validation then reuses. One round of them, no reset start
  // (FitOptions::global_reset), no fits with softer switches (global_soft_switches) and no
  // polish again (global_repolish): a refit's two starts are the loop's own search
  // (docs/residual-loop.md, "Refits and acceptance"). The stopping rule as the loop's
  // decisions were measured with it (FitOptions::first_step_decrease off).
  FitOptions fit = [] {
    FitOptions options;
    options.cross_validation_folds = 3;
    options.global_keep = FitOptions::GlobalKeep::kLowestRateRmse;
    options.global_rounds = 1;
    options.global_reset = false;
    options.global_repolish = 0;
    options.global_soft_switches.clear();
    options.first_step_decrease = false;
    return options;
  }();

  // The effects the loop may add; empty: the whole catalogue. Effects the model already
  // has are never candidates.
  std::vector<effects::Kind> candidates;

  // --- Stopping and acceptance ---
  int max_steps = 4;         // effects added at most
  int refit_candidates = 3;  // the best-ranked candidates refitted at each step
  // A candidate is refitted only if its best amplitude explains at least this share of the
  // rate residual's sum of squares (it cannot be what the model lacks otherwise).
  double min_explained_fraction = 0.01;
  // ... and its score is significant: score_z (CandidateEvidence) at least this. The largest
  // of the candidates' scans is taken, so the level is above the usual 2 or 3.
  double min_score_z = 4.0;
  // Accept only if the held-out window RMSE of ω falls by more than this fraction of its
  // value before the step ...
  double min_held_out_improvement = 0.02;
  // ... and BIC = n ln(SSR/n) + p ln(n) falls by more than this (0: falls at all) ...
  double min_bic_decrease = 0.0;
  // ... and the refit's amplitude (the effect's first parameter; Stribeck: d_s − d1) lies at
  // least this many of its standard uncertainties from its neutral value (0; Stribeck: the
  // refit's d1). The refit must confirm, with its own (window-robust) uncertainty, what the
  // examination's z promised: an effect that lowers the error without being told apart from
  // nothing is the fit bending to the data route's misfit (docs/residual-loop.md, "An
  // amplitude told apart from nothing"). 0: off.
  double min_amplitude_z = 4.0;
  // The second look at weak candidates (docs/residual-loop.md, "The second look"): the
  // best-ranked candidates that do not pass both min_explained_fraction and min_score_z,
  // as many as the refit slots the passing candidates leave free, are each added at their
  // examination start (and at a far start: the amplitude 3 standard errors further from 0)
  // and refined with the free parameters by at most this many Gauss–Newton steps on the
  // examination's windows (no fit_model call); a candidate
  // is refitted when its refined share and z pass both thresholds. 0: off.
  int screen_steps = 5;

  // --- The residual examination's scans of nonlinear parameters (start values) ---
  std::vector<double> stribeck_speeds_rad_s = {0.01, 0.02, 0.05, 0.1, 0.2, 0.5};  // w_s
  std::vector<double> soft_close_angles_rad = {0.05, 0.1, 0.15, 0.2, 0.3, 0.4};   // θ_sc
  std::vector<double> soft_close_sharpness_per_rad = {10.0, 50.0};                // β_sc
  int end_stop_angles = 12;  // θ_e: this many angles evenly over the data's angle range
  // Effect parameters held at their start (the scan's or the catalogue's default) in every
  // refit, as the fit holds the sensory beta and beta_f by default. The end stop's switch is
  // about 1 mrad wide: its sharpness is nearly unidentifiable and makes the cost rough.
  std::vector<std::string> fixed_effect_parameters = {"end_stop.beta_e"};

  // Where each candidate's refit starts.
  enum class RefitStart {
    // Both starts below, fitted without cross-validation; the one with the lower window sum
    // of squares is fitted again from its result, with cross-validation (fit_model three times).
    kBest,
    // The current fitted model with the effect added.
    kCurrentFit,
    // The start model's base values (the latch read off the data again when options.fit
    // asks), the effects already added at their fitted values, and the new effect. A fit
    // that had to distort its parameters for the missing effect can leave a basin from
    // which the refit cannot climb out; this start avoids it.
    kStartModel,
  };
  RefitStart refit_start = RefitStart::kBest;
  // Run a step's refits (and kBest's two starts, and the second look's refinements) at
  // once, each on a thread of its own.
  // fit_model's result does not depend on the thread or on num_threads (docs/fitting.md,
  // "Threads and determinism"), so the decisions are the same either way; only the wall
  // time changes.
  bool parallel_refits = true;

  // --- The structure check (docs/residual-loop.md, "The structure check" and "Family before
  // stacking") ---
  // At each step, once the step's refits are judged (or when the loop stops: no candidate is
  // left, or max_steps, then the final model is examined once more without refits): when the
  // held-out window RMSE is more than structure_noise_ratio times the noise floor the
  // examination estimates from the residual itself (ResidualExamination::noise_floor_rad_s),
  // and neither the best candidate's share of the residual (linear or second look) nor the
  // best refit's fall of the held-out RMSE reaches structure_max_explained_fraction, the loop
  // fits the other model family (sensory <-> physical, the reference door of that family as
  // the start) before it adds anything more. It does so once. It names the other family the
  // better structure when its held-out RMSE is lower by more than min_held_out_improvement
  // and its BIC lower too; then the loop goes on in that family (the step under way is
  // abandoned) and refits the effects it had added before in the new family, keeping each
  // only if it qualifies there.
  bool structure_check = true;
  double structure_max_explained_fraction = 0.5;
  double structure_noise_ratio = 4.0;
  // The other family's free parameters; empty: for the physical model a small set the
  // strokes determine (J_d, k_s, F0, T_h, mu_g), for the sensory model its default set.
  std::vector<std::string> structure_free_parameters;

  // Called with one line at each stage (fits, the ranking, each verdict); may be empty.
  std::function<void(const std::string&)> progress;
  // Called when a step's refits are known (refits_done 0; not for a step without refits,
  // which ends the loop) and after each of them (from the thread that ran it, never two at
  // once); may be empty. fit.progress reports the start
  // model's fit and the structure check's; the refits (several at once) do not report.
  std::function<void(const LoopProgress&)> step_progress;
  // Asked, on the caller's thread, at the loop's stage boundaries: before each step, after
  // each step's residual examination (before its refits) and before the structure check.
  // When it returns true the loop stops there: the steps accepted so far are kept, the
  // step under way is abandoned (a step whose refits have run is finished first), the
  // structure check is not run and LoopResult::interrupted is set. The loop's fits ask it
  // too (as fit.stop_requested, when that is empty) and end at their next solver iteration:
  // the step under way is then abandoned the same way, and a stop during the start model's
  // fit throws StopRequested (nothing was finished). May be empty (never stop). `doorbench
  // loop` sets it from a SIGINT/SIGTERM flag (a lock-free atomic the signal handler sets).
  StopHook stop_requested;

  // Empty when usable, else a one-line message naming the option.
  std::string validate() const;
};

// Figures of one fitted model, the loop's "before" and "after".
struct ModelFigures {
  double fitted_rmse_rad_s = 0.0;    // window RMSE of ω on the fitted strokes
  double fitted_fit_percent = 0.0;   // window FIT% on the fitted strokes
  double held_out_rmse_rad_s = 0.0;  // the same on held-out strokes (cross-validation)
  double held_out_fit_percent = 0.0;
  // BIC = n ln(SSR/n) + p ln(n) of the window least-squares problem: n its residuals, SSR
  // their weighted sum of squares (residual_variance · (n − p)), p the free parameters plus
  // the estimated window start states.
  std::size_t residuals = 0;
  int free_parameters = 0;  // the model's free parameters
  int parameters = 0;       // p: free parameters plus window start states
  double sum_of_squares = 0.0;
  double bic = 0.0;
  // The window samples behind the two RMSEs: a refit is compared with its parent on the same
  // windows, so these (and `residuals`) are equal for both.
  std::size_t fitted_samples = 0;
  std::size_t held_out_samples = 0;
};
ModelFigures model_figures(const FitSummary& summary);

// One candidate effect as the residual examination and (if refitted) its fit saw it.
struct CandidateEvidence {
  effects::Kind kind = effects::Kind::kViscousDamping;
  std::string name;
  // The share of Σ(ω − ω̂)² over the windows that the effect's best amplitude removes, to
  // first order (0 when the best amplitude has the wrong sign for the effect's bounds).
  // The free parameters' own sensitivities are projected out first (they are refitted with
  // the effect), so this is the first-order gain of the refit: a score test.
  double explained_fraction = 0.0;
  // The share of the effect's regressor (Σx²) the free parameters cannot mimic; near 0 the
  // effect is indistinguishable from them (the inertia error while J is free).
  double independent_share = 0.0;
  // The significance of the amplitude: â = x·Pe / |Px|² (x its regressor, e the rate
  // residual, P the projection above) over its window-clustered standard error
  // √(Σ_w (Px·(Pe − â Px))_w²) / |Px|² (a Wald test robust to errors correlated within a
  // window). About |N(0, 1)| when the effect is absent; 0 when the amplitude is clamped to 0.
  double score_z = 0.0;
  int rank = 0;  // 1 = explains the most
  // The effect's parameters for the refit's start, in the catalogue's order: the amplitude
  // from the regression (clamped into bounds), nonlinear ones from the scan's best point.
  std::vector<double> start_values;
  std::string scan;  // the scanned values chosen, e.g. "w_s = 0.05"; empty when none

  // The second look (LoopOptions::screen_steps), when it was taken: the share of the
  // examination's Σe² that the effect removes once it and the free parameters are refined
  // (against the model without it, refined the same way), the refined amplitude's z
  // (window-clustered), and the refined effect parameters, the refit's start when the
  // second look promotes the candidate.
  bool screened = false;
  bool promoted = false;  // refitted on the second look's evidence alone
  double screen_explained_fraction = 0.0;
  double screen_score_z = 0.0;
  std::vector<double> screen_values;

  bool refitted = false;
  // Refitted after a family switch because the loop had added it in the other family
  // (docs/residual-loop.md, "Family before stacking"), whatever its share and z: it is kept
  // only if it qualifies in the new family.
  bool reexamined = false;
  // "the current fit", "the start model" or "the parent's optimum (the effect at neutral)"
  // (LoopOptions::RefitStart), with " (the parent's fit stands)" when parent_stands.
  std::string refit_start;
  // No refit ended with a fitted sum of squares at or below the parent's: the refit is the
  // parent's optimum with the effect at its neutral value (zero torque), whose figures are
  // the parent's with p larger by the effect's free parameters. Never qualifies.
  bool parent_stands = false;
  ModelFigures before;                // the parent's figures: the model the refit extends
  std::optional<ModelFigures> after;  // the refit's figures
  // The effect's parameters as the refit left them ("<effect>.<param>", with standard
  // uncertainty, at_bound and determined); at neutral, without uncertainty, when
  // parent_stands.
  std::vector<FittedParameter> parameters;
  double held_out_improvement = 0.0;  // (before − after) / before, held-out window RMSE
  double bic_change = 0.0;            // after − before
  // Passed both tests, and no free parameter of the effect ended at a bound or undetermined.
  bool qualifies = false;
  std::string verdict;  // "not refitted: ...", "held-out RMSE fell 0.8% (needs > 2%)", ...
};

// The rate residual in one band of measured speed |ω| (low ≤ |ω| < high): where the model
// misses. Breakaway friction shows below about 0.1 rad/s, a missing weight at all speeds.
struct SpeedBand {
  double low_rad_s = 0.0, high_rad_s = 0.0;
  std::size_t samples = 0;
  double rms_rad_s = 0.0;  // √(mean (ω − ω̂)²) over the band's samples; 0 when none
};

// The bands of the examination: [0, 0.01), [0.01, 0.05), [0.05, 0.2), [0.2, 0.5), [0.5, ∞) rad/s.
inline constexpr double kSpeedBandEdges_rad_s[] = {0.0, 0.01, 0.05, 0.2, 0.5};

// The residual examination of one model (step 2 of the loop), without refits.
struct ResidualExamination {
  std::size_t samples = 0;           // rate residuals used (window samples after the first)
  double rate_sum_of_squares = 0.0;  // Σ(ω − ω̂)², rad²/s²
  // The noise floor of the window RMSE, from the residual's own differences along each
  // window (docs/residual-loop.md, "The structure check"): with e_j the residual at the
  // j-th sample of a window, white measurement noise σ² and a random walk of q per sample
  // (the measured force's noise integrated by the simulation) give a variance of
  // e_j − e_{j−1} of q + 2σ² and of e_j − e_{j−2} of 2q + 2σ², each taken about its window's
  // mean; a model error, smooth along a window, shifts the differences' mean and adds little
  // to their variance. The floor is √(σ² + q·mean j), what a right model would leave.
  double white_noise_rad_s = 0.0;      // σ
  double walk_per_sample_rad_s = 0.0;  // √q
  double noise_floor_rad_s = 0.0;
  std::vector<CandidateEvidence> candidates;  // best first
  std::vector<SpeedBand> speed_bands;         // the residual by measured speed
  double time_s = 0.0;                        // wall clock, the second look included
  double screen_time_s = 0.0;                 // the second look's share of it
};

struct LoopStep {
  int number = 0;                              // 1, 2, ...
  ModelKind model_kind = ModelKind::kSensory;  // the family the effect was added to
  effects::Kind effect = effects::Kind::kViscousDamping;
  std::string effect_name;
  // The evidence that had it refitted: the examination's linear share and z, or the second
  // look's when that promoted it (second_look).
  double explained_fraction = 0.0;
  double score_z = 0.0;
  bool second_look = false;
  int rank = 0;  // among `candidates`
  // The added effect's parameters as the step's fit left them ("<effect>.<param>", with
  // standard uncertainty).
  std::vector<FittedParameter> parameters;
  ModelFigures before, after;
  double held_out_improvement = 0.0;
  double bic_change = 0.0;
  std::vector<CandidateEvidence> candidates;  // the whole ranking, with every refit's verdict
  std::vector<SpeedBand> speed_bands;         // the examination's residual by speed
};

// The structure check's comparison (LoopOptions::structure_check): the loop's final model
// against the other model family fitted to the same data with the loop's fit options, but
// for the free set (structure_free_parameters) and, for the physical model, monotonic steps
// (FitOptions::nonmonotonic_steps false).
struct StructureCheck {
  bool ran = false;                      // false: `reason` says why not
  std::string reason;                    // the conditions met, or the one that was not
  double noise_floor_rad_s = 0.0;        // the last examination's
  double best_explained_fraction = 0.0;  // the best remaining candidate's share
  ModelKind current_kind = ModelKind::kSensory;
  ModelKind other_kind = ModelKind::kPhysical;
  ModelFigures current, other;                  // held-out RMSE, BIC, parameters of both
  std::vector<std::string> other_free;          // the other family's free parameters
  std::vector<std::string> other_undetermined;  // those the data did not determine
  bool other_better = false;
  double held_out_improvement = 0.0;  // (current − other) / current, held-out window RMSE
  double bic_change = 0.0;            // other − current
  // Catalogue effects the examination of the other family's fit still ranks above the
  // refit thresholds (share and z), best first: what that family leaves unexplained.
  std::vector<CandidateEvidence> remaining;
  std::optional<FitResult> other_fit;
  std::string verdict;
  // When it ran: after this many steps had been accepted, on the examination and refits of
  // the step under way (`candidates`, with their verdicts). When the other family is the
  // better structure the loop switches to it (`switched`): that step is abandoned, the other
  // family's fit is the new current model, and the effects added before are refitted in it
  // (CandidateEvidence::reexamined); `reexamined` says what became of each ("force_offset:
  // dropped: ...", "gravity_imbalance: kept (step 3)").
  int after_steps = 0;
  bool switched = false;
  std::vector<CandidateEvidence> candidates;
  std::vector<std::string> reexamined;
};

struct LoopResult {
  FitResult start_fit;  // the start model's fit (step 0)
  FitResult final_fit;  // the fit of the final model (= start_fit when nothing was added)
  std::vector<LoopStep> steps;
  // The examination that ended the loop, with why each candidate failed (empty when the
  // loop stopped at max_steps or ran out of candidates).
  std::vector<CandidateEvidence> last_candidates;
  std::vector<SpeedBand> last_speed_bands;  // that examination's residual by speed
  std::string stop_reason;
  // LoopOptions::stop_requested stopped the loop before its end: `steps` are those finished
  // before it, stop_reason says where it stopped, and the structure check did not run.
  bool interrupted = false;
  int fits = 0;  // calls of fit_model
  double total_time_s = 0.0;
  LoopOptions options;       // as given
  StructureCheck structure;  // the loop's last step when it ran

  const DoorModel& model() const { return final_fit.model; }
  std::string brief_report() const;  // a few lines: the effects added and the error
  std::string full_report() const;   // every step's evidence, parameters, figures, verdicts
};

// Why a refit's effect parameters rule the effect out (empty when they do not): each free
// parameter of `parameters` (the effect's, "<effect>.<param>", in the catalogue's order) that
// ended at a bound or undetermined, e.g. "end_stop.theta_e = -0.1 rad at its lower bound -0.1
// (the end of the search range, not a physical limit), undetermined". A bound at the
// catalogue's physical minimum (EffectParameter::minimum) is called a physical limit, and
// for an amplitude there "where the effect vanishes"; "; " between parameters.
std::string refit_parameter_problems(effects::Kind kind,
                                     const std::vector<FittedParameter>& parameters);

// Why a refit's amplitude does not tell the effect apart from nothing (empty when it does):
// the effect's first parameter (`parameters[0]`, free and determined) lies fewer than
// `min_z` of its standard uncertainties from `neutral` (0; for Stribeck the refit's d1),
// e.g. "viscous_damping.b = 1.626 +- 1.611 N*m*s/rad is 1.01 standard uncertainties from
// its neutral value 0 (needs 4)". Empty for a held, undetermined or missing amplitude (the
// first two are refit_parameter_problems' to name) and for min_z 0.
std::string weak_amplitude_problem(const std::vector<FittedParameter>& parameters, double neutral,
                                   double min_z);

// Step 2 alone: how much of the rate residual of `model` on `data` (windows as in
// options.fit) each candidate effect of options.candidates would explain, best first.
// The model's parameters are used as they are (fit it first).
ResidualExamination examine_residual(const DoorModel& model, const PreparedData& data,
                                     const LoopOptions& options = {});

// The whole loop. Throws std::invalid_argument for unusable options (the validate()
// message) or data, and whatever fit_model throws for the start model's fit.
LoopResult run_residual_loop(const DoorModel& start, const PreparedData& data,
                             const LoopOptions& options = {});

}  // namespace doorbench
