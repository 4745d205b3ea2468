#pragma once
// The inverse design fit (docs/inverse-design.md): which physical door produces
// the TO-BE feel, recorded by haptic playback, with the smallest change to the AS-IS door.
//
//   doorbench::InverseDesignOptions options;      // default costs of change, λ, fixed set
//   doorbench::InverseDesignResult result =
//       doorbench::inverse_design(asis_physical_model, {tobe_prepared}, options);
//   std::cout << result.brief_report();
//   result.solutions.front().model;               // the first design
//
// For recordings of a door the first design is the sparse design search's (parts freed one
// at a time from AS-IS, InverseDesignOptions::sparse_search); for playbacks (commanded
// torque) the smallest change below and the fewest-changes search.
//
// The method: the physical model is fitted to the TO-BE strokes with fit_model's
// machinery (multiple shooting on windows), plus one prior residual per free parameter
// pulling it toward its AS-IS value,
//   r_i = sqrt(λ · w_i) · (p_i − p_asis_i) / s_i,
// with w_i the parameter's cost of change and s_i its scale: the width of its bounds
// (upper − lower). With λ = 0 the fit is the plain fit of the TO-BE data; the larger λ,
// the more a change must be paid for by a better fit before it is made. The residuals of
// the data are in units of their noise (σ_ω, σ_θ), so λ·w_i compares a change of one
// bound width with one noise-level of error on one sample.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "analysis/design/perceptual_tolerance.h"
#include "analysis/fit/commanded_torque.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench {

// The default cost of changing each physical parameter (relative weights w_i; 1 is a
// cheap change). Cheap: the spring preload F0 and the anchor A_x/A_y (a screw, a hole),
// friction (lubricant, bushing): T_h, b_h, mu_g, mu_l; the latch's catch spring k_l and
// preload F_l0 (a spring part); the seal's stiffness k_seal. Moderate: the spring rate k_s
// and free length L0, the lever point B_u/B_v, the seal's extent theta_seal. Expensive:
// the latch's geometry r_l, h, alpha_o, alpha_c (new tooling); the door's mass m_d, l_c,
// J_d (a new door). A parameter not in the map costs 1.
std::map<std::string, double> default_costs_of_change();

// The parameters the engineering fixes by default: m_d, l_c, J_d (known from CAD), and
// k_stop, c_stop, e, w_f (end stops and smoothing lengths: modelling devices, not design
// parameters).
std::vector<std::string> default_fixed_design_parameters();

// Thread safety: inverse_design() uses only its arguments (the fits run on options.fit's
// threads); calls on different data may run at once.

