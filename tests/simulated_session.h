#pragma once
// Records the built-in simulated bench (the reference door opened and closed by the
// virtual hand, through the sensor models) into a session at `path`, through the real
// recorder and session writer. Returns the number of scans recorded.
#include <cstdint>
#include <filesystem>

#include "acquisition/recorder.h"
#include "acquisition/rig_file.h"
#include "sensors/simulated_bench.h"

namespace doorbench::testing {

inline std::size_t record_built_in_session(const std::filesystem::path& path, double duration_s,
                                           std::uint64_t seed) {
  RigDefinition rig =
      parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
  rig.simulation->seed = seed;
  const DoorModel model = sensors::simulated_door_model(rig);
  sensors::SimulatedBench bench(rig, model, duration_s);
  SessionMetadata metadata;
  metadata.rig_name = rig.name;
  metadata.rig_definition = rig.text;
  RecordOptions options;
  options.duration_s = duration_s;
  return record_session(bench, metadata, path, options).scans;
}

}  // namespace doorbench::testing
