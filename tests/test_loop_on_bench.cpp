// The residual loop on a session recorded on the simulated bench, through the sensor
// models, the session file and preprocessing: the path a real recording takes. The door
// has a gravity imbalance that the sensory model does not declare.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <string>

#include "analysis/parameter_file.h"
#include "analysis/preprocessing.h"
#include "analysis/residual_loop.h"
#include "tests/simulated_session.h"
#include "tests/temp_dir.h"

using doorbench::LoopResult;
using doorbench::ModelKind;
using doorbench::PreparedData;

TEST_CASE("residual loop: names an undeclared gravity imbalance in a bench recording",
          "[residual_loop][session]") {
  const doorbench::testing::TempDir dir("loop_on_bench");
  const double g1_N_m = 3.0;
  const auto effects_path = std::filesystem::absolute(dir.path / "undeclared.json");
  std::ofstream(effects_path) << R"({"gravity_imbalance": {"g1": )" << g1_N_m << "}}\n";
  const auto session_path = dir.path / "undeclared.h5";
  doorbench::testing::record_built_in_session(session_path, 19.0, 1, "sensory", effects_path);

  const PreparedData data = doorbench::prepare_session(session_path);
  REQUIRE(data.strokes.size() == 6);
  const LoopResult loop =
      doorbench::run_residual_loop(doorbench::reference_model(ModelKind::kSensory), data);
  INFO(loop.full_report());
  REQUIRE(loop.steps.size() == 1);
  const doorbench::LoopStep& step = loop.steps.front();
  CHECK(step.effect_name == "gravity_imbalance");
  CHECK(step.rank == 1);
  // Measured: held-out window RMSE of ω 0.148 → 0.0085 rad/s.
  CHECK(step.after.held_out_rmse_rad_s < 0.1 * step.before.held_out_rmse_rad_s);
  CHECK(step.after.bic < step.before.bic);
  REQUIRE(step.parameters.size() == 1);
  const doorbench::FittedParameter& g1 = step.parameters.front();
  INFO(g1.name << " = " << g1.value << " +- " << g1.uncertainty);
  CHECK(g1.name == "gravity_imbalance.g1");
  CHECK(std::abs(g1.value - g1_N_m) <= 3.0 * g1.uncertainty);
}