struct InverseDesignOptions {
  // Parameters kept exactly at their AS-IS values. Empty is allowed (every parameter of
  // fit.free_parameters, or of the default free set, is free); the default set is
  // default_fixed_design_parameters().
  std::vector<std::string> fixed = default_fixed_design_parameters();
  // Cost of change per parameter (w_i ≥ 0); missing parameters take 1; 0 makes a change
  // free.
  std::map<std::string, double> weights = default_costs_of_change();
  // λ: how strongly the smallest change is preferred (see above). ≥ 0. The default makes a
  // change by a whole bound width of a cheap parameter cost as much as 1000 samples missed
  // by one noise level; docs/inverse-design.md shows what it does on synthetic data.
  double regularization = 1000.0;
  // Measure the data residuals in units of the misfit the fit actually leaves rather than
  // of the recording's noise: after a first fit from AS-IS, when its reduced data cost
  // φ = Σ r² / (n − p) exceeds 1, every prior is strengthened by φ (σ_i → σ_i / √φ) and
  // the design is fitted again. Without it λ's meaning would hang on the noise level: a
  // haptic playback recording (noise 100 times below the bench's, missed by 40 noise
  // levels where the device renders the latch) made the priors 1600 times weaker than on
  // bench data, and cheap parameters drifted to absorb rendering effects.
  bool scale_priors_by_misfit = true;
  // With commanded torques given (playback recordings, analysis/fit/commanded_torque.h): fit
  // every free parameter but the inertia to them, and the inertia to the motion. Off: the
  // motion alone, as for a recording of a real door.
  bool use_commanded_torque = true;
  // Fits in all: one from AS-IS, the others from starts perturbed along the directions the
  // data determine least (eigenvectors of the information matrix's smallest eigenvalues),
  // to find distinct designs that fit equally well. ≥ 1.
  int starts = 3;
  double perturbation = 0.15;  // the perturbed starts' step, in scaled units (bound widths)
  // Two solutions are distinct when some free parameter differs by more than this, in
  // scaled units (fraction of the bound width). > 0.
  double distinct_threshold = 0.02;
  // A solution is kept when its data cost (½ Σ r² of the data residuals, the fit's
  // objective without the priors) is within this fraction of the best one's (the data
  // cannot tell them apart). ≥ 0.
  double equivalent_cost_tolerance = 0.05;
  // Feasibility check: when the best solution holds free parameters on a bound, the fit is
  // repeated with those bounds moved outward by this many bound widths (not below 0 for a
  // parameter whose lower bound is ≥ 0). The request is infeasible when that fit fits
  // the data clearly better (data cost lower by more than equivalent_cost_tolerance):
  // the data ask for more than the bounds allow. > 0.
  double bound_widening = 1.0;
  // ... and the request is infeasible when the within-bounds design's data cost is more than
  // this fraction above the widened fit's. ≥ 0.
  double infeasibility_cost_tolerance = 0.01;
  // Fewest changes: from the smallest-change solution, the changed parameters are held at
  // their AS-IS values one at a time (the smallest change first) and the design refitted,
  // keeping each hold after which it still fits equivalently. The result, when distinct, is
  // reported beside the others: the same feel with fewer parts changed (the smallest change
  // spreads a change over every parameter that can share it, such as a preload over the
  // spring's free length and anchor). At most `fewest_changes_refits` refits; 0 turns it
  // off. The inertia is never held when fitted from commanded torques (its evidence is the
  // motion).
  int fewest_changes_refits = 10;
  // Sparse design search (recordings of a door; a playback's commanded torque keeps the
  // smallest change and the fewest-changes search above): from AS-IS, free one more
  // parameter at a time, the one whose refit lowers the data cost most, and stop when the
  // best addition lowers it by less than `sparse_min_improvement` of the current data cost
  // (the misfit no longer falls measurably: what is left is noise and what the model
  // cannot show). Candidates are ranked by the Gauss–Newton predicted decrease (one
  // Jacobian at the current design) and the best `sparse_refits_per_step` are refitted.
  // Candidates whose refit fits as well as the best (equivalent_cost_tolerance) are the
  // alternatives the data cannot separate; of them the smallest weighted change
  // (w_i |Δp_i| / s_i) is chosen, so costs of change decide. The sparse design is the first
  // solution; the smallest change (every free parameter, priors strengthened by the sparse
  // design's φ) is fitted from it and reported beside it. Off: the smallest change and the
  // fewest-changes search as for playbacks.
  bool sparse_search = true;
  // With the sparse search: also fit the smallest change (every free parameter) from the
  // sparse design and report it beside it, from `smallest_change_starts` starts (the
  // perturbed ones as above; `starts` is the playback path's).
  bool smallest_change_alongside = true;
  int smallest_change_starts = 1;        // 1 to 32
  int sparse_max_parts = 6;              // ≥ 1
  int sparse_refits_per_step = 4;        // ≥ 1
  double sparse_min_improvement = 0.10;  // > 0
  // The sparse search's goal is the feel when `felt_jnds` is not empty (docs/inverse-design.md,
  // "A design that feels like the TO-BE"): it stops as soon as every felt quantity of the
  // design, read along the TO-BE recordings' motion (compare_feel with `felt`), is within its
  // JND of the recordings' (felt_as_different). While one is not, a part that lowers the data
  // cost by less than sparse_min_improvement is still added (up to sparse_max_parts) when it
  // brings the design nearer the feel (fewer JNDs missed in all); a part is dropped after the
  // forward pass only when the design without it misses no more quantities. Quantities not named
  // take their typical JND (typical_felt_jnd); a quantity the recordings leave undefined or at 0 is
  // not judged. What still misses at the end is InverseDesignResult::felt_misses.
  std::vector<FeltJnd> felt_jnds;
  FeltOptions felt;
  // A change counts (listed, highlighted, counted in parts_changed_cost) only when it is
  // larger than `significant_uncertainties` times its uncertainty (when finite) and than
  // `significant_fraction_of_bounds` of its bound width. ≥ 0.
  double significant_uncertainties = 1.0;
  double significant_fraction_of_bounds = 0.005;
  // Called before each fit with a line saying which (pass, start, refit); may be empty. Called
  // on the calling thread.
  std::function<void(const std::string&)> progress;
  // The fit's options (windows, solver, uncertainties). Its free_parameters are the
  // candidates (empty: the default free set); fixed_parameters are added to `fixed`.
  // Cross-validation is off by default here (it refits per fold, per start).
  FitOptions fit = default_fit_options();

