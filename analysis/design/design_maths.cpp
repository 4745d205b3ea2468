// The maths of the inverse design (internal/design_maths.h).
#include "analysis/design/internal/design_maths.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/number_format.h"
#include "core/numbers.h"

namespace doorbench::design_detail {

namespace {

// A parameter counts as a changed part when it moves by more than this fraction of its
// scale (the bound width).
constexpr double kChangedFraction = 1e-3;
// The physical model's inertia: the commanded torque does not contain it.
constexpr const char* kInertiaParameter = "J_d";
// The unit of the commanded-torque residuals before φ rescales the priors: the torque is
// exact, so any unit well below what is felt serves (0.01 N*m is 0.017 N at the handle).
constexpr double kCommandedTorqueScale_Nm = 0.01;

bool on_bound(double value, const Bounds& bounds) {
  const double width = bounds.upper - bounds.lower;
  return std::abs(value - bounds.lower) <= 1e-6 * width ||
         std::abs(bounds.upper - value) <= 1e-6 * width;
}

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

}  // namespace

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

double misfit_factor(const DesignSolution& solution) {
  return std::isfinite(solution.reduced_data_cost) ? solution.reduced_data_cost : 1.0;
}

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

double scaled_distance(const DesignSolution& a, const DesignSolution& b, const Setup& setup) {
  double largest = 0.0;
  for (int index : setup.free_index) {
    largest = std::max(largest, std::abs(a.parameters[index].to_be - b.parameters[index].to_be) /
                                    setup.scale[index]);
  }
  return largest;
}

bool equivalent_cost(double cost, double best_cost, int residuals, double tolerance) {
  return cost <= (1.0 + tolerance) * best_cost + 0.005 * residuals;
}

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

void rank_solutions(std::vector<DesignSolution>& solutions) {
  std::stable_sort(solutions.begin(), solutions.end(),
                   [](const DesignSolution& a, const DesignSolution& b) {
                     if (a.parts_changed_cost != b.parts_changed_cost) {
                       return a.parts_changed_cost < b.parts_changed_cost;
                     }
                     return a.size_of_change < b.size_of_change;
                   });
}

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

}  // namespace doorbench::design_detail
