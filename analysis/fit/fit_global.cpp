// The global stage (internal/fit_global.h): the starts after the first, screened, the promising
// ones polished, further rounds of subset refits and the hops.
#include "analysis/fit/internal/fit_global.h"

#include <algorithm>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/internal/fit_search.h"
#include "core/clock.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "core/parallel.h"
#include "core/stop_request.h"

namespace doorbench::fit_detail {

namespace {

constexpr const char* kResetOrigin =
    "the first optimum with its undetermined or bound parameters at their starts";

// The global stage's starts after the first (FitOptions::global_search): each start's model,
// where it came from and its kind's rank (subset refits 0, the start as given 1, the sample 2).
struct SearchStart {
  std::string origin;
  DoorModel model;
  int rank = 0;
  double rmse = kNaN;  // window RMSE on every stroke, from the measured states
};

// Each start's window RMSE on every stroke, from the measured states, all at once on the fit's
// threads.
void screen(std::vector<SearchStart>& starts, const PreparedData& data, const FitOptions& options) {
  parallel_for(static_cast<int>(starts.size()), fit_thread_count(options), [&](int k) {
    const DoorModel& model = starts[static_cast<std::size_t>(k)].model;
    starts[static_cast<std::size_t>(k)].rmse =
        compute_window_errors(model, data, metric_windows(options, model)).rmse();
  });
}

// The starts to screen: the subset refits from the first fit's optimum, the start as given
// when it differs from the first start, and the sample of the bounds.
std::vector<SearchStart> search_starts(const DoorModel& start, const FitResult& first,
                                       const std::vector<FoldOutcome>& refits,
                                       const FitOptions& options, const KeptFit& kept,
                                       GlobalSearch& global) {
  std::vector<SearchStart> starts;
  for (std::size_t k = 0; k < refits.size(); ++k) {
    if (!refits[k].refitted) continue;
    starts.push_back({"the refit without subset " + std::to_string(k + 1) + " of " +
                          std::to_string(refits.size()),
                      *refits[k].model, 0});
    ++global.subset_refits;
  }
  // The start as given, unless the first start's windows began exactly there.
  const std::span<const double> given = start.parameter_values();
  std::vector<double> first_start;
  for (const FittedParameter& parameter : first.summary.parameters) {
    first_start.push_back(parameter.equation_error);
  }
  if (first_start != std::vector<double>(given.begin(), given.end())) {
    starts.push_back({"the start as given", start, 1});
    global.start_as_given = true;
  }
  for (std::vector<double>& values :
       space_filling_sample(first.model, kept.map, options.global_samples, options.global_seed)) {
    starts.push_back({"sample point " + std::to_string(global.sample_points + 1),
                      first.model.with_parameter_values(values), 2});
    ++global.sample_points;
  }
  return starts;
}

// The best optimum of the global stage so far, when not the first start's: its fit, what the
// fit keeps, its place among the polished optima and its global_keep measure.
struct BestOptimum {
  std::optional<FitResult> fit;
  KeptFit kept;
  std::size_t index = 0;
  double measure = kNaN;
};

// `options` with its window fit's progress reported as the global stage's
// FitProgress::Stage::kPolish, `what` naming the fit; as they are when nobody listens.
FitOptions reporting_as_polish(const FitOptions& options, std::string what) {
  FitOptions reporting = options;
  if (options.progress) {
    reporting.progress = [report = options.progress, what = std::move(what)](FitProgress progress) {
      if (progress.stage == FitProgress::Stage::kWindows) {
        progress.stage = FitProgress::Stage::kPolish;
        progress.what = what;
      }
      report(progress);
    };
  }
  return reporting;
}

// Polishes `model` exactly from its values with `polish`; adds its optimum to `optima` and
// makes it `best` when its options.global_keep measure is lower. A start whose simulation or
// solve fails is one the stage cannot use: a note in `failures`. True when it became the best.
// Its progress is kPolish, named `what` ("polishing " and the origin when empty).
bool polish_start(const std::string& origin, const DoorModel& model, const PreparedData& data,
                  const FitOptions& polish, std::vector<PolishedOptimum>& optima,
                  std::vector<std::string>& failures, BestOptimum& best,
                  const std::string& what = "") {
  KeptFit polished_kept;
  std::optional<FitResult> attempt;
  try {
    attempt = fit_once(model, data,
                       reporting_as_polish(polish, what.empty() ? "polishing " + origin : what),
                       polished_kept);
  } catch (const std::runtime_error& error) {
    failures.push_back("the global stage's polish from " + origin + " failed: " + error.what());
    return false;
  }
  FitResult& polished = *attempt;
  optima.push_back({origin, polished.summary.final_cost,
                    polished.summary.fitted.window.fit_percent(),
                    free_values(polished_kept.map, polished_kept.x)});
  const double measure = polish.global_keep == FitOptions::GlobalKeep::kLowestCost
                             ? polished.summary.final_cost
                             : polished.summary.fitted.window.rmse();
  if (!(measure < best.measure)) return false;
  best.measure = measure;
  best.fit = std::move(polished);
  best.kept = std::move(polished_kept);
  best.index = optima.size() - 1;
  best.fit->summary.notes.insert(best.fit->summary.notes.begin(),
                                 "the global stage's best optimum was reached from " + origin +
                                     ", not from the data-derived start");
  return true;
}

// The reset start (FitOptions::global_reset): the first optimum with its free parameters that
// are undetermined or on a bound back at their starts, and how many were put back.
struct ResetStart {
  std::optional<DoorModel> model;  // none when the door put back breaks a model constraint
  int parameters = 0;              // 0: every such parameter is at its start already
  std::string broken;              // the constraint the door put back breaks, when it does
};

ResetStart reset_start(const FitResult& first) {
  const std::span<const double> optimum = first.model.parameter_values();
  std::vector<double> values(optimum.begin(), optimum.end());
  ResetStart reset;
  for (std::size_t i = 0; i < first.summary.parameters.size() && i < values.size(); ++i) {
    const FittedParameter& parameter = first.summary.parameters[i];
    if (!parameter.free || (parameter.determined && !parameter.at_bound)) continue;
    if (values[i] == parameter.start) continue;
    values[i] = parameter.start;
    ++reset.parameters;
  }
  if (reset.parameters == 0) return reset;
  try {
    reset.model = first.model.with_parameter_values(values);
  } catch (const std::invalid_argument& error) {
    reset.broken = error.what();
  }
  return reset;
}

// The reset start polished (FitOptions::global_reset), when the first optimum has one; a note
// in `failures` when the door put back breaks a constraint of the model.
void polish_reset(const FitResult& first, const PreparedData& data, const FitOptions& options,
                  const FitOptions& polish, GlobalSearch& global,
                  std::vector<PolishedOptimum>& optima, std::vector<std::string>& failures,
                  BestOptimum& best) {
  const ResetStart reset = reset_start(first);
  if (reset.parameters == 0) return;
  if (!reset.model) {
    failures.push_back(std::string("the global stage did not try ") + kResetOrigin +
                       ": that door breaks a constraint of the model: " + reset.broken);
    return;
  }
  throw_if_stop_requested(options.stop_requested, "the global search");
  global.reset_parameters = reset.parameters;
  ++global.starts_tried;
  (void)polish_start(kResetOrigin, *reset.model, data, polish, optima, failures, best);
}

// The first start fitted with each of FitOptions::global_soft_switches' softer switches (no
// global stage, no folds). Each fit's optimum, with the model's own switches, is screened as a
// round's subset refits are: polished when its window RMSE on every stroke is below the best
// optimum's so far (`first_rmse` while that is the first fit). A soft fit that fails (a start
// that breaks a constraint, a simulation or solve that fails) is a note in `failures`, not the
// fit's failure. True when a polish became the best.
bool polish_soft_starts(const DoorModel& start, const PreparedData& data, const FitOptions& options,
                        const FitOptions& polish, GlobalSearch& global,
                        std::vector<PolishedOptimum>& optima, std::vector<std::string>& failures,
                        BestOptimum& best, double first_rmse) {
  const std::optional<int> sharpness = start.switch_sharpness_index();
  if (!sharpness) return false;
  const auto index = static_cast<std::size_t>(*sharpness);
  const std::span<const double> given = start.parameter_values();
  FitOptions soft = options;
  soft.global_search = false;
  soft.cross_validation_folds = 0;
  soft.what_would_determine = false;
  soft.window_state_start.clear();
  soft.partial_on_stop = false;  // a stop ends the whole fit, as in every other step here
  bool lower = false;
  for (double factor : options.global_soft_switches) {
    throw_if_stop_requested(options.stop_requested, "the global search");
    const std::string softer = "switches " + format_significant(1.0 / factor, 3) + " times softer";
    const std::string origin = "the data-derived start fitted with " + softer;
    try {
      std::vector<double> values(given.begin(), given.end());
      values[index] *= factor;
      const FitResult soft_fit =
          fit_model(start.with_parameter_values(values), data,
                    reporting_as_polish(soft, "fitting the data-derived start with " + softer));
      values.assign(soft_fit.model.parameter_values().begin(),
                    soft_fit.model.parameter_values().end());
      values[index] = given[index];
      ++global.soft_starts;
      ++global.starts_tried;
      std::vector<SearchStart> sharp{{origin, start.with_parameter_values(values), 0}};
      screen(sharp, data, options);
      const double best_rmse = best.fit ? best.fit->summary.fitted.window.rmse() : first_rmse;
      if (!(sharp.front().rmse < best_rmse)) continue;
      ++global.promising;
      ++global.soft_polished;
      lower =
          polish_start(origin, sharp.front().model, data, polish, optima, failures, best) || lower;
    } catch (const std::invalid_argument& error) {
      failures.push_back("the global stage did not try " + origin + ": " + error.what());
    } catch (const std::runtime_error& error) {
      failures.push_back("the global stage's fit of " + origin + " failed: " + error.what());
    }
  }
  return lower;
}

// The best optimum so far (the first fit's when no polish became the best) polished again
// from its own values (FitOptions::global_repolish), while each polish lowers the best by more
// than GlobalSearch::kSameOptimumCost. True when a polish became the best.
bool polish_again(const FitResult& first, const PreparedData& data, const FitOptions& options,
                  const FitOptions& polish, GlobalSearch& global,
                  std::vector<PolishedOptimum>& optima, std::vector<std::string>& failures,
                  BestOptimum& best, double first_measure) {
  bool lower = false;
  for (int again = 1; again <= options.global_repolish; ++again) {
    throw_if_stop_requested(options.stop_requested, "the global search");
    const double before = best.fit ? best.measure : first_measure;
    const DoorModel from = best.fit ? best.fit->model : first.model;
    ++global.repolished;
    ++global.starts_tried;
    const std::string origin =
        "polish " + std::to_string(global.repolished) + " of the best optimum from its own values";
    if (!polish_start(origin, from, data, polish, optima, failures, best, origin)) {
      break;
    }
    lower = true;
    ++global.repolished_lower;
    if (!(best.measure < (1.0 - GlobalSearch::kSameOptimumCost) * before)) break;
  }
  return lower;
}

// After the rounds: the best polished again (polish_again), then the soft starts
// (polish_soft_starts), last so that they only ever lower the fit, their best polished again
// in turn. True when a polish became the best.
bool polish_last(const FitResult& first, const DoorModel& start, const PreparedData& data,
                 const FitOptions& options, const FitOptions& polish, GlobalSearch& global,
                 std::vector<PolishedOptimum>& optima, std::vector<std::string>& failures,
                 BestOptimum& best, double first_measure) {
  bool lower =
      polish_again(first, data, options, polish, global, optima, failures, best, first_measure);
  if (polish_soft_starts(start, data, options, polish, global, optima, failures, best,
                         first.summary.fitted.window.rmse())) {
    lower = true;
    (void)polish_again(first, data, options, polish, global, optima, failures, best, first_measure);
  }
  return lower;
}

// One further round of subset refits (FitOptions::global_rounds), from the best optimum so
// far: the refits screened by their window RMSE on every stroke, the best global_polished of
// those below the best's polished. `refits` receives the round's refits. True when a polish
// became the best.
bool subset_round(int round, const PreparedData& data, const FitOptions& options,
                  const FitOptions& polish, GlobalSearch& global,
                  std::vector<PolishedOptimum>& optima, std::vector<std::string>& failures,
                  BestOptimum& best, std::vector<FoldOutcome>& refits) {
  FitOptions in_round = options;
  if (options.progress) {
    in_round.progress = [&options, round](FitProgress progress) {
      progress.round = round;
      options.progress(progress);
    };
  }
  refits = subset_refits(best.fit->model, data, best.kept.map, best.kept.x, in_round,
                         best.kept.weights, global.partition, FitProgress::Stage::kSearch);
  std::vector<SearchStart> starts;
  for (std::size_t k = 0; k < refits.size(); ++k) {
    if (!refits[k].refitted) continue;
    starts.push_back({"the refit without subset " + std::to_string(k + 1) + " of " +
                          std::to_string(refits.size()) + " in round " + std::to_string(round),
                      *refits[k].model, 0});
  }
  global.subset_refits += static_cast<int>(starts.size());
  global.starts_tried += static_cast<int>(starts.size());
  ++global.rounds;
  throw_if_stop_requested(options.stop_requested, "the global search");
  screen(starts, data, options);
  const double best_rmse = best.fit->summary.fitted.window.rmse();
  std::vector<std::size_t> promising;
  for (std::size_t k = 0; k < starts.size(); ++k) {
    if (starts[k].rmse < best_rmse) promising.push_back(k);
  }
  std::stable_sort(promising.begin(), promising.end(),
                   [&](std::size_t a, std::size_t b) { return starts[a].rmse < starts[b].rmse; });
  if (promising.size() > static_cast<std::size_t>(options.global_polished)) {
    promising.resize(static_cast<std::size_t>(options.global_polished));
  }
  global.promising += static_cast<int>(promising.size());
  bool lower = false;
  for (std::size_t k : promising) {
    throw_if_stop_requested(options.stop_requested, "the global search");
    lower = polish_start(starts[k].origin, starts[k].model, data, polish, optima, failures, best) ||
            lower;
  }
  return lower;
}

// Basin hops (FitOptions::global_hops) from the best optimum so far, each seeded by its number.
// True when a hop became the best.
bool hop_from_best(const FitResult& first, const PreparedData& data, const FitOptions& options,
                   const FitOptions& polish, const KeptFit& kept, GlobalSearch& global,
                   std::vector<PolishedOptimum>& optima, std::vector<std::string>& failures,
                   BestOptimum& best) {
  FitOptions hop_polish = polish;
  hop_polish.progress = nullptr;
  bool lower = false;
  for (int h = 1; h <= options.global_hops; ++h) {
    throw_if_stop_requested(options.stop_requested, "the global search");
    if (options.progress) options.progress({FitProgress::Stage::kHops, h - 1, options.global_hops});
    const DoorModel& from = best.fit ? best.fit->model : first.model;
    const std::vector<double> values = hop_point(
        from, kept.map, options.global_hop_size,
        static_cast<std::uint32_t>(options.global_seed) * 7919u + static_cast<std::uint32_t>(h));
    if (values.empty()) continue;
    ++global.hops;
    if (polish_start("hop " + std::to_string(h), from.with_parameter_values(values), data,
                     hop_polish, optima, failures, best)) {
      ++global.hops_lower;
      lower = true;
    }
  }
  if (options.progress && options.global_hops > 0) {
    options.progress({FitProgress::Stage::kHops, options.global_hops, options.global_hops});
  }
  return lower;
}

}  // namespace

bool global_stage(FitResult& result, const DoorModel& start, const PreparedData& data,
                  const FitOptions& options, KeptFit& kept, std::vector<FoldOutcome>& refits) {
  const StageClock::time_point began = StageClock::now();
  GlobalSearch global;
  global.ran = true;
  const int stroke_count = static_cast<int>(data.strokes.size());
  global.partition = std::min(options.global_subsets, stroke_count);
  if (global.partition >= 2) {
    refits = subset_refits(result.model, data, kept.map, kept.x, options, kept.weights,
                           global.partition, FitProgress::Stage::kSearch);
  } else {
    global.partition = 0;
  }
  std::vector<SearchStart> starts = search_starts(start, result, refits, options, kept, global);
  global.starts_tried = 1 + static_cast<int>(starts.size());
  throw_if_stop_requested(options.stop_requested, "the global search");
  screen(starts, data, options);
  const double first_rmse = result.summary.fitted.window.rmse();
  std::vector<std::size_t> promising;
  for (std::size_t k = 0; k < starts.size(); ++k) {
    if (starts[k].rmse < options.global_promising_ratio * first_rmse) promising.push_back(k);
  }
  global.promising = static_cast<int>(promising.size());
  std::stable_sort(promising.begin(), promising.end(), [&](std::size_t a, std::size_t b) {
    return starts[a].rank != starts[b].rank ? starts[a].rank < starts[b].rank
                                            : starts[a].rmse < starts[b].rmse;
  });
  // At most global_polished of each kind: a kind's best start is never crowded out by another
  // kind's many.
  std::vector<int> per_kind(3, 0);
  std::erase_if(promising, [&](std::size_t k) {
    return ++per_kind[static_cast<std::size_t>(starts[k].rank)] > options.global_polished;
  });
  // Each promising start polished exactly from its values, one after another (each fit uses
  // every thread); the optima in the order polished, the first start's first.
  FitOptions polish = options;
  polish.latch_start_from_data = false;
  polish.equation_error_start = false;
  polish.window_state_start.clear();  // the other starts are not the given optimum
  std::vector<PolishedOptimum> optima{{"the data-derived start", result.summary.final_cost,
                                       result.summary.fitted.window.fit_percent(),
                                       free_values(kept.map, kept.x)}};
  std::vector<std::string> failures;  // notes of the kept fit, whichever it is
  BestOptimum best;
  const double first_measure = options.global_keep == FitOptions::GlobalKeep::kLowestCost
                                   ? result.summary.final_cost
                                   : first_rmse;
  best.measure = first_measure;
  for (std::size_t k : promising) {
    throw_if_stop_requested(options.stop_requested, "the global search");
    (void)polish_start(starts[k].origin, starts[k].model, data, polish, optima, failures, best);
  }
  if (options.global_reset) {
    polish_reset(result, data, options, polish, global, optima, failures, best);
  }
  global.rounds = global.partition >= 2 ? 1 : 0;
  // Further rounds while the best is a polish's and the last round lowered it by more than
  // kSameOptimumCost. A round none of whose polishes became the best refitted the subsets
  // from the kept optimum: the cross-validation can reuse its refits.
  double round_began_at = first_measure;
  bool refits_from_kept = !best.fit.has_value();
  for (int round = 2; round <= options.global_rounds && global.partition >= 2 && best.fit &&
                      best.measure < (1.0 - GlobalSearch::kSameOptimumCost) * round_began_at;
       ++round) {
    round_began_at = best.measure;
    refits_from_kept =
        !subset_round(round, data, options, polish, global, optima, failures, best, refits);
  }
  if (polish_last(result, start, data, options, polish, global, optima, failures, best,
                  first_measure)) {
    refits_from_kept = false;
  }
  if (hop_from_best(result, data, options, polish, kept, global, optima, failures, best)) {
    refits_from_kept = false;
  }
  global.starts_tried += global.hops;
  const std::size_t best_index = best.index;
  global.polished = static_cast<int>(optima.size());
  distinct_optima(optima, best_index, global);
  if (best.fit) {
    // The parameters' starts as the user gave them, and how the fit was reached.
    FitSummary& summary = best.fit->summary;
    for (std::size_t i = 0; i < summary.parameters.size() && i < result.summary.parameters.size();
         ++i) {
      summary.parameters[i].start = result.summary.parameters[i].start;
      summary.parameters[i].start_origin = result.summary.parameters[i].start_origin;
      summary.parameters[i].equation_error = result.summary.parameters[i].equation_error;
    }
    summary.latch_start = result.summary.latch_start;
    summary.equation_error_iterations = result.summary.equation_error_iterations;
    summary.equation_error_termination = result.summary.equation_error_termination;
    summary.iterations += result.summary.iterations;
    summary.initial_cost = result.summary.initial_cost;
    summary.options = options;
    result = std::move(*best.fit);
    kept = std::move(best.kept);
  }
  result.summary.notes.insert(result.summary.notes.end(), failures.begin(), failures.end());
  global.time_s = seconds_since(began);
  result.summary.times.search_s = global.time_s;
  result.summary.global = std::move(global);
  return refits_from_kept;
}

}  // namespace doorbench::fit_detail