  static FitOptions default_fit_options();
  // Empty when usable, else a one-line message naming the option.
  std::string validate() const;
};

struct DesignParameter {
  std::string name;
  std::string unit;
  bool free = false;
  double as_is = 0.0;
  double to_be = 0.0;
  double change = 0.0;           // to_be − as_is
  double relative_change = 0.0;  // change / |as_is| (NaN when as_is is 0)
  double uncertainty = 0.0;      // the fit's standard uncertainty of to_be (NaN when fixed)
  double weight = 0.0;           // its cost of change
  Bounds bounds;
  bool at_bound = false;
  // Free, and changed by more than significant_uncertainties × uncertainty and
  // significant_fraction_of_bounds × the bound width: a part to change.
  bool changed = false;
};

struct DesignSolution {
  DoorModel model;                          // the TO-BE physical door (checked)
  std::vector<DesignParameter> parameters;  // every parameter, in the model's order
  // Fit of the TO-BE data by this model (the data part only, without the priors).
  FitMetrics fit;
  double data_cost = 0.0;  // ½ Σ r² of the data residuals
  // Σ r² / (n − p) of the data residuals: 1 when the design misses the data by their noise
  // (or, fitted to commanded torques, by the torque scale) only.
  double reduced_data_cost = 1.0;
  double prior_cost = 0.0;  // ½ Σ r² of the prior residuals
  // √(Σ w_i ((p_i − p_asis_i)/s_i)²): the weighted size of the change.
  double size_of_change = 0.0;
  // Σ w_i over the parameters whose change counts (DesignParameter::changed): what the
  // change costs in parts (a spring changed by 5 % or by 10 % is one new spring).
  double parts_changed_cost = 0.0;
  int parts_changed = 0;  // how many parameters' changes count
  // Which start found it (0: from AS-IS; −1: the feasibility refit; −2: the fewest-changes
  // search; kSparseSearch: the sparse design search).
  int start_index = 0;
  static constexpr int kSparseSearch = -3;
  int data_residuals = 0;  // n of the data cost
  // Free parameters held at their AS-IS values (the fewest-changes alternative).
  std::vector<std::string> held_at_as_is;
  // The sparse design with one part swapped for one its step could not tell from it:
  // "F0 -> L0" (the part, then the one in its place); empty otherwise.
  std::string swapped{};
  bool converged = false;
  std::vector<std::string> at_bound;  // free parameters on a bound
  FitSummary summary;                 // the underlying fit's summary
};

// A felt quantity of the design that a panel member would feel as different from the TO-BE's
// (InverseDesignOptions::felt_jnds).
struct FeltMiss {
  std::string quantity;     // a kFeltQuantities name
  double design = 0.0;      // the design's, along the TO-BE recordings' motion
  double tobe = 0.0;        // the recordings'
  double difference = 0.0;  // design − tobe, in the quantity's unit
  // |ln(design / tobe)| / ln(1 + w): how many JNDs apart (infinite when the sign differs).
  double jnds = 0.0;
  FeltJnd jnd;
};

// One step of the sparse design search: the parameter freed and the fit with it.
struct SparseStep {
  std::string added;              // empty for step 0, AS-IS
  std::vector<std::string> free;  // every parameter free after this step
  double data_cost = 0.0;
  double reduced_data_cost = 0.0;  // φ
  double window_rmse_rad_s = 0.0;
  // Candidates refitted at this step: (name, data cost), best first. Those whose cost the
  // data cannot tell from the chosen one's are in `equivalent`.
  std::vector<std::pair<std::string, double>> tried;
  std::vector<std::string> equivalent;
};

