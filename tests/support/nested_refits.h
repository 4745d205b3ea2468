#pragma once
// The nested-refit inequality (docs/residual-loop.md, "Nested refits never lose"):
// every refit of the residual loop extends its parent by one effect and starts, among others,
// at the parent's optimum with the effect at its neutral value, so its fitted (weighted) sum
// of squares is never above the parent's. It is compared with its parent on the same windows
// (the same residuals n, the same window samples fitted and held out), so its BIC is at most
// Δp ln n above the parent's.
//
// check_nested_refits walks every refit of a LoopResult (each step's candidates, the last
// examination's, and those of a step abandoned for a family switch); check_nested_refits_json
// does the same on `doorbench loop`'s result.json. Both return how many refits they checked,
// so a caller can ask that there were some. Catch CHECKs: call from a test case.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "analysis/loop/residual_loop.h"

namespace doorbench::testing {

// One refit against its parent (CandidateEvidence::before); 0 when it was not refitted.
inline int check_nested_refit(const CandidateEvidence& candidate) {
  if (!candidate.after) return 0;
  const ModelFigures& before = candidate.before;
  const ModelFigures& after = *candidate.after;
  INFO(candidate.name << ": " << candidate.verdict << " [refit from " << candidate.refit_start
                      << "]; fitted sum of squares " << after.sum_of_squares
                      << " against the parent's " << before.sum_of_squares);
  CHECK(after.residuals == before.residuals);
  CHECK(after.fitted_samples == before.fitted_samples);
  CHECK(after.held_out_samples == before.held_out_samples);
  CHECK(after.sum_of_squares <= before.sum_of_squares);
  const int added = after.parameters - before.parameters;
  CHECK(added >= 1);
  CHECK(after.bic - before.bic <=
        added * std::log(static_cast<double>(before.residuals)) + 1e-9 * std::abs(before.bic));
  return 1;
}

inline int check_nested_refits(const LoopResult& loop) {
  int checked = 0;
  for (const LoopStep& step : loop.steps) {
    for (const CandidateEvidence& candidate : step.candidates) {
      checked += check_nested_refit(candidate);
    }
  }
  for (const CandidateEvidence& candidate : loop.last_candidates) {
    checked += check_nested_refit(candidate);
  }
  for (const CandidateEvidence& candidate : loop.structure.candidates) {
    checked += check_nested_refit(candidate);
  }
  return checked;
}

// The same on result.json (app/loop_output.cpp): every candidate with "after".
template <typename Json>
int check_nested_refits_json(const Json& result) {
  int checked = 0;
  auto check_list = [&checked](const Json& candidates) {
    for (const auto& candidate : candidates) {
      if (!candidate.contains("after")) continue;
      const Json& before = candidate["before"];
      const Json& after = candidate["after"];
      INFO(candidate["effect"].template get<std::string>()
           << ": " << candidate["verdict"].template get<std::string>());
      CHECK(after["residuals"] == before["residuals"]);
      CHECK(after["fitted_samples"] == before["fitted_samples"]);
      CHECK(after["held_out_samples"] == before["held_out_samples"]);
      CHECK(after["sum_of_squares"].template get<double>() <=
            before["sum_of_squares"].template get<double>());
      ++checked;
    }
  };
  for (const auto& step : result["steps"]) check_list(step["candidates"]);
  check_list(result["last_candidates"]);
  if (result["structure_check"].contains("abandoned_step_candidates")) {
    check_list(result["structure_check"]["abandoned_step_candidates"]);
  }
  return checked;
}

}  // namespace doorbench::testing
