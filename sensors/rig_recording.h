#pragma once
// Recording a session from a rig, whatever records it: the rig's DAQ (a comedi card, or the
// simulated bench) with its Modbus sensors polled beside it on one session clock, or its
// polled sensors alone (daq.backend "none"); through the rig's triggers when it has a
// [recording] table (docs/triggering.md), the Enter key standing for a manual trigger.
//
// The simulated bench is above this library (simulated_bench/): the caller passes how to
// make it (simulated_bench::simulated_scans, simulated_bench/simulated_bench.h).
//
// Errors: RigRecording's constructor throws std::invalid_argument with
// RigRecordingOptions::problem's text, std::runtime_error for a DAQ channel the simulated
// bench cannot record and whatever opening the devices throws; record() throws what
// record_session throws.
// Thread safety: one RigRecording per thread; its ManualKeys runs one reader thread of its
// own, stopped and joined when the recording is destroyed.
#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"

namespace doorbench::sensors {

class ComediBackend;

// The simulated bench for a rig's DAQ channels, made by the caller: the backend (owning
// its door model), the duration it plays (its hand cycles unless a duration is asked for)
// and whether it is paced like a real DAQ.
struct SimulatedScans {
  std::shared_ptr<AcquisitionBackend> backend;
  double duration_s = 0.0;
  bool paced = false;
};
using SimulatedScansMaker =
    std::function<SimulatedScans(const RigDefinition& daq_rig, double duration_s)>;

// The Enter key for a manual trigger: lines read from `fd` (stdin) on a thread of its own;
// the first sets start() (already set when `start_set`), every later one sets stop(). The
// destructor wakes the reader through a pipe and joins it, so nothing reads `fd` after.
class ManualKeys {
 public:
  explicit ManualKeys(bool start_set, int fd = 0);
  ~ManualKeys();
  ManualKeys(const ManualKeys&) = delete;
  ManualKeys& operator=(const ManualKeys&) = delete;
  const std::atomic<bool>* start() const { return &start_; }
  const std::atomic<bool>* stop() const { return &stop_; }

 private:
  void read_keys(int fd);
  std::atomic<bool> start_{false}, stop_{false};
  int wake_[2] = {-1, -1};  // a pipe: writing to wake_[1] ends the reader
  std::thread reader_;
};

struct RigRecordingOptions {
  // > 0: how long to record (from the trigger when the rig has a [recording] table); 0: the
  // simulated bench's hand cycles (a card or polled sensors then need the rig's triggers).
  double duration_s = 0.0;
  // With a rig trigger: how long the acquisition may wait, armed, for its start condition.
  double max_wait_s = 600.0;
  double flush_interval_s = 0.05;                     // RecordOptions::flush_interval_s
  const std::atomic<bool>* stop_requested = nullptr;  // RecordOptions::stop_requested
  int key_fd = 0;  // where a manual trigger's Enter key is read (stdin)
  // Instructions for the operator ("armed: press Enter to start recording"), each one line
  // without its newline, while the recording is set up; null: none shown.
  std::function<void(const std::string&)> notice;

  // "" when `rig` can record with these options; else why not, naming the command line's
  // option: "a comedi rig records for a set time: give --duration-s (or a [recording] table
  // with its triggers)" (likewise "a rig of polled sensors"), or a duration, wait or flush
  // interval that is not a positive number.
  std::string problem(const RigDefinition& rig) const;
};

// One recording of a rig: the sources opened and the trigger armed on construction,
// recorded by record().
class RigRecording {
 public:
  RigRecording(const RigDefinition& rig, const RigRecordingOptions& options,
               const SimulatedScansMaker& simulated);
  ~RigRecording();
  RigRecording(const RigRecording&) = delete;
  RigRecording& operator=(const RigRecording&) = delete;

  // The duration a status line counts towards: the trigger's, else the recording's.
  double display_duration_s() const { return display_duration_s_; }
  // The DAQ's set-up as the card will run it (ComediSetup::brief_report), "" for others.
  const std::string& setup_report() const { return setup_report_; }
  // Records once; `progress` gets the live status from the recorder's writer thread
  // (RecordOptions::progress; null: none).
  RecordSummary record(const SessionMetadata& metadata, const std::filesystem::path& out_path,
                       std::function<void(const RecordStatus&)> progress = nullptr);
  // After record(): "" or why the DAQ ended early ("...; the session keeps what was read
  // before it").
  std::string end_warning() const;

 private:
  void open_daq(const RigDefinition& daq_rig, const SimulatedScansMaker& simulated);
  double configure_triggering(const RigDefinition& rig);
  void set_timed_recording(const RigDefinition& rig);

  RigRecordingOptions options_;
  RecordOptions record_;
  double display_duration_s_ = 0.0;
  std::string setup_report_;
  std::unique_ptr<ManualKeys> keys_;
  std::shared_ptr<AcquisitionBackend> daq_;
  ComediBackend* comedi_ = nullptr;  // daq_ when it is a comedi card
  std::vector<std::unique_ptr<PolledSource>> polled_;
};

}  // namespace doorbench::sensors