struct InverseDesignResult {
  // Distinct solutions that fit the TO-BE data equally well, ranked by the size of the
  // change: the fewest parts first (parts_changed_cost), then the smallest size_of_change.
  // With the sparse search its design is first whatever the ranking (the smallest change
  // beside it is kept when it fits equivalently; a note says when it fits clearly better;
  // so is the sparse design with a part swapped for a candidate of its step that fitted
  // alike, refitted: DesignSolution::swapped).
  std::vector<DesignSolution> solutions;
  bool feasible = true;
  // When infeasible: which parameters bind at which bound and what the data asked for
  // (the fit with widened bounds); the first solution is then the nearest feasible design.
  std::string infeasibility;
  // The binding parameters as the fit with widened bounds has them (to_be: what the data
  // ask for); empty when no bound binds.
  std::vector<DesignParameter> requested;
  double requested_rmse_rad_s = 0.0;  // that fit's window RMSE of ω (0 when not run)
  double requested_data_cost = 0.0;   // and its data cost
  double rate_noise_rad_s = 0.0;      // the TO-BE data's σ_ω
  // φ: the first fit's reduced data cost Σ r² / (n − p) (1 for a model that misses the data
  // by their noise only); the priors were strengthened by it when it is above 1 and
  // scale_priors_by_misfit is on. λ·φ is the effective regularization.
  double misfit_factor = 1.0;
  bool commanded_torque = false;  // the design was fitted to commanded torques
  double effective_regularization = 0.0;
  int starts_run = 0;
  // The sparse design search (empty when not run): AS-IS, then one row per part freed; and
  // why it stopped.
  std::vector<SparseStep> sparse_steps;
  std::string sparse_stop;
  // With InverseDesignOptions::felt_jnds: the search's goal was the feel; the first
  // solution's felt quantities that still miss their JND of the TO-BE's (empty: it feels like
  // the TO-BE), and every part the sparse search refitted, in the order first tried.
  bool felt_goal = false;
  std::vector<FeltMiss> felt_misses;
  std::vector<std::string> parts_tried;
  // With the feel as the goal and the smallest change fitted beside the sparse design
  // (smallest_change_alongside): that fit's felt misses, every free parameter free (its lowest
  // data cost of its starts), and the parts it changes. They tell a miss of the model family
  // from a miss of the sparse search. every_part_fitted is false when it was not fitted.
  bool every_part_fitted = false;
  int every_part_parts_changed = 0;
  std::vector<FeltMiss> every_part_felt_misses;
  int fits_run = 0;              // fits of every kind (starts, refits, candidates)
  double sparse_search_s = 0.0;  // wall time of the sparse search (the rest: the smallest
                                 // change beside it, the feasibility refit)
  FitSummary::Times fit_times;   // where the fits' time went, summed over every fit
  double total_time_s = 0.0;
  std::vector<std::string> notes;

  // One sentence per felt miss: "the design does not feel like the TO-BE: its peak force to
  // latch (N) is 53.1 against the TO-BE's 9.48 (+43.6, 12.3 JNDs; JND 15 %, typical: stiffness
  // 15%); the sparse search tried F0, L0", and when every_part_fitted "; with every part free
  // (9 parts changed) 12.1 JNDs" or "...) within its JND"; empty when there is none.
  std::vector<std::string> felt_miss_warnings() const;
  std::string brief_report() const;  // a few lines: feasible?, biggest changes
  std::string full_report() const;   // every solution, every parameter, the fit metrics
};

// Merges several prepared recordings into one (strokes renumbered so that ids stay unique,
// noise levels the largest of theirs). Throws std::invalid_argument when their handle
// radii differ (naming the sources) or `data` is empty.
PreparedData merge_prepared(const std::vector<PreparedData>& data);

// `asis` must be a physical model (its values are the AS-IS design and the start, its
// bounds the feasible range). Throws std::invalid_argument for a sensory model, an empty
// `tobe`, unusable options (the validate() message), unknown parameter names in fixed or
// weights, or TO-BE data whose handle radius differs from the model's.
//
// `commanded`: the commanded torques of the TO-BE recordings when they are haptic
// playbacks (read_commanded_torque); empty for recordings of a real door.
InverseDesignResult inverse_design(const DoorModel& asis, const std::vector<PreparedData>& tobe,
                                   const InverseDesignOptions& options = {},
                                   const std::vector<CommandedTorque>& commanded = {});

}  // namespace doorbench
