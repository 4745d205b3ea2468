#pragma once
// Recording a session from a rig, shared by `doorbench record` and the demo.
#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"

namespace doorbench::app {

struct SessionRecordingOptions {
  double duration_s = 0.0;  // 0: the rig's hand cycles
  std::string operator_name;
  std::string product_id;
  std::string notes;
  bool show_progress = true;
  double flush_interval_s = 0.05;                     // RecordOptions::flush_interval_s
  const std::atomic<bool>* stop_requested = nullptr;  // RecordOptions::stop_requested
  // With a rig [recording] table (a trigger): how long the acquisition may wait, armed,
  // for its start condition; --duration-s then counts from the trigger.
  double max_wait_s = 600.0;
};

// The rig file, or the built-in simulated-dishwasher rig when `rig_path` is empty.
RigDefinition load_rig(const std::string& rig_path);
// The rig's DAQ channels on the simulated bench, whatever its daq.backend says.
RecordSummary record_simulated_session(const RigDefinition& rig,
                                       const SessionRecordingOptions& options,
                                       const std::filesystem::path& out_path);
// Any rig: the simulated bench, a comedi card, Modbus sensors, or a DAQ with Modbus sensors
// beside it, on one session clock (sensors::RigRecording, which chooses the backends), with
// the live status on stderr. Throws UsageError for a rig that needs --duration-s.
RecordSummary record_rig_session(const RigDefinition& rig, const SessionRecordingOptions& options,
                                 const std::filesystem::path& out_path);

}  // namespace doorbench::app
