#pragma once
// A TO-BE door recorded as `doorbench record` records a prototype on the simulated rig: the
// built-in dishwasher rig (virtual hand, sensor models with their noise, the session writer)
// with `door` as the door, then prepared as `doorbench spec` prepares it. The data a
// design search meets on a real bench, not the model's own torque.
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/preprocessing/preprocessing.h"
#include "tests/support/simulated_session.h"

namespace doorbench::testing {

// Records `door` (a physical model) for `duration_s` into `path` and prepares it.
inline PreparedData record_bench_door(const DoorModel& door, const std::filesystem::path& path,
                                      double duration_s = 19.0, std::uint64_t seed = 1) {
  RigDefinition rig =
      parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
  rig.simulation->seed = seed;
  rig.simulation->model = "physical";
  record_door_on_rig(rig, door, path, duration_s);
  return prepare_session(path);
}

// `model` with the named parameters multiplied by their factors.
inline DoorModel with_factors(const DoorModel& model,
                              const std::vector<std::pair<std::string, double>>& factors) {
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  for (const auto& [name, factor] : factors) values[*model.find_parameter(name)] *= factor;
  return model.with_parameter_values(values);
}

}  // namespace doorbench::testing
