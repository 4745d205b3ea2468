// The fit gives the same answer on every run, whatever the number of threads: the residual
// blocks are evaluated in parallel, but every sum is formed on one thread in a fixed order
// (docs/fitting.md, "Threads and determinism"). Compared bit for bit: any difference in the
// last bit would grow through the stopping rule and the cross-validation folds.
#include <atomic>
#include <catch2/catch.hpp>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/sensory_model.h"
#include "analysis/simulation/fit_synthetic.h"
#include "core/parallel.h"

namespace {

using doorbench::FitResult;

// The same double, bit for bit (NaN equal to the same NaN).
bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// Every number a fit reports that depends on the solver's path, with its name.
std::vector<std::pair<std::string, double>> figures(const FitResult& result) {
  const doorbench::FitSummary& summary = result.summary;
  std::vector<std::pair<std::string, double>> out;
  for (const doorbench::FittedParameter& parameter : summary.parameters) {
    out.emplace_back(parameter.name, parameter.value);
    out.emplace_back(parameter.name + " uncertainty", parameter.uncertainty);
  }
  out.emplace_back("iterations", summary.iterations);
  out.emplace_back("equation-error iterations", summary.equation_error_iterations);
  out.emplace_back("final cost", summary.final_cost);
  out.emplace_back("residual variance", summary.residual_variance);
  out.emplace_back("fitted window RMSE", summary.fitted.window.rmse());
  out.emplace_back("fitted replay RMSE", summary.fitted.replay.rmse());
  REQUIRE(summary.held_out);
  for (const doorbench::StrokeFitMetrics& stroke : summary.held_out->strokes) {
    out.emplace_back("held-out window RMSE of stroke " + std::to_string(stroke.stroke_id),
                     stroke.window.rmse());
  }
  return out;
}

void require_identical(const FitResult& a, const FitResult& b) {
  const auto first = figures(a);
  const auto second = figures(b);
  REQUIRE(first.size() == second.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    INFO(first[i].first << ": " << first[i].second << " vs " << second[i].second);
    CHECK(same_bits(first[i].second, second[i].second));
  }
  CHECK(a.summary.termination == b.summary.termination);
  CHECK(a.summary.notes == b.summary.notes);
}

}  // namespace

TEST_CASE("a fit with cross-validation is the same bit for bit on 1, 2 and 3 threads",
          "[fitting][determinism]") {
  namespace sensory = doorbench::sensory;
  const doorbench::DoorModel truth = doorbench::reference_model(doorbench::ModelKind::kSensory);
  doorbench::SyntheticStrokeOptions strokes;
  strokes.runs = {{0.6, 3.0}, {1.0, 3.0}};
  strokes.seed = 7;
  const doorbench::PreparedData data = doorbench::synthetic_strokes(truth, strokes);
  // From 20% off: the equation-error stage, the latch read-off, both window passes and the
  // folds all do work.
  std::vector<double> values(truth.parameter_values().begin(), truth.parameter_values().end());
  for (int i = 0; i <= sensory::kTheta4; ++i) values[i] *= i % 2 == 1 ? 1.2 : 0.8;
  for (int i = sensory::kTheta0; i <= sensory::kTheta3; ++i) {
    values[i] = truth.parameter_values()[i] * 1.2;
  }
  const doorbench::DoorModel start = truth.with_parameter_values(values);

  doorbench::FitOptions options;
  options.cross_validation_folds = 3;
  options.num_threads = 1;
  const FitResult one = doorbench::fit_model(start, data, options);
  options.num_threads = 2;
  const FitResult two = doorbench::fit_model(start, data, options);
  options.num_threads = 3;
  const FitResult three = doorbench::fit_model(start, data, options);
  INFO(one.summary.brief_report());
  CHECK(one.summary.iterations > 2);
  require_identical(one, two);
  require_identical(one, three);

  // Each fold's refit is reported: which strokes it left out, how it ended, how it did.
  REQUIRE(one.summary.fold_fits.size() == 3);
  std::size_t held_out_strokes = 0;
  for (const doorbench::FoldFit& fold : one.summary.fold_fits) {
    CHECK_FALSE(fold.held_out_strokes.empty());
    held_out_strokes += fold.held_out_strokes.size();
    CHECK(fold.iterations > 0);
    CHECK(fold.converged);  // the right model on synthetic strokes: a well-posed fit
    CHECK_FALSE(fold.termination.empty());
    CHECK(fold.fitted_rmse_rad_s > 0);
    CHECK(fold.held_out_rmse_rad_s > 0);
  }
  CHECK(held_out_strokes == data.strokes.size());
  CHECK_THAT(one.summary.full_report(), Catch::Matchers::Contains("fold 1 (leaves out 1,4): ") &&
                                            Catch::Matchers::Contains(" held out\n"));
}

TEST_CASE("parallel_for runs every index once and passes a task's exception on",
          "[fitting][determinism]") {
  for (int threads : {1, 2, 5}) {
    INFO(threads << " threads");
    std::vector<std::atomic<int>> runs(1000);
    doorbench::parallel_for(static_cast<int>(runs.size()), threads, [&](int i) { ++runs[i]; });
    int wrong = 0;
    for (const std::atomic<int>& count : runs) wrong += count.load() == 1 ? 0 : 1;
    CHECK(wrong == 0);
    doorbench::parallel_for(0, threads, [](int) { throw std::logic_error("never called"); });
    CHECK_THROWS_WITH(doorbench::parallel_for(50, threads,
                                              [](int i) {
                                                if (i == 17) throw std::runtime_error("task 17");
                                              }),
                      "task 17");
  }
}
