// `doorbench loop`'s result.json lists every refit of every step, kept or rejected, with its
// figures against its parent (fitted and held-out RMSE, BIC, the fitted sum of squares), the
// effect's parameters with their uncertainties and flags, and the verdict
// (docs/residual-loop.md "What result.json holds"); the nested-refit inequality holds on every
// refit it lists.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/files.h"
#include "tests/support/loop_recording.h"
#include "tests/support/nested_refits.h"
#include "tests/support/run_doorbench.h"

TEST_CASE(
    "loop: result.json lists every refit, kept or rejected, with its figures, "
    "parameters and verdict",
    "[cli][loop]") {
  const doorbench::testing::TempDir dir("loop_result");
  // The reference door with a gravity imbalance and viscous damping the start model lacks
  // (the recording of tests/app/test_loop_interrupt.cpp): the loop adds both, and step 1
  // refits and rejects a soft close whose damping the data does not determine.
  const std::string csv = doorbench::testing::simulate_loop_recording(dir);
  const auto out = dir / "out";
  const doorbench::testing::DoorbenchRun run = doorbench::testing::run_doorbench_shell(
      "loop '" + csv + "' --out '" + out.string() + "'", dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const nlohmann::json result =
      nlohmann::json::parse(doorbench::testing::read_file(out / "result.json"));
  INFO(result.dump(1));
  CHECK(doorbench::testing::check_nested_refits_json(result) >= 4);
  REQUIRE(result.at("steps").size() == 2);
  CHECK(result.at("final_model") == "sensory");

  int rejected = 0;
  for (const nlohmann::json& step : result.at("steps")) {
    CHECK(step.at("model") == "sensory");
    int kept = 0;
    for (const nlohmann::json& candidate : step.at("candidates")) {
      const std::string effect = candidate.at("effect");
      const std::string verdict = candidate.at("verdict");
      INFO(effect << ": " << verdict);
      CHECK_FALSE(verdict.empty());
      if (!candidate.at("refitted").get<bool>()) {
        CHECK(verdict.rfind("not refitted: ", 0) == 0);
        CHECK_FALSE(candidate.contains("after"));
        continue;
      }
      // A refit: its figures before and after, and the effect's parameters.
      REQUIRE(candidate.contains("after"));
      for (const char* field :
           {"fitted_rmse_rad_s", "held_out_rmse_rad_s", "bic", "sum_of_squares"}) {
        CHECK(candidate.at("after").at(field).is_number());
        CHECK(candidate.at("before").at(field).is_number());
      }
      CHECK(candidate.at("before") == step.at("before"));
      REQUIRE_FALSE(candidate.at("parameters").empty());
      bool undetermined = false, at_bound = false;
      for (const nlohmann::json& p : candidate.at("parameters")) {
        CHECK(p.at("name").get<std::string>().rfind(effect + ".", 0) == 0);
        CHECK((p.at("standard_uncertainty").is_number() || p.at("standard_uncertainty").is_null()));
        if (p.at("free").get<bool>()) {
          undetermined = undetermined || !p.at("determined").get<bool>();
          at_bound = at_bound || p.at("at_bound").get<bool>();
        }
      }
      // The verdict says what the parameters show: an effect with a free parameter at a bound
      // or undetermined is rejected for it.
      if (undetermined || at_bound) {
        CHECK_FALSE(candidate.at("qualifies").get<bool>());
        CHECK(verdict.find(undetermined ? " undetermined" : " bound ") != std::string::npos);
      }
      if (effect == step.at("effect")) {
        ++kept;
        CHECK(candidate.at("qualifies") == true);
        CHECK(candidate.at("after") == step.at("after"));
        CHECK(verdict.rfind("qualifies: ", 0) == 0);
      } else if (!candidate.at("qualifies").get<bool>()) {
        ++rejected;
        CHECK(verdict.rfind("rejected: ", 0) == 0);
      }
    }
    CHECK(kept == 1);
  }
  CHECK(rejected >= 1);
  CHECK(result.at("last_candidates").is_array());
}
