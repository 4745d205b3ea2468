// The sparse search of the inverse design (InverseDesignOptions::sparse_search;
// docs/inverse-design.md): forward selection from AS-IS, one part at a time by its
// predicted decrease, then the refinement that swaps or drops parts chosen too early.
// DesignRun's stages (internal/design_run.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>

#include "analysis/design/internal/design_run.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "core/parallel.h"

namespace doorbench::design_detail {

namespace {

// Two refits of the sparse search whose data costs differ by less than this fraction fit
// the same (a degenerate pair of parameters).
constexpr double kSameCost = 1e-4;

// How far a design is from the TO-BE's feel: the JNDs its misses lie beyond their JND, summed
// (0 when it misses none).
double felt_gap(const std::vector<FeltMiss>& misses) {
  double gap = 0.0;
  for (const FeltMiss& miss : misses) gap += std::isfinite(miss.jnds) ? miss.jnds - 1.0 : 1e6;
  return gap;
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

}  // namespace

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

// Forward selection from AS-IS (InverseDesignOptions::sparse_search): the sequence goes to
// result.sparse_steps, the reason it stopped to result.sparse_stop.
DesignSolution DesignRun::sparse_search() {
  DesignSolution current = as_is_design();
  result_.sparse_steps.push_back(sparse_row(current, "", {}));
  result_.felt_goal = !options_.felt_jnds.empty();
  std::vector<int> chosen;  // positions in setup_.free_index
  while (static_cast<int>(chosen.size()) < options_.sparse_max_parts &&
         chosen.size() < setup_.free_index.size()) {
    if (result_.felt_goal && felt_misses(current.model).empty()) {
      result_.sparse_stop = printf_text(
          "stopped at %zu part(s): every felt quantity is within its JND of the TO-BE's",
          chosen.size());
      break;
    }
    if (!sparse_step(chosen, current)) break;
  }
  if (result_.sparse_stop.empty()) {
    result_.sparse_stop =
        printf_text("stopped at %zu parts: %s", chosen.size(),
                    chosen.size() == setup_.free_index.size() ? "every free parameter is in"
                                                              : "sparse_max_parts reached");
  }
  refine_sparse(chosen, current);
  sparse_swaps(chosen, current);
  sparse_held_ = names_except(chosen);
  current.held_at_as_is.clear();
  current.start_index = DesignSolution::kSparseSearch;
  if (result_.felt_goal) result_.felt_misses = felt_misses(current.model);
  return current;
}

std::vector<FeltMiss> DesignRun::felt_misses(const DoorModel& model) const {
  const FeelCheck check =
      compare_feel(model, std::span<const PreparedData>(&data_, 1), options_.felt);
  std::vector<FeltMiss> misses;
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    const double design = check.model.*info.member;
    const double tobe = check.recorded.*info.member;
    if (!std::isfinite(tobe) || tobe == 0.0 || !std::isfinite(design)) continue;
    const auto given = std::find_if(options_.felt_jnds.begin(), options_.felt_jnds.end(),
                                    [&](const FeltJnd& jnd) { return jnd.quantity == info.name; });
    const FeltJnd jnd = given != options_.felt_jnds.end() ? *given : typical_felt_jnd(info.name);
    if (!felt_as_different(design, tobe, jnd.weber_fraction)) continue;
    const double ratio = design / tobe;
    misses.push_back({std::string(info.name), design, tobe, design - tobe,
                      ratio > 0 ? std::abs(std::log(ratio)) / std::log1p(jnd.weber_fraction)
                                : std::numeric_limits<double>::infinity(),
                      jnd});
  }
  return misses;
}

void DesignRun::note_part_tried(const std::string& name) {
  std::vector<std::string>& tried = result_.parts_tried;
  if (std::find(tried.begin(), tried.end(), name) == tried.end()) tried.push_back(name);
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
    // With the feel as the goal, a part stays when the design without it misses more.
    if (!refit ||
        refit->data_cost - current.data_cost >=
            options_.sparse_min_improvement * refit->data_cost ||
        (result_.felt_goal &&
         felt_misses(refit->model).size() > felt_misses(current.model).size())) {
      ++c;
      continue;
    }
    chosen = trial;
    current = std::move(*refit);
    result_.sparse_steps.push_back(sparse_row(current, what, names_of(chosen)));
  }
}

