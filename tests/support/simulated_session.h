#pragma once
// Records the built-in simulated bench (the reference door opened and closed by the
// virtual hand, through the sensor models) into a session at `path`, through the real
// recorder and session writer. Returns the number of scans recorded.
//
// model "physical" (the built-in rig's) or "sensory". The physical reference door falls
// open by its weight once unlatched, faster than the gyroscope's ±100 °/s: its openings
// saturate the gyroscope from about 1.2 s in. The sensory door has no weight and stays
// inside every sensor's range: tests about accuracy use it. effects_file: an effects file
// (door-models.md §4) the simulated door has, by absolute path.
#include <cstdint>
#include <filesystem>
#include <string>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::testing {

// Records `door` on `rig`'s simulated bench into `path`; the number of scans recorded.
inline std::size_t record_door_on_rig(const RigDefinition& rig, const DoorModel& door,
                                      const std::filesystem::path& path, double duration_s) {
  simulated_bench::SimulatedBench bench(rig, door, duration_s);
  SessionMetadata metadata;
  metadata.rig_name = rig.name;
  metadata.rig_definition = rig.text;
  RecordOptions options;
  options.duration_s = duration_s;
  return record_session(bench, metadata, path, options).scans;
}

inline std::size_t record_built_in_session(const std::filesystem::path& path, double duration_s,
                                           std::uint64_t seed,
                                           const std::string& model_kind = "physical",
                                           const std::filesystem::path& effects_file = {}) {
  RigDefinition rig =
      parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
  rig.simulation->seed = seed;
  rig.simulation->model = model_kind;
  rig.simulation->effects = effects_file.string();  // absolute, or empty: none
  return record_door_on_rig(rig, simulated_bench::simulated_door_model(rig), path, duration_s);
}

}  // namespace doorbench::testing
