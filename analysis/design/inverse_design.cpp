// The inverse design (inverse_design(); docs/inverse-design.md): its options and their
// validation, the TO-BE data merged, and the run's stages but the sparse search's
// (sparse_search.cpp): the set-up, the starts, the smallest change and the fewest-changes
// search, the equivalent designs kept, the notes on the fit.
#include "analysis/design/inverse_design.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include "analysis/design/internal/design_run.h"
#include "core/clock.h"
#include "core/number_format.h"

namespace doorbench {

using namespace design_detail;

namespace {

// A best fit missing the data by more than this many rate-noise levels gets a note.
constexpr double kMissedFeelFactor = 10.0;
// A perturbed start that breaks a constraint is retried this many times at half the step.
constexpr int kStartShrinks = 4;

bool finite_positive(double value) {
  return std::isfinite(value) && value > 0;
}

// s_i: the width of the parameter's bounds; its AS-IS magnitude (or 1) when the bounds
// have no usable width.
double change_scale(double as_is, const Bounds& bounds) {
  const double width = bounds.upper - bounds.lower;
  if (std::isfinite(width) && width > 0) return width;
  return std::abs(as_is) > 0 ? std::abs(as_is) : 1.0;
}

int find_or_throw(const DoorModel& model, const std::string& name, const char* option) {
  const std::optional<int> index = model.find_parameter(name);
  if (!index) {
    throw std::invalid_argument(std::string("inverse design: ").append(option) + " names '" + name +
                                "', which the physical model does not have");
  }
  return *index;
}

}  // namespace

std::map<std::string, double> default_costs_of_change() {
  return {
      // Cheap: adjustments, lubricant, a spring part.
      {"F0", 1.0},
      {"A_x", 1.0},
      {"A_y", 1.0},
      {"T_h", 1.0},
      {"b_h", 1.0},
      {"mu_g", 1.0},
      {"mu_l", 1.0},
      {"k_l", 1.0},
      {"F_l0", 1.0},
      {"k_seal", 1.0},
      // Moderate: another spring, a changed bracket or seal profile.
      {"k_s", 3.0},
      {"L0", 3.0},
      {"B_u", 3.0},
      {"B_v", 3.0},
      {"theta_seal", 3.0},
      // Expensive: new latch tooling, a new door.
      {"r_l", 10.0},
      {"h", 10.0},
      {"alpha_o", 10.0},
      {"alpha_c", 10.0},
      {"m_d", 30.0},
      {"l_c", 30.0},
      {"J_d", 30.0},
  };
}

std::vector<std::string> default_fixed_design_parameters() {
  return {"m_d", "l_c", "J_d", "k_stop", "c_stop", "e", "w_f"};
}

FitOptions InverseDesignOptions::default_fit_options() {
  FitOptions fit;
  fit.cross_validation_folds = 0;
  // The design's starts are its own (AS-IS, the sparse search's parts, the perturbed starts):
  // of the global stage only the start as given is screened, no reset start is polished, no
  // start is fitted with softer switches and the best is not polished again.
  fit.global_subsets = 0;
  fit.global_samples = 0;
  fit.global_reset = false;
  fit.global_repolish = 0;
  fit.global_soft_switches.clear();
  return fit;
}

std::string InverseDesignOptions::validate() const {
  if (!std::isfinite(regularization) || regularization < 0) {
    return "inverse design regularization must be >= 0";
  }
  if (starts < 1 || starts > 32) return "inverse design starts must be between 1 and 32";
  if (!finite_positive(perturbation)) return "inverse design perturbation must be > 0";
  if (!finite_positive(distinct_threshold)) {
    return "inverse design distinct_threshold must be > 0";
  }
  if (!std::isfinite(equivalent_cost_tolerance) || equivalent_cost_tolerance < 0) {
    return "inverse design equivalent_cost_tolerance must be >= 0";
  }
  if (!finite_positive(bound_widening)) return "inverse design bound_widening must be > 0";
  if (!std::isfinite(infeasibility_cost_tolerance) || infeasibility_cost_tolerance < 0) {
    return "inverse design infeasibility_cost_tolerance must be >= 0";
  }
  if (fewest_changes_refits < 0) return "inverse design fewest_changes_refits must be >= 0";
  if (smallest_change_starts < 1 || smallest_change_starts > 32) {
    return "inverse design smallest_change_starts must be between 1 and 32";
  }
  if (sparse_max_parts < 1) return "inverse design sparse_max_parts must be >= 1";
  if (sparse_refits_per_step < 1) return "inverse design sparse_refits_per_step must be >= 1";
  if (!finite_positive(sparse_min_improvement)) {
    return "inverse design sparse_min_improvement must be > 0";
  }
  if (!std::isfinite(significant_uncertainties) || significant_uncertainties < 0) {
    return "inverse design significant_uncertainties must be >= 0";
  }
  if (!std::isfinite(significant_fraction_of_bounds) || significant_fraction_of_bounds < 0) {
    return "inverse design significant_fraction_of_bounds must be >= 0";
  }
  for (const auto& [name, weight] : weights) {
    if (!std::isfinite(weight) || weight < 0) {
      return "inverse design weights: the cost of change of '" + name + "' must be >= 0";
    }
  }
  if (!fit.priors.empty()) {
    return "inverse design fit.priors must be empty (the priors are the AS-IS design's)";
  }
  for (const FeltJnd& jnd : felt_jnds) {
    const bool known =
        std::any_of(kFeltQuantities.begin(), kFeltQuantities.end(),
                    [&](const FeltQuantityInfo& info) { return info.name == jnd.quantity; });
    if (!known) return "inverse design felt_jnds: no felt quantity named '" + jnd.quantity + "'";
    if (!finite_positive(jnd.weber_fraction)) {
      return "inverse design felt_jnds: the Weber fraction of " + jnd.quantity + " must be > 0";
    }
  }
  if (!felt_jnds.empty()) {
    if (std::string message = felt.validate(); !message.empty()) return message;
  }
  if (fit.objective != FitOptions::Objective::kWindows) {
    return "inverse design fit.objective must be the window objective";
  }
  return fit.validate();
}

PreparedData merge_prepared(const std::vector<PreparedData>& data) {
  if (data.empty()) throw std::invalid_argument("inverse design: no TO-BE data");
  if (data.size() == 1) return data.front();
  PreparedData merged;
  const PreparedData* radius_source = nullptr;
  for (const PreparedData& part : data) {
    if (part.handle_radius_m > 0) {
      if (radius_source == nullptr) {
        radius_source = &part;
      } else if (std::abs(part.handle_radius_m - radius_source->handle_radius_m) >
                 1e-6 * radius_source->handle_radius_m) {
        throw std::invalid_argument(
            "inverse design: the TO-BE recordings' handle radii differ: '" + radius_source->source +
            "' has " + format_number(radius_source->handle_radius_m) + " m, '" + part.source +
            "' has " + format_number(part.handle_radius_m) + " m");
      }
    }
    merged.source += (merged.source.empty() ? "" : " + ") + part.source;
    merged.sample_rate_hz = std::max(merged.sample_rate_hz, part.sample_rate_hz);
    merged.angle_noise_rad = std::max(merged.angle_noise_rad, part.angle_noise_rad);
    merged.rate_noise_rad_s = std::max(merged.rate_noise_rad_s, part.rate_noise_rad_s);
    for (const Stroke& stroke : part.strokes) {
      merged.strokes.push_back(stroke);
      merged.strokes.back().id = static_cast<int>(merged.strokes.size());  // unique ids
    }
    for (const ExcludedSegment& segment : part.excluded) merged.excluded.push_back(segment);
    for (const std::string& note : part.notes) merged.notes.push_back(part.source + ": " + note);
  }
  if (radius_source != nullptr) {
    merged.handle_radius_m = radius_source->handle_radius_m;
    merged.geometry_calibration_id = radius_source->geometry_calibration_id;
  }
  merged.angle_source = data.front().angle_source;
  merged.notes.push_back(std::to_string(data.size()) +
                         " recordings merged; strokes renumbered 1.." +
                         std::to_string(merged.strokes.size()) + " in order");
  return merged;
}

namespace {

const DesignSolution* lowest_cost(const std::vector<DesignSolution>& found) {
  const auto best = std::min_element(found.begin(), found.end(), [](const auto& a, const auto& b) {
    return a.data_cost < b.data_cost;
  });
  return best == found.end() ? nullptr : &*best;
}

}  // namespace

namespace design_detail {

void DesignRun::set_up() {
  const int n = asis_.parameter_count();
  std::vector<char> free(n, 0);
  const std::vector<std::string> candidates = options_.fit.free_parameters.empty()
                                                  ? default_free_parameters(asis_)
                                                  : options_.fit.free_parameters;
  for (const std::string& name : candidates) {
    free[find_or_throw(asis_, name, "fit.free_parameters")] = 1;
  }
  fit_ = options_.fit;
  fit_.what_would_determine = false;  // the design's reports do not show its fits' proposals
  for (const std::string& name : options_.fixed) {
    free[find_or_throw(asis_, name, "fixed")] = 0;
    fit_.fixed_parameters.push_back(name);
  }
  for (const std::string& name : options_.fit.fixed_parameters) {
    free[find_or_throw(asis_, name, "fit.fixed_parameters")] = 0;
  }
  setup_.as_is.assign(asis_.parameter_values().begin(), asis_.parameter_values().end());
  setup_.significant_uncertainties = options_.significant_uncertainties;
  setup_.significant_fraction_of_bounds = options_.significant_fraction_of_bounds;
  const auto bounds = asis_.parameter_bounds();
  for (int i = 0; i < n; ++i) {
    if (free[i]) setup_.free_index.push_back(i);
    setup_.scale.push_back(change_scale(setup_.as_is[i], bounds[i]));
    setup_.weight.push_back(1.0);
  }
  if (setup_.free_index.empty()) {
    throw std::invalid_argument("inverse design: every parameter is fixed; nothing to design");
  }
  for (const auto& [name, weight] : options_.weights) {
    setup_.weight[find_or_throw(asis_, name, "weights")] = weight;
  }
  lambda_ = options_.regularization;
  set_priors(lambda_);
  result_.rate_noise_rad_s =
      fit_.rate_noise_rad_s > 0 ? fit_.rate_noise_rad_s : data_.rate_noise_rad_s;
  angle_noise_rad_ = fit_.angle_noise_rad > 0 ? fit_.angle_noise_rad : data_.angle_noise_rad;
  result_.commanded_torque = options_.use_commanded_torque && !commanded_.empty();
}

// r_i = sqrt(λ w_i) (p_i − p_asis_i) / s_i, i.e. a prior centred on AS-IS with
// σ_i = s_i / sqrt(λ w_i); a change that costs nothing gets no prior.
void DesignRun::set_priors(double lambda) {
  fit_.priors.clear();
  for (int index : setup_.free_index) {
    const double strength = lambda * setup_.weight[index];
    if (!(strength > 0)) continue;
    fit_.priors.push_back({asis_.parameter_name(index), setup_.as_is[index],
                           setup_.scale[index] / std::sqrt(strength)});
  }
}

DesignSolution DesignRun::fit_only(const DoorModel& start, int start_index,
                                   const std::vector<std::string>& held, int threads) const {
  FitOptions fit = fit_;
  if (threads > 0) fit.num_threads = threads;
  DesignSolution solution = [&] {
    if (result_.commanded_torque) {
      return fit_commanded_design(start, commanded_, data_, fit, asis_, setup_, lambda_,
                                  start_index, held);
    }
    if (held.empty()) {
      return make_solution(fit_model(start, data_, fit), asis_, setup_, lambda_, start_index);
    }
    fit.fixed_parameters.insert(fit.fixed_parameters.end(), held.begin(), held.end());
    std::erase_if(fit.priors, [&](const ParameterPrior& prior) {
      return std::find(held.begin(), held.end(), prior.parameter) != held.end();
    });
    return make_solution(fit_model(start, data_, fit), asis_, setup_, lambda_, start_index);
  }();
  solution.held_at_as_is = held;
  return solution;
}

void DesignRun::add_fit_times(const DesignSolution& solution) {
  FitSummary::Times& sum = result_.fit_times;
  const FitSummary::Times& times = solution.summary.times;
  sum.start_s += times.start_s;
  sum.equation_error_s += times.equation_error_s;
  sum.windows_s += times.windows_s;
  sum.statistics_s += times.statistics_s;
  sum.metrics_s += times.metrics_s;
  sum.held_out_s += times.held_out_s;
}

DesignSolution DesignRun::fit_design(const DoorModel& start, int start_index,
                                     const std::vector<std::string>& held) {
  ++result_.fits_run;
  DesignSolution solution = fit_only(start, start_index, held, 0);
  add_fit_times(solution);
  return solution;
}

// One pass: a fit from `origin`, then the perturbed starts around its result: ± perturbation
// along the weakest directions. The equation-error stage stays on: a start off in a
// determined direction inflates the robust uncertainties so much that the window fit's
// stopping rule would end it at once, and the stage cannot move the start along a direction
// the data do not determine.
std::vector<DesignSolution> DesignRun::run_starts(const DoorModel& origin, int pass, int starts) {
  std::vector<DesignSolution> found;
  start_notes_.clear();
  const auto report = [&](int start) {
    if (options_.progress) {
      options_.progress(printf_text("pass %d, start %d of %d", pass, start + 1, starts));
    }
  };
  report(0);
  found.push_back(fit_design(origin, 0, {}));
  result_.starts_run = 1;
  const DoorModel first_model = found.front().model;
  const auto bounds = asis_.parameter_bounds();
  const int extra = starts - 1;
  const std::vector<Eigen::VectorXd> directions =
      weak_directions(first_model, data_, fit_, result_.rate_noise_rad_s, angle_noise_rad_, setup_,
                      (extra + 1) / 2);
  for (int j = 0; j < extra && j / 2 < static_cast<int>(directions.size()); ++j) {
    const Eigen::VectorXd& direction = directions[j / 2];
    const double sign = j % 2 == 0 ? 1.0 : -1.0;
    std::optional<DoorModel> start;
    double step = options_.perturbation;
    for (int attempt = 0; attempt <= kStartShrinks && !start; ++attempt, step *= 0.5) {
      std::vector<double> values(first_model.parameter_values().begin(),
                                 first_model.parameter_values().end());
      for (std::size_t k = 0; k < setup_.free_index.size(); ++k) {
        const int index = setup_.free_index[k];
        values[index] = std::clamp(values[index] + sign * step * direction(k) * setup_.scale[index],
                                   bounds[index].lower, bounds[index].upper);
      }
      try {
        start = asis_.with_parameter_values(values);
      } catch (const std::invalid_argument&) {
        // breaks a constraint: try a smaller step
      }
    }
    if (!start) {
      start_notes_.push_back("perturbed start " + std::to_string(j + 1) +
                             " broke a constraint at every step tried; skipped");
      continue;
    }
    try {
      report(j + 1);
      found.push_back(fit_design(*start, j + 1, {}));
    } catch (const std::runtime_error& error) {
      start_notes_.push_back("the fit from perturbed start " + std::to_string(j + 1) +
                             " failed: " + error.what());
    }
    ++result_.starts_run;
  }
  return found;
}

// Adds to result.solutions the designs of found_ the data cannot tell from `reference`,
// distinct from each other and from those kept, smallest change first; notes each start.
void DesignRun::keep_equivalent(const std::vector<DesignSolution>& found,
                                const DesignSolution* reference) {
  std::vector<const DesignSolution*> order;
  const auto equivalent = [&](const DesignSolution& solution) {
    return equivalent_cost(solution.data_cost, reference->data_cost, reference->data_residuals,
                           options_.equivalent_cost_tolerance);
  };
  for (const DesignSolution& solution : found) {
    if (equivalent(solution)) order.push_back(&solution);
  }
  std::stable_sort(order.begin(), order.end(), [](const auto* a, const auto* b) {
    return a->size_of_change < b->size_of_change;
  });
  std::vector<int> kept_starts;
  for (const DesignSolution* candidate : order) {
    bool distinct = true;
    for (const DesignSolution& kept : result_.solutions) {
      distinct =
          distinct && scaled_distance(*candidate, kept, setup_) > options_.distinct_threshold;
    }
    if (!distinct) continue;
    result_.solutions.push_back(*candidate);
    kept_starts.push_back(candidate->start_index);
  }
  for (const DesignSolution& solution : found) {
    const bool kept = std::find(kept_starts.begin(), kept_starts.end(), solution.start_index) !=
                      kept_starts.end();
    result_.notes.push_back(
        printf_text("start %d: data cost %.6g, size of change %.4g: %s", solution.start_index,
                    solution.data_cost, solution.size_of_change,
                    kept                   ? "kept"
                    : equivalent(solution) ? "dropped (the same design as one kept)"
                                           : "dropped (fits clearly worse than the best)"));
  }
}

void DesignRun::smallest_change_then_fewest() {
  // The first pass starts from AS-IS with the priors as given. When its best design misses
  // the data by more than their noise (φ > 1), the priors are strengthened by φ and a second
  // pass starts from that best design.
  found_ = run_starts(asis_, 1, options_.starts);
  result_.misfit_factor = misfit_factor(*lowest_cost(found_));
  if (options_.scale_priors_by_misfit && lambda_ > 0 && result_.misfit_factor > 1.0) {
    const DesignSolution first_best = *lowest_cost(found_);
    lambda_ *= result_.misfit_factor;
    set_priors(lambda_);
    found_ = run_starts(first_best.model, 2, options_.starts);
    result_.notes.push_back(printf_text(
        "the first pass's best design missed the TO-BE data by %.3g times their %s (reduced "
        "data cost phi %.4g, data cost %.6g): the priors were strengthened by phi (effective "
        "lambda %.4g) and the design fitted again, from that design",
        std::sqrt(result_.misfit_factor),
        result_.commanded_torque ? "torque scale (0.01 N*m)" : "noise", result_.misfit_factor,
        first_best.data_cost, lambda_));
  }
  result_.effective_regularization = lambda_;
  result_.notes.insert(result_.notes.end(), start_notes_.begin(), start_notes_.end());
  best_ = lowest_cost(found_);
  keep_equivalent(found_, best_);
  rank_solutions(result_.solutions);
  if (!result_.solutions.empty() && options_.fewest_changes_refits > 0) {
    add_fewest_changes(asis_, fitter(), options_, setup_, best_->data_cost, best_->data_residuals,
                       result_.commanded_torque, result_);
  }
  if (!best_->at_bound.empty()) check_bounds(asis_, fitter(), options_, *best_, {}, result_);
}

void DesignRun::sparse_then_smallest_change() {
  const auto began = StageClock::now();
  DesignSolution sparse = sparse_search();
  result_.sparse_search_s = seconds_since(began);
  result_.misfit_factor = misfit_factor(sparse);
  if (options_.scale_priors_by_misfit && lambda_ > 0 && result_.misfit_factor > 1.0) {
    lambda_ *= result_.misfit_factor;
  }
  result_.effective_regularization = lambda_;
  result_.solutions.push_back(sparse);
  found_.push_back(std::move(sparse));
  best_ = &found_.front();
  keep_sparse_swaps();
  if (options_.smallest_change_alongside && result_.sparse_steps.size() > 1) {
    // The smallest change, every parameter free, from the sparse design, with the priors
    // strengthened by the sparse design's φ.
    set_priors(lambda_);
    std::vector<DesignSolution> smallest =
        run_starts(found_.front().model, 1, options_.smallest_change_starts);
    result_.notes.insert(result_.notes.end(), start_notes_.begin(), start_notes_.end());
    keep_equivalent(smallest, &found_.front());
    const DesignSolution* low = lowest_cost(smallest);
    if (low != nullptr && result_.felt_goal) {
      result_.every_part_fitted = true;
      result_.every_part_parts_changed = low->parts_changed;
      result_.every_part_felt_misses = felt_misses(low->model);
    }
    if (low != nullptr &&
        !equivalent_cost(found_.front().data_cost, low->data_cost, low->data_residuals,
                         options_.equivalent_cost_tolerance)) {
      result_.notes.push_back(printf_text(
          "every parameter free, the data cost falls to %.6g from the sparse design's %.6g: "
          "more than the data cannot tell apart; the parts the sparse search stopped short of "
          "are in that solution",
          low->data_cost, found_.front().data_cost));
    }
  }
  // The sparse design first (it is what the search was for), the others by their ranking.
  std::stable_sort(result_.solutions.begin() + 1, result_.solutions.end(),
                   [](const DesignSolution& a, const DesignSolution& b) {
                     return a.parts_changed_cost != b.parts_changed_cost
                                ? a.parts_changed_cost < b.parts_changed_cost
                                : a.size_of_change < b.size_of_change;
                   });
  if (!found_.front().at_bound.empty()) {
    check_bounds(asis_, fitter(), options_, found_.front(), sparse_held_, result_);
  }
}

void DesignRun::note_fit_quality() {
  if (best_ == nullptr) return;
  const double noise = result_.rate_noise_rad_s;
  const double best_rmse = best_->fit.window.rmse();
  if (result_.commanded_torque) {
    result_.notes.push_back(printf_text(
        "fitted to the torque the playback commanded; the recorded motion differs from the "
        "design's by a window RMSE of omega of %.3g rad/s (%.3g times the rate noise): the "
        "device's rendering (control delay, admittance, servo) is in the motion, not in the "
        "commanded torque",
        best_rmse, best_rmse / noise));
  } else if (result_.feasible && best_rmse > kMissedFeelFactor * noise) {
    result_.notes.push_back(printf_text(
        "the best design misses the TO-BE data by %.3g times the rate noise (%.3g rad/s; the "
        "force noise integrated by the model adds to it: compare with the AS-IS fit's figure)",
        best_rmse / noise, best_rmse));
  }
}

// The free parameters' names but those at `free_positions` (positions in free_index).
std::vector<std::string> DesignRun::names_except(const std::vector<int>& free_positions) const {
  std::vector<std::string> names;
  for (int k = 0; k < static_cast<int>(setup_.free_index.size()); ++k) {
    if (std::find(free_positions.begin(), free_positions.end(), k) != free_positions.end()) {
      continue;
    }
    names.push_back(asis_.parameter_name(setup_.free_index[k]));
  }
  return names;
}

}  // namespace design_detail

namespace {

void check_inputs(const DoorModel& asis, const std::vector<PreparedData>& tobe,
                  const InverseDesignOptions& options) {
  if (asis.kind() != ModelKind::kPhysical) {
    throw std::invalid_argument(
        "inverse design: the AS-IS model must be the physical model (its parameters are the "
        "design), not the sensory one");
  }
  if (tobe.empty()) throw std::invalid_argument("inverse design: no TO-BE data");
  if (const std::string message = options.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
}

void check_radius(const DoorModel& asis, const PreparedData& data) {
  const double radius = asis.geometry().handle_radius_m;
  if (data.handle_radius_m > 0 && std::abs(data.handle_radius_m - radius) > 1e-6 * radius) {
    throw std::invalid_argument(
        "inverse design: the TO-BE data's handle radius (" + format_number(data.handle_radius_m) +
        " m) differs from the AS-IS model's (" + format_number(radius) + " m)");
  }
}

}  // namespace

InverseDesignResult inverse_design(const DoorModel& asis, const std::vector<PreparedData>& tobe,
                                   const InverseDesignOptions& options,
                                   const std::vector<CommandedTorque>& commanded) {
  const auto began = StageClock::now();
  check_inputs(asis, tobe, options);
  const PreparedData data = merge_prepared(tobe);
  check_radius(asis, data);
  InverseDesignResult result;
  DesignRun run(asis, data, options, commanded, result);
  run.set_up();
  if (options.sparse_search && !result.commanded_torque) {
    run.sparse_then_smallest_change();
  } else {
    run.smallest_change_then_fewest();
  }
  run.note_fit_quality();
  result.total_time_s = seconds_since(began);
  return result;
}

}  // namespace doorbench