void DesignRun::sparse_swaps(const std::vector<int>& chosen, const DesignSolution& current) {
  const auto name_of = [&](int k) { return asis_.parameter_name(setup_.free_index[k]); };
  std::vector<std::string> chosen_names;
  for (int k : chosen) chosen_names.push_back(name_of(k));
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    // The candidates of the step that added this part, or of the step that found it alike.
    std::vector<std::string> alike;
    for (const SparseStep& step : result_.sparse_steps) {
      const bool here =
          step.added == chosen_names[c] || std::find(step.equivalent.begin(), step.equivalent.end(),
                                                     chosen_names[c]) != step.equivalent.end();
      if (!here) continue;
      for (const std::string& name : step.equivalent) {
        if (name == chosen_names[c] || name.find(' ') != std::string::npos) continue;
        if (std::find(chosen_names.begin(), chosen_names.end(), name) != chosen_names.end()) {
          continue;
        }
        if (std::find(alike.begin(), alike.end(), name) == alike.end()) alike.push_back(name);
      }
    }
    for (const std::string& name : alike) {
      const int index = *asis_.find_parameter(name);
      const auto position = std::find(setup_.free_index.begin(), setup_.free_index.end(), index);
      if (position == setup_.free_index.end()) continue;
      std::vector<int> trial = chosen;
      trial[c] = static_cast<int>(position - setup_.free_index.begin());
      const std::string what = chosen_names[c] + " -> " + name;
      std::optional<DesignSolution> refit = refit_set(current, chosen[c], trial, what);
      if (!refit) continue;
      refit->swapped = what;
      refit->start_index = DesignSolution::kSparseSearch;
      refit->held_at_as_is.clear();
      sparse_swaps_.push_back(std::move(*refit));
    }
  }
}

void DesignRun::keep_sparse_swaps() {
  const DesignSolution& sparse = found_.front();
  for (const DesignSolution& swap : sparse_swaps_) {
    const bool alike = equivalent_cost(swap.data_cost, sparse.data_cost, sparse.data_residuals,
                                       options_.equivalent_cost_tolerance);
    bool distinct = true;
    for (const DesignSolution& kept : result_.solutions) {
      distinct = distinct && scaled_distance(swap, kept, setup_) > options_.distinct_threshold;
    }
    result_.notes.push_back(
        printf_text("sparse search, %s: data cost %.6g against the sparse design's %.6g: %s",
                    swap.swapped.c_str(), swap.data_cost, sparse.data_cost,
                    !alike      ? "dropped (fits clearly worse)"
                    : !distinct ? "dropped (the same design as one kept)"
                                : "kept as an alternative"));
    if (alike && distinct) result_.solutions.push_back(swap);
  }
}

// The refits of the candidates `order` added to `chosen`, side by side on the fit's threads
// (each on its share: a fit's solve is one thread's work, its windows' evaluation several),
// in `order`'s order; a candidate whose fit fails is left out with a note.
std::vector<std::pair<int, DesignSolution>> DesignRun::fit_candidates(
    const std::vector<int>& chosen, const std::vector<int>& order, const DesignSolution& current) {
  const int count = static_cast<int>(order.size());
  std::string names;
  for (int k : order) {
    const std::string name = asis_.parameter_name(setup_.free_index[k]);
    note_part_tried(name);
    names += (names.empty() ? "" : ", ") + name;
  }
  if (options_.progress) {
    options_.progress(
        printf_text("sparse search, part %zu: trying %s", chosen.size() + 1, names.c_str()));
  }
  std::vector<std::optional<DesignSolution>> fitted(order.size());
  std::vector<std::string> failures(order.size());
  const int threads = fit_thread_count(fit_);
  const int at_once = std::max(1, std::min(threads, count));
  parallel_for(count, at_once, [&](int t) {
    std::vector<int> trial = chosen;
    trial.push_back(order[static_cast<std::size_t>(t)]);
    try {
      fitted[static_cast<std::size_t>(t)] = fit_only(current.model, DesignSolution::kSparseSearch,
                                                     names_except(trial), threads / at_once);
    } catch (const std::runtime_error& error) {
      failures[static_cast<std::size_t>(t)] = error.what();
    }
  });
  std::vector<std::pair<int, DesignSolution>> trials;
  for (std::size_t t = 0; t < order.size(); ++t) {
    ++result_.fits_run;
    if (!fitted[t]) {
      result_.notes.push_back("sparse search: the fit with " +
                              asis_.parameter_name(setup_.free_index[order[t]]) +
                              " failed: " + failures[t]);
      continue;
    }
    add_fit_times(*fitted[t]);
    trials.emplace_back(order[t], std::move(*fitted[t]));
  }
  return trials;
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
  std::vector<std::pair<int, DesignSolution>> trials = fit_candidates(chosen, order, current);
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
  // With the feel as the goal, a part that lowers the data cost by less than
  // sparse_min_improvement is still taken when it brings the design nearer the TO-BE's feel
  // (fewer JNDs missed in all).
  const double gap = result_.felt_goal ? felt_gap(felt_misses(current.model)) : 0.0;
  const double gap_with = result_.felt_goal ? felt_gap(felt_misses(picked.model)) : 0.0;
  if (result_.felt_goal && !(improvement >= options_.sparse_min_improvement) &&
      !(improvement > 0 && gap_with < gap)) {
    result_.sparse_stop = printf_text(
        "stopped at %zu part(s): the best further part, %s, lowers the data cost by %.2f %% "
        "(%.6g to %.6g) and brings the design no nearer the TO-BE's feel (%.3g JNDs missed in "
        "all, %.3g with it)",
        chosen.size(), picked_name.c_str(), 100 * improvement, current.data_cost, picked.data_cost,
        gap, gap_with);
    return false;
  }
  if (!result_.felt_goal && !(improvement >= options_.sparse_min_improvement)) {
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

}  // namespace doorbench::design_detail
