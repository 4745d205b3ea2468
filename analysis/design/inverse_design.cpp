#include "analysis/design/inverse_design.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <stdexcept>

#include "analysis/fit/commanded_torque.h"
#include "analysis/fit/fit_problem.h"
#include "core/clock.h"
#include "core/number_format.h"

namespace doorbench {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// A best fit missing the data by more than this many rate-noise levels gets a note.
constexpr double kMissedFeelFactor = 10.0;
// A perturbed start that breaks a constraint is retried this many times at half the step.
constexpr int kStartShrinks = 4;
// A parameter counts as a changed part when it moves by more than this fraction of its
// scale (the bound width).
constexpr double kChangedFraction = 1e-3;
// The physical model's inertia: the commanded torque does not contain it.
constexpr const char* kInertiaParameter = "J_d";
// The unit of the commanded-torque residuals before φ rescales the priors: the torque is
// exact, so any unit well below what is felt serves (0.01 N*m is 0.017 N at the handle).
constexpr double kCommandedTorqueScale_Nm = 0.01;
// Two refits of the sparse search whose data costs differ by less than this fraction fit
// the same (a degenerate pair of parameters).
constexpr double kSameCost = 1e-4;

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

bool on_bound(double value, const Bounds& bounds) {
  const double width = bounds.upper - bounds.lower;
  return std::abs(value - bounds.lower) <= 1e-6 * width ||
         std::abs(bounds.upper - value) <= 1e-6 * width;
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

struct Setup {
  std::vector<int> free_index;                  // model order
  std::vector<double> as_is;                    // every parameter
  std::vector<double> scale;                    // s_i, every parameter
  std::vector<double> weight;                   // w_i, every parameter
  double significant_uncertainties = 1.0;       // a change counts when larger than these
  double significant_fraction_of_bounds = 0.0;  // (InverseDesignOptions)
};

// Whether a free parameter's change counts (InverseDesignOptions::significant_*).
bool significant_change(const DesignParameter& p, const Setup& setup, double scale) {
  if (!p.free) return false;
  const double change = std::abs(p.change);
  if (std::isfinite(p.uncertainty) && change <= setup.significant_uncertainties * p.uncertainty) {
    return false;
  }
  return change > setup.significant_fraction_of_bounds * scale;
}

// A design at `model`: every parameter against AS-IS, the size of the change and the prior
// cost; the caller sets data_cost and reduced_data_cost.
DesignSolution describe_design(const DoorModel& model, const std::vector<double>& uncertainty,
                               const FitMetrics& metrics, bool converged, const FitSummary& summary,
                               const DoorModel& asis, const Setup& setup, double lambda,
                               int start_index) {
  DesignSolution solution{.model = model,
                          .parameters = {},
                          .fit = metrics,
                          .start_index = start_index,
                          .held_at_as_is = {},
                          .converged = converged,
                          .at_bound = {},
                          .summary = summary};
  const auto values = model.parameter_values();
  const auto bounds = asis.parameter_bounds();
  double weighted = 0.0;
  for (int i = 0; i < asis.parameter_count(); ++i) {
    DesignParameter parameter;
    parameter.name = asis.parameter_name(i);
    parameter.unit = std::string(asis.parameter_unit(i));
    parameter.free =
        std::find(setup.free_index.begin(), setup.free_index.end(), i) != setup.free_index.end();
    parameter.as_is = setup.as_is[i];
    parameter.to_be = values[i];
    parameter.change = parameter.to_be - parameter.as_is;
    parameter.relative_change =
        parameter.as_is != 0 ? parameter.change / std::abs(parameter.as_is) : kNaN;
    parameter.uncertainty = parameter.free ? uncertainty[i] : kNaN;
    parameter.weight = setup.weight[i];
    parameter.bounds = bounds[i];
    parameter.at_bound = parameter.free && on_bound(parameter.to_be, bounds[i]);
    if (parameter.at_bound) solution.at_bound.push_back(parameter.name);
    const double scaled = parameter.change / setup.scale[i];
    weighted += parameter.weight * scaled * scaled;
    parameter.changed = significant_change(parameter, setup, setup.scale[i]);
    if (parameter.changed) {
      solution.parts_changed_cost += parameter.weight;
      ++solution.parts_changed;
    }
    if (parameter.free) solution.prior_cost += 0.5 * lambda * parameter.weight * scaled * scaled;
    solution.parameters.push_back(std::move(parameter));
  }
  solution.size_of_change = std::sqrt(weighted);
  return solution;
}

// A design from a fit of the TO-BE motion.
DesignSolution make_solution(const FitResult& fit, const DoorModel& asis, const Setup& setup,
                             double lambda, int start_index) {
  std::vector<double> uncertainty;
  for (const FittedParameter& parameter : fit.summary.parameters) {
    uncertainty.push_back(parameter.uncertainty);
  }
  DesignSolution solution =
      describe_design(fit.model, uncertainty, fit.summary.fitted, fit.summary.converged,
                      fit.summary, asis, setup, lambda, start_index);
  solution.data_cost = std::max(0.0, fit.summary.final_cost - solution.prior_cost);
  const double dof = static_cast<double>(fit.summary.residuals) - fit.summary.free_parameters -
                     fit.summary.window_state_parameters;
  solution.reduced_data_cost = dof > 0 ? 2.0 * solution.data_cost / dof : 1.0;
  solution.data_residuals = static_cast<int>(fit.summary.residuals);
  return solution;
}

// A design from the commanded torques of playback recordings: every free parameter but the
// inertia from the torque map (fit_commanded_torque), then the inertia, when free, from the
// motion with the others held. The data cost and φ are the torque fit's.
DesignSolution fit_commanded_design(const DoorModel& start,
                                    const std::vector<CommandedTorque>& commanded,
                                    const PreparedData& data, const FitOptions& fit,
                                    const DoorModel& asis, const Setup& setup, double lambda,
                                    int start_index, const std::vector<std::string>& held) {
  std::vector<std::string> torque_free;
  bool inertia_free = false;
  for (int index : setup.free_index) {
    const std::string name = asis.parameter_name(index);
    if (std::find(held.begin(), held.end(), name) != held.end()) continue;
    if (name == kInertiaParameter) {
      inertia_free = true;
    } else {
      torque_free.push_back(name);
    }
  }
  std::vector<ParameterPrior> torque_priors;
  std::vector<ParameterPrior> inertia_priors;
  for (const ParameterPrior& prior : fit.priors) {
    if (std::find(held.begin(), held.end(), prior.parameter) != held.end()) continue;
    (prior.parameter == kInertiaParameter ? inertia_priors : torque_priors).push_back(prior);
  }
  CommandedTorqueFit torque =
      torque_free.empty() ? CommandedTorqueFit(start)
                          : fit_commanded_torque(start, commanded, torque_free, torque_priors, fit,
                                                 kCommandedTorqueScale_Nm);
  std::vector<double> uncertainty = torque.uncertainty;
  uncertainty.resize(asis.parameter_count(), kNaN);
  DoorModel model = torque.model;
  FitSummary summary;
  FitMetrics metrics;
  bool converged = torque.converged || torque_free.empty();
  if (inertia_free) {
    FitOptions inertia_fit = fit;
    inertia_fit.free_parameters = {kInertiaParameter};
    inertia_fit.fixed_parameters.clear();
    inertia_fit.priors = inertia_priors;
    const FitResult motion = fit_model(model, data, inertia_fit);
    model = motion.model;
    const int index = *asis.find_parameter(kInertiaParameter);
    uncertainty[index] = motion.summary.parameters[index].uncertainty;
    summary = motion.summary;
    metrics = motion.summary.fitted;
    converged = converged && motion.summary.converged;
  } else {
    metrics = evaluate_model(model, data, fit);
  }
  summary.notes.push_back(printf_text(
      "fitted to the commanded torque of %d samples: RMS error %.4g N*m, %d iterations (%s)%s",
      torque.samples, torque.rms_error_Nm, torque.iterations, torque.termination.c_str(),
      inertia_free ? "; the inertia from the motion with the other parameters held" : ""));
  DesignSolution solution = describe_design(model, uncertainty, metrics, converged, summary, asis,
                                            setup, lambda, start_index);
  solution.data_cost = torque.data_cost;
  solution.reduced_data_cost = torque_free.empty() ? 1.0 : torque.reduced_data_cost;
  solution.data_residuals = torque.samples;
  return solution;
}

// φ: the reduced data cost, 1 when the model misses the data by their noise only.
double misfit_factor(const DesignSolution& solution) {
  return std::isfinite(solution.reduced_data_cost) ? solution.reduced_data_cost : 1.0;
}

// The reduced Gauss–Newton system (window states eliminated) of the data at `model` over
// every free parameter of `setup`, in scaled units (s_i); the priors of `fit` included when
// `with_priors`. Empty when a window cannot be evaluated.
std::optional<ReducedSystem> reduced_system(const DoorModel& model, const PreparedData& data,
                                            const FitOptions& fit, double rate_noise_rad_s,
                                            double angle_noise_rad, const Setup& setup,
                                            bool with_priors) {
  ParameterMap map;
  map.base_values.assign(model.parameter_values().begin(), model.parameter_values().end());
  map.free_index = setup.free_index;
  for (int index : setup.free_index) map.scale.push_back(setup.scale[index]);
  ProblemKind kind;
  kind.windows = metric_window_options(fit, model);
  kind.windows.disjoint = fit.estimate_window_states;
  kind.estimate_start_states = fit.estimate_window_states;
  FitWeights weights;
  weights.rate_noise_rad_s = rate_noise_rad_s;
  weights.angle_noise_rad = angle_noise_rad;
  weights.angle_residuals = fit.angle_residuals;
  for (const ParameterPrior& prior : with_priors ? fit.priors : std::vector<ParameterPrior>{}) {
    const int index = *model.find_parameter(prior.parameter);
    const auto position = std::find(setup.free_index.begin(), setup.free_index.end(), index);
    if (position == setup.free_index.end()) continue;
    weights.priors.push_back({static_cast<int>(position - setup.free_index.begin()),
                              prior.center / setup.scale[index], prior.sigma / setup.scale[index]});
  }
  WindowProblem problem(model, data, map, kind, weights, map.scaled(map.base_values));
  ReducedSystem system;
  if (!problem.reduce(/*cached_only=*/false, system)) return std::nullopt;
  return system;
}

// The directions the data determines least, in scaled units (s_i), most poorly first: the
// eigenvectors of the information matrix H (window states eliminated, the priors
// included) with the smallest eigenvalues, at `model`. H itself rather than the fit's
// covariance: a pseudo-inverse would hide exactly the directions the data cannot see.
std::vector<Eigen::VectorXd> weak_directions(const DoorModel& model, const PreparedData& data,
                                             const FitOptions& fit, double rate_noise_rad_s,
                                             double angle_noise_rad, const Setup& setup,
                                             int count) {
  if (count <= 0) return {};
  const std::optional<ReducedSystem> system =
      reduced_system(model, data, fit, rate_noise_rad_s, angle_noise_rad, setup, true);
  if (!system) return {};
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(system->information);
  if (eigen.info() != Eigen::Success) return {};
  std::vector<Eigen::VectorXd> directions;
  const int p = static_cast<int>(system->information.rows());
  for (int j = 0; j < p && static_cast<int>(directions.size()) < count; ++j) {
    directions.push_back(eigen.eigenvectors().col(j).normalized());  // ascending eigenvalues
  }
  return directions;
}

// Newton decrement gᵀ H⁻¹ g of the system restricted to `positions` (H normalized to a unit
// diagonal, so that the solve does not depend on the units; a pseudo-inverse where the
// restriction is singular).
double restricted_decrement(const Eigen::MatrixXd& information, const Eigen::VectorXd& gradient,
                            const std::vector<int>& positions) {
  const int k = static_cast<int>(positions.size());
  if (k == 0) return 0.0;
  Eigen::MatrixXd h(k, k);
  Eigen::VectorXd g(k);
  for (int a = 0; a < k; ++a) {
    const double da = information(positions[a], positions[a]);
    const double na = da > 0 ? 1.0 / std::sqrt(da) : 0.0;
    g(a) = gradient(positions[a]) * na;
    for (int b = 0; b < k; ++b) {
      const double db = information(positions[b], positions[b]);
      h(a, b) = information(positions[a], positions[b]) * na * (db > 0 ? 1.0 / std::sqrt(db) : 0.0);
    }
  }
  const Eigen::VectorXd step = h.completeOrthogonalDecomposition().solve(g);
  return std::max(0.0, g.dot(step));
}

// Per free position of `setup`: the Gauss–Newton predicted decrease of the data's Σ r² at
// `model` when that parameter is freed beside `chosen` (free positions), from one Jacobian;
// −∞ for the chosen ones. Empty when the system cannot be evaluated.
std::vector<double> predicted_decreases(const ReducedSystem& system,
                                        const std::vector<int>& chosen) {
  const int p = static_cast<int>(system.information.rows());
  const double base = restricted_decrement(system.information, system.gradient, chosen);
  std::vector<double> out(p, -std::numeric_limits<double>::infinity());
  for (int j = 0; j < p; ++j) {
    if (std::find(chosen.begin(), chosen.end(), j) != chosen.end()) continue;
    std::vector<int> trial = chosen;
    trial.push_back(j);
    out[j] = restricted_decrement(system.information, system.gradient, trial) - base;
  }
  return out;
}

// The largest difference between two solutions' free parameters, in scaled units.
double scaled_distance(const DesignSolution& a, const DesignSolution& b, const Setup& setup) {
  double largest = 0.0;
  for (int index : setup.free_index) {
    largest = std::max(largest, std::abs(a.parameters[index].to_be - b.parameters[index].to_be) /
                                    setup.scale[index]);
  }
  return largest;
}

// Fits a design from a start model (its bounds are the fit's); the int is the start's index,
// the names are free parameters held at their start values.
using DesignFitter =
    std::function<DesignSolution(const DoorModel&, int, const std::vector<std::string>&)>;

// Whether a design's data cost is one the data cannot tell from the best: within `tolerance`
// of it, or above it by less than a hundredth of a noise level's variance per residual (so
// that exact data, whose best cost is ~0, have a usable test).
bool equivalent_cost(double cost, double best_cost, int residuals, double tolerance) {
  return cost <= (1.0 + tolerance) * best_cost + 0.005 * residuals;
}

// Refits with the bounds on which `best` holds parameters moved outward by
// options.bound_widening widths and decides feasibility (see InverseDesignOptions). `held`:
// the free parameters `best` kept at AS-IS, kept so in the refit.
void check_bounds(const DoorModel& asis, const DesignFitter& fit_design,
                  const InverseDesignOptions& options, const DesignSolution& best,
                  const std::vector<std::string>& held, InverseDesignResult& result) {
  const int base = asis.base_parameter_count();
  // From AS-IS, with the equation-error stage: from `best` the fit tends to stay in the
  // valley the bound pushed it into (the latch's shape parameters making up for k_l).
  std::vector<double> values(asis.parameter_values().begin(),
                             asis.parameter_values().begin() + base);
  std::vector<Bounds> bounds(asis.parameter_bounds().begin(),
                             asis.parameter_bounds().begin() + base);
  std::vector<int> binding;
  for (int i = 0; i < asis.parameter_count(); ++i) {
    const DesignParameter& parameter = best.parameters[i];
    if (!parameter.at_bound) continue;
    binding.push_back(i);
    if (i >= base) continue;  // effect parameters keep their bounds
    const double width = parameter.bounds.upper - parameter.bounds.lower;
    const bool upper = std::abs(parameter.bounds.upper - parameter.to_be) <=
                       std::abs(parameter.to_be - parameter.bounds.lower);
    if (upper) {
      bounds[i].upper += options.bound_widening * width;
    } else {
      const double lower = bounds[i].lower - options.bound_widening * width;
      bounds[i].lower = bounds[i].lower >= 0 ? std::max(0.0, lower) : lower;
    }
  }
  const DesignSolution widened = fit_design(
      DoorModel(ModelKind::kPhysical, asis.geometry(), values, bounds,
                std::vector<EffectSetting>(asis.effects().begin(), asis.effects().end())),
      -1, held);
  const double best_rmse = best.fit.window.rmse();
  result.requested_rmse_rad_s = widened.fit.window.rmse();
  result.requested_data_cost = widened.data_cost;
  std::string binding_text;
  for (int i : binding) {
    DesignParameter requested = widened.parameters[i];
    requested.bounds = i < base ? bounds[i] : best.parameters[i].bounds;
    requested.at_bound = on_bound(requested.to_be, requested.bounds);
    const DesignParameter& held = best.parameters[i];
    const bool upper =
        std::abs(held.bounds.upper - held.to_be) <= std::abs(held.to_be - held.bounds.lower);
    binding_text += (binding_text.empty() ? "" : "; ") + held.name + " held at its " +
                    (upper ? "upper" : "lower") + " bound " + format_number(held.to_be) + " " +
                    held.unit + " (AS-IS " + format_number(held.as_is) + "); the data ask for " +
                    (requested.at_bound ? (upper ? "at least " : "at most ") : "") +
                    printf_text("%.5g", requested.to_be) + " " + held.unit;
    result.requested.push_back(std::move(requested));
  }
  if (!equivalent_cost(best.data_cost, widened.data_cost, best.data_residuals,
                       options.infeasibility_cost_tolerance)) {
    result.feasible = false;
    result.infeasibility =
        binding_text +
        printf_text(
            ". Within the bounds the data cost is %.5g (window RMSE of omega %.4g rad/s), "
            "beyond them %.5g (%.4g rad/s): the TO-BE feel lies outside the bounds; the "
            "first solution is the nearest feasible design.",
            best.data_cost, best_rmse, widened.data_cost, result.requested_rmse_rad_s);
  } else {
    result.notes.push_back(
        binding_text + printf_text(" (beyond the bounds the fit is not clearly better: data cost "
                                   "%.5g against %.5g; feasible)",
                                   widened.data_cost, best.data_cost));
  }
}

// The ranking of equivalent designs: fewest parts changed (weighted by their costs of
// change) first, then the smallest weighted size of the change.
void rank_solutions(std::vector<DesignSolution>& solutions) {
  std::stable_sort(solutions.begin(), solutions.end(),
                   [](const DesignSolution& a, const DesignSolution& b) {
                     if (a.parts_changed_cost != b.parts_changed_cost) {
                       return a.parts_changed_cost < b.parts_changed_cost;
                     }
                     return a.size_of_change < b.size_of_change;
                   });
}

// The fewest-changes alternative (InverseDesignOptions::fewest_changes_refits), added to
// result.solutions; the solutions are then ranked again.
void add_fewest_changes(const DoorModel& asis, const DesignFitter& fit_design,
                        const InverseDesignOptions& options, const Setup& setup, double best_cost,
                        int residuals, bool commanded_torque, InverseDesignResult& result) {
  DesignSolution current = result.solutions.front();
  std::vector<std::pair<double, int>> candidates;  // (scaled change, index)
  for (int index : setup.free_index) {
    const double scaled = std::abs(current.parameters[index].change) / setup.scale[index];
    if (scaled <= kChangedFraction) continue;  // unchanged already
    if (commanded_torque && asis.parameter_name(index) == kInertiaParameter) continue;
    candidates.emplace_back(scaled, index);
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<std::string> held;
  int refits = 0;
  for (const auto& [scaled, index] : candidates) {
    if (refits >= options.fewest_changes_refits) break;
    std::vector<std::string> trial = held;
    trial.push_back(asis.parameter_name(index));
    std::vector<double> values(current.model.parameter_values().begin(),
                               current.model.parameter_values().end());
    values[index] = setup.as_is[index];
    std::optional<DoorModel> start;
    try {
      start = asis.with_parameter_values(values);
    } catch (const std::invalid_argument&) {
      continue;  // the AS-IS value breaks a constraint with the others as they are
    }
    ++refits;
    try {
      if (options.progress) {
        options.progress(printf_text("fewest changes: refit %d of at most %d, %s at AS-IS", refits,
                                     options.fewest_changes_refits,
                                     asis.parameter_name(index).c_str()));
      }
      DesignSolution refit = fit_design(*start, -2, trial);
      if (equivalent_cost(refit.data_cost, best_cost, residuals,
                          options.equivalent_cost_tolerance)) {
        current = std::move(refit);
        held = std::move(trial);
      }
    } catch (const std::runtime_error&) {
      // that hold does not fit: keep the parameter changed
    }
  }
  std::string held_text;
  for (const std::string& name : held) held_text += (held_text.empty() ? "" : ", ") + name;
  if (held.empty()) {
    result.notes.push_back(printf_text(
        "fewest changes: no changed parameter can be left at its AS-IS value (%d refits)", refits));
    return;
  }
  // Distinct by construction: the smallest-change solution changes every held parameter.
  result.notes.push_back(printf_text(
      "fewest changes: %s left at AS-IS, the same fit (data cost %.6g, size of change %.4g; %d "
      "refits)",
      held_text.c_str(), current.data_cost, current.size_of_change, refits));
  result.solutions.push_back(std::move(current));
  rank_solutions(result.solutions);
}

}  // namespace

namespace {

// One inverse design, stage by stage (inverse_design() below reads as their list).
class DesignRun {
 public:
  DesignRun(const DoorModel& asis, const PreparedData& data, const InverseDesignOptions& options,
            const std::vector<CommandedTorque>& commanded, InverseDesignResult& result)
      : asis_(asis), data_(data), options_(options), commanded_(commanded), result_(result) {}

  // The free set, scales, costs of change and priors; the noise levels.
  void set_up();
  // Sparse search, then the smallest change beside it (recordings of a door).
  void sparse_then_smallest_change();
  // The smallest change from several starts, then the fewest-changes search (playbacks).
  void smallest_change_then_fewest();
  // Notes on how well the first design fits.
  void note_fit_quality();

 private:
  DesignSolution fit_design(const DoorModel& start, int start_index,
                            const std::vector<std::string>& held);
  DesignFitter fitter() {
    return [this](const DoorModel& start, int index, const std::vector<std::string>& held) {
      return fit_design(start, index, held);
    };
  }
  void set_priors(double lambda);
  std::vector<DesignSolution> run_starts(const DoorModel& origin, int pass, int starts);
  DesignSolution as_is_design();
  DesignSolution sparse_search();
  bool sparse_step(std::vector<int>& chosen, DesignSolution& current);
  void refine_sparse(std::vector<int>& chosen, DesignSolution& current);
  std::optional<DesignSolution> refit_set(const DesignSolution& current, int reset_position,
                                          const std::vector<int>& set, const std::string& what);
  void keep_equivalent(const std::vector<DesignSolution>& found, const DesignSolution* reference);
  std::vector<std::string> names_except(const std::vector<int>& free_positions) const;

  const DoorModel& asis_;
  const PreparedData& data_;
  const InverseDesignOptions& options_;
  const std::vector<CommandedTorque>& commanded_;
  InverseDesignResult& result_;
  Setup setup_;
  FitOptions fit_;
  double lambda_ = 0.0;
  double angle_noise_rad_ = 0.0;
  std::vector<std::string> start_notes_;
  const DesignSolution* best_ = nullptr;  // the best data cost among the solutions found
  std::vector<DesignSolution> found_;
  std::vector<std::string> sparse_held_;  // the free parameters the sparse design keeps
};

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

DesignSolution DesignRun::fit_design(const DoorModel& start, int start_index,
                                     const std::vector<std::string>& held) {
  ++result_.fits_run;
  DesignSolution solution = [&] {
    if (result_.commanded_torque) {
      return fit_commanded_design(start, commanded_, data_, fit_, asis_, setup_, lambda_,
                                  start_index, held);
    }
    if (held.empty()) {
      return make_solution(fit_model(start, data_, fit_), asis_, setup_, lambda_, start_index);
    }
    FitOptions held_fit = fit_;
    held_fit.fixed_parameters.insert(held_fit.fixed_parameters.end(), held.begin(), held.end());
    std::erase_if(held_fit.priors, [&](const ParameterPrior& prior) {
      return std::find(held.begin(), held.end(), prior.parameter) != held.end();
    });
    return make_solution(fit_model(start, data_, held_fit), asis_, setup_, lambda_, start_index);
  }();
  solution.held_at_as_is = held;
  FitSummary::Times& sum = result_.fit_times;
  const FitSummary::Times& times = solution.summary.times;
  sum.start_s += times.start_s;
  sum.equation_error_s += times.equation_error_s;
  sum.windows_s += times.windows_s;
  sum.statistics_s += times.statistics_s;
  sum.metrics_s += times.metrics_s;
  sum.held_out_s += times.held_out_s;
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

const DesignSolution* lowest_cost(const std::vector<DesignSolution>& found) {
  const auto best = std::min_element(found.begin(), found.end(), [](const auto& a, const auto& b) {
    return a.data_cost < b.data_cost;
  });
  return best == found.end() ? nullptr : &*best;
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
  if (options_.smallest_change_alongside && result_.sparse_steps.size() > 1) {
    // The smallest change, every parameter free, from the sparse design, with the priors
    // strengthened by the sparse design's φ.
    set_priors(lambda_);
    std::vector<DesignSolution> smallest =
        run_starts(found_.front().model, 1, options_.smallest_change_starts);
    result_.notes.insert(result_.notes.end(), start_notes_.begin(), start_notes_.end());
    keep_equivalent(smallest, &found_.front());
    const DesignSolution* low = lowest_cost(smallest);
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

// The AS-IS door as a design: nothing changed. Its data cost is that of a fit of the window
// start states alone (one free parameter held at AS-IS by a prior of 1e-9 of its scale), so
// that it compares with the candidates' fits, whose states are fitted too.
DesignSolution DesignRun::as_is_design() {
  const int pinned = setup_.free_index.front();
  const std::string name = asis_.parameter_name(pinned);
  FitOptions states = fit_;
  states.free_parameters = {name};
  states.fixed_parameters.clear();
  states.priors = {{name, setup_.as_is[pinned], 1e-9 * setup_.scale[pinned]}};
  states.equation_error_start = false;
  ++result_.fits_run;
  const FitResult fit = fit_model(asis_, data_, states);
  DesignSolution solution = make_solution(fit, asis_, setup_, 0.0, DesignSolution::kSparseSearch);
  solution.model = asis_;  // exactly AS-IS, not the pinned parameter's 1e-9 move
  for (DesignParameter& parameter : solution.parameters) {
    parameter.to_be = parameter.as_is;
    parameter.change = 0.0;
    parameter.relative_change = parameter.as_is != 0 ? 0.0 : kNaN;
    parameter.uncertainty = kNaN;
    parameter.changed = false;
  }
  solution.parts_changed = 0;
  solution.parts_changed_cost = 0.0;
  solution.size_of_change = 0.0;
  solution.prior_cost = 0.0;
  solution.data_cost = std::max(0.0, fit.summary.final_cost);
  return solution;
}

SparseStep sparse_row(const DesignSolution& design, std::string added,
                      std::vector<std::string> free) {
  SparseStep row;
  row.added = std::move(added);
  row.free = std::move(free);
  row.data_cost = design.data_cost;
  row.reduced_data_cost = design.reduced_data_cost;
  row.window_rmse_rad_s = design.fit.window.rmse();
  return row;
}

// Forward selection from AS-IS (InverseDesignOptions::sparse_search): the sequence goes to
// result.sparse_steps, the reason it stopped to result.sparse_stop.
DesignSolution DesignRun::sparse_search() {
  DesignSolution current = as_is_design();
  result_.sparse_steps.push_back(sparse_row(current, "", {}));
  std::vector<int> chosen;  // positions in setup_.free_index
  while (static_cast<int>(chosen.size()) < options_.sparse_max_parts &&
         chosen.size() < setup_.free_index.size()) {
    if (!sparse_step(chosen, current)) break;
  }
  if (result_.sparse_stop.empty()) {
    result_.sparse_stop =
        printf_text("stopped at %zu parts: %s", chosen.size(),
                    chosen.size() == setup_.free_index.size() ? "every free parameter is in"
                                                              : "sparse_max_parts reached");
  }
  refine_sparse(chosen, current);
  sparse_held_ = names_except(chosen);
  current.held_at_as_is.clear();
  current.start_index = DesignSolution::kSparseSearch;
  return current;
}

// A refit of the design with the parameters at `set` (free positions) free, from `current`
// with the parameter at `reset_position` back at AS-IS; empty when that start or the fit
// fails.
std::optional<DesignSolution> DesignRun::refit_set(const DesignSolution& current,
                                                   int reset_position, const std::vector<int>& set,
                                                   const std::string& what) {
  std::vector<double> values(current.model.parameter_values().begin(),
                             current.model.parameter_values().end());
  const int index = setup_.free_index[reset_position];
  values[index] = setup_.as_is[index];
  try {
    const DoorModel start = asis_.with_parameter_values(values);
    if (options_.progress) options_.progress("sparse search, refining: " + what);
    return fit_design(start, DesignSolution::kSparseSearch, names_except(set));
  } catch (const std::exception&) {
    return std::nullopt;  // the start breaks a constraint, or the fit failed
  }
}

// After the forward pass. A part chosen early, while others were still missing, may have
// stood in for them: each chosen part is swapped for a candidate its step found equivalent
// when that refit fits better, then dropped when the design without it still fits within
// sparse_min_improvement. Each change is a row of the sequence.
void DesignRun::refine_sparse(std::vector<int>& chosen, DesignSolution& current) {
  const std::vector<SparseStep> steps = result_.sparse_steps;
  const auto name_of = [&](int k) { return asis_.parameter_name(setup_.free_index[k]); };
  const auto names_of = [&](const std::vector<int>& set) {
    std::vector<std::string> names;
    for (int k : set) names.push_back(name_of(k));
    return names;
  };
  const auto position_of = [&](const std::string& name) {
    const int index = *asis_.find_parameter(name);
    return static_cast<int>(std::find(setup_.free_index.begin(), setup_.free_index.end(), index) -
                            setup_.free_index.begin());
  };
  for (std::size_t c = 0; c < chosen.size() && c + 1 < steps.size(); ++c) {
    for (const std::string& alternative : steps[c + 1].equivalent) {
      const int k = position_of(alternative);
      if (std::find(chosen.begin(), chosen.end(), k) != chosen.end()) continue;
      std::vector<int> trial = chosen;
      trial[c] = k;
      const std::string what = name_of(chosen[c]) + " -> " + alternative;
      std::optional<DesignSolution> refit = refit_set(current, chosen[c], trial, what);
      if (!refit) continue;
      // Better by more than a hair, or as good (a degenerate pair such as F0 and L0, whose
      // difference sets the spring's tension) with a smaller weighted change.
      const auto weighted = [&](const DesignSolution& design, int position) {
        const int index = setup_.free_index[position];
        return setup_.weight[index] * std::abs(design.parameters[index].change) /
               setup_.scale[index];
      };
      const bool better = refit->data_cost < (1 - kSameCost) * current.data_cost;
      const bool same = refit->data_cost <= (1 + kSameCost) * current.data_cost;
      if (!better && !(same && weighted(*refit, k) < weighted(current, chosen[c]))) continue;
      chosen = trial;
      current = std::move(*refit);
      result_.sparse_steps.push_back(sparse_row(current, what, names_of(chosen)));
    }
  }
  for (std::size_t c = 0; c < chosen.size() && chosen.size() > 1;) {
    std::vector<int> trial = chosen;
    trial.erase(trial.begin() + static_cast<std::ptrdiff_t>(c));
    const std::string what = "- " + name_of(chosen[c]);
    std::optional<DesignSolution> refit = refit_set(current, chosen[c], trial, what);
    if (!refit || refit->data_cost - current.data_cost >=
                      options_.sparse_min_improvement * refit->data_cost) {
      ++c;
      continue;
    }
    chosen = trial;
    current = std::move(*refit);
    result_.sparse_steps.push_back(sparse_row(current, what, names_of(chosen)));
  }
}

// One step: rank the candidates by their predicted decrease, refit the best few, take the
// one that fits best (of those the data cannot tell apart, the smallest weighted change)
// when it lowers the data cost by sparse_min_improvement. False when the search stops.
bool DesignRun::sparse_step(std::vector<int>& chosen, DesignSolution& current) {
  const std::optional<ReducedSystem> system = reduced_system(
      current.model, data_, fit_, result_.rate_noise_rad_s, angle_noise_rad_, setup_, false);
  if (!system) {
    result_.sparse_stop = "stopped: the design's windows cannot be evaluated";
    return false;
  }
  const std::vector<double> decrease = predicted_decreases(*system, chosen);
  std::vector<int> order;
  for (int k = 0; k < static_cast<int>(decrease.size()); ++k) {
    if (std::isfinite(decrease[k])) order.push_back(k);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return decrease[a] > decrease[b]; });
  if (static_cast<int>(order.size()) > options_.sparse_refits_per_step) {
    order.resize(options_.sparse_refits_per_step);
  }
  std::vector<std::pair<int, DesignSolution>> trials;
  for (int k : order) {
    std::vector<int> trial = chosen;
    trial.push_back(k);
    const std::string name = asis_.parameter_name(setup_.free_index[k]);
    if (options_.progress) {
      options_.progress(
          printf_text("sparse search, part %zu: trying %s", chosen.size() + 1, name.c_str()));
    }
    try {
      trials.emplace_back(
          k, fit_design(current.model, DesignSolution::kSparseSearch, names_except(trial)));
    } catch (const std::runtime_error& error) {
      result_.notes.push_back("sparse search: the fit with " + name + " failed: " + error.what());
    }
  }
  if (trials.empty()) {
    result_.sparse_stop = "stopped: no candidate could be fitted";
    return false;
  }
  std::stable_sort(trials.begin(), trials.end(), [](const auto& a, const auto& b) {
    return a.second.data_cost < b.second.data_cost;
  });
  const DesignSolution& best = trials.front().second;
  // Of the candidates the data cannot tell from the best, the smallest weighted change.
  std::size_t pick = 0;
  double pick_change = std::numeric_limits<double>::infinity();
  SparseStep row;
  for (std::size_t t = 0; t < trials.size(); ++t) {
    const int index = setup_.free_index[trials[t].first];
    const std::string name = asis_.parameter_name(index);
    row.tried.emplace_back(name, trials[t].second.data_cost);
    if (!equivalent_cost(trials[t].second.data_cost, best.data_cost, best.data_residuals,
                         options_.equivalent_cost_tolerance)) {
      continue;
    }
    row.equivalent.push_back(name);
    const double weighted = setup_.weight[index] *
                            std::abs(trials[t].second.parameters[index].change) /
                            setup_.scale[index];
    if (weighted < pick_change) {
      pick_change = weighted;
      pick = t;
    }
  }
  DesignSolution& picked = trials[pick].second;
  const double improvement = (current.data_cost - picked.data_cost) / current.data_cost;
  const std::string picked_name = asis_.parameter_name(setup_.free_index[trials[pick].first]);
  if (!(improvement >= options_.sparse_min_improvement)) {
    result_.sparse_stop = printf_text(
        "stopped at %zu part(s): the best further part, %s, lowers the data cost by %.2f %% "
        "(%.6g to %.6g), less than the %.2f %% asked for (sparse_min_improvement): the rest of "
        "the misfit is noise or beyond the model",
        chosen.size(), picked_name.c_str(), 100 * improvement, current.data_cost, picked.data_cost,
        100 * options_.sparse_min_improvement);
    return false;
  }
  chosen.push_back(trials[pick].first);
  std::vector<std::string> free_names;
  for (int k : chosen) free_names.push_back(asis_.parameter_name(setup_.free_index[k]));
  const std::vector<std::pair<std::string, double>> tried = row.tried;
  const std::vector<std::string> equivalent = row.equivalent;
  row = sparse_row(picked, picked_name, free_names);
  row.tried = tried;
  row.equivalent = equivalent;
  result_.sparse_steps.push_back(std::move(row));
  current = std::move(picked);
  return true;
}

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

namespace {

std::string parameter_table(const DesignSolution& solution, bool changed_only) {
  std::string text =
      "    parameter        AS-IS          TO-BE          change     rel      +-          w\n";
  for (const DesignParameter& p : solution.parameters) {
    if (changed_only && !p.changed) continue;
    text += printf_text(
        "    %-12s %12.5g %14.5g %14.4g %6s %11.3g %6.3g%s%s\n", p.name.c_str(), p.as_is, p.to_be,
        p.change,
        std::isfinite(p.relative_change) ? printf_text("%+.0f%%", 100 * p.relative_change).c_str()
                                         : "",
        p.uncertainty, p.weight, p.free ? "" : "  not free", p.at_bound ? "  AT BOUND" : "");
  }
  return text;
}

std::string solution_header(const DesignSolution& solution, int rank) {
  std::string origin = printf_text("start %d", solution.start_index);
  if (solution.start_index == DesignSolution::kSparseSearch) origin = "sparse design search";
  if (!solution.held_at_as_is.empty()) {
    origin = "fewest changes, AS-IS kept for";
    for (const std::string& name : solution.held_at_as_is) origin += " " + name;
  }
  return printf_text(
      "Solution %d (%s): parts changed %d (cost %.4g), size of change %.4g; window RMSE of omega "
      "%.4g rad/s, FIT %.1f%%; data cost %.4g, prior cost %.4g%s\n",
      rank, origin.c_str(), solution.parts_changed, solution.parts_changed_cost,
      solution.size_of_change, solution.fit.window.rmse(), solution.fit.window.fit_percent(),
      solution.data_cost, solution.prior_cost, solution.converged ? "" : " (not converged)");
}

std::string sparse_table(const InverseDesignResult& result) {
  if (result.sparse_steps.empty()) return "";
  std::string text = "Sparse design search (parts freed one at a time from AS-IS):\n";
  text += "    parts  added        data cost    phi      RMSE omega   also tried (data cost)\n";
  for (std::size_t s = 0; s < result.sparse_steps.size(); ++s) {
    const SparseStep& step = result.sparse_steps[s];
    std::string tried;
    for (const auto& [name, cost] : step.tried) {
      if (name == step.added) continue;
      const bool same =
          std::find(step.equivalent.begin(), step.equivalent.end(), name) != step.equivalent.end();
      tried += printf_text(" %s %.6g%s", name.c_str(), cost, same ? " (equivalent)" : "");
    }
    text += printf_text("    %5zu  %-12s %-12.6g %-8.4g %-12.4g%s\n", s,
                        s == 0 ? "(AS-IS)" : step.added.c_str(), step.data_cost,
                        step.reduced_data_cost, step.window_rmse_rad_s, tried.c_str());
  }
  return text + "    " + result.sparse_stop + "\n";
}

}  // namespace

std::string InverseDesignResult::brief_report() const {
  std::string text = feasible ? "Inverse design: feasible" : "Inverse design: INFEASIBLE";
  text += printf_text(", %zu distinct solution(s) from %d start(s), %.1f s.\n", solutions.size(),
                      starts_run, total_time_s);
  if (!feasible) text += std::string("  ").append(infeasibility).append("\n");
  if (!solutions.empty()) {
    text += solution_header(solutions.front(), 1);
    text += parameter_table(solutions.front(), /*changed_only=*/true);
  }
  text += sparse_table(*this);
  return text;
}

std::string InverseDesignResult::full_report() const {
  std::string text = brief_report();
  text += printf_text(
      "TO-BE rate noise: %.4g rad/s; misfit factor phi %.4g; effective regularization %.4g\n",
      rate_noise_rad_s, misfit_factor, effective_regularization);
  for (std::size_t s = 0; s < solutions.size(); ++s) {
    text += std::string("\n").append(solution_header(solutions[s], static_cast<int>(s + 1)));
    text += parameter_table(solutions[s], /*changed_only=*/false);
    for (const std::string& note : solutions[s].summary.notes)
      text += std::string("    note: ").append(note).append("\n");
  }
  for (const std::string& note : notes) text += std::string("Note: ").append(note).append("\n");
  return text;
}

}  // namespace doorbench
