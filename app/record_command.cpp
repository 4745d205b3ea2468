// doorbench record: a session from a rig; first recovers what an earlier recording in the
// output folder left unfinished (docs/crash-safety.md).
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include "acquisition/record/recorder.h"
#include "acquisition/record/recovery.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/output_file.h"
#include "acquisition/session/printable.h"
#include "acquisition/session/session_csv.h"
#include "acquisition/session/tdms.h"
#include "app/commands.h"
#include "app/limit_watcher.h"
#include "app/number_options.h"
#include "app/session_recording.h"
#include "calibration/range_warnings.h"
#include "sensors/comedi_backend.h"
#include "sensors/modbus_source.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::app {
namespace {

struct RecordCommandOptions {
  std::string rig_path;
  std::string out_path;
  SessionRecordingOptions recording;
};

// Set by SIGINT/SIGTERM while recording; the recorder polls it (a lock-free atomic is
// async-signal-safe).
std::atomic<bool> g_stop_recording{false};

extern "C" void request_stop(int signal_number) {
  g_stop_recording.store(true);
  // A second Ctrl-C ends doorbench at once; the journal keeps what was recorded.
  ::signal(signal_number, SIG_DFL);
}

// Recovers every unfinished session (a journal no running recording holds) in `folder`.
void recover_unfinished_sessions(const std::filesystem::path& folder) {
  for (const std::filesystem::path& journal : find_unfinished_sessions(folder)) {
    std::cerr << "found an unfinished session: " << journal.string() << "\n";
    try {
      const ConvertResult result = recover_session(journal);
      std::cerr << "recovered " << result.brief_report() << "\n";
    } catch (const std::exception& error) {
      std::cerr << "could not recover it: " << error.what() << "\n";
    }
  }
}

void run_record(const RecordCommandOptions& options) {
  const RigDefinition rig = load_rig(options.rig_path);
  const std::filesystem::path out(options.out_path);
  recover_unfinished_sessions(out.parent_path().empty() ? std::filesystem::path(".")
                                                        : out.parent_path());
  // After recovery, which may have made it (docs/output-files.md).
  std::vector<std::filesystem::path> inputs;
  if (!options.rig_path.empty()) inputs.emplace_back(options.rig_path);
  check_output_session(out, inputs);
  SessionRecordingOptions recording = options.recording;
  recording.stop_requested = &g_stop_recording;
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  struct sigaction old_int {
  }, old_term{};
  ::sigaction(SIGINT, &action, &old_int);
  ::sigaction(SIGTERM, &action, &old_term);
  struct Restore {
    const struct sigaction &old_int, &old_term;
    ~Restore() {
      ::sigaction(SIGINT, &old_int, nullptr);
      ::sigaction(SIGTERM, &old_term, nullptr);
    }
  } restore{old_int, old_term};
  const RecordSummary summary = record_rig_session(rig, recording, options.out_path);
  if (summary.stopped_by_request) {
    std::cerr << "stopped by request after " << summary.duration_s << " s\n";
  }
  if (summary.dropped_scans > 0 || summary.dropped_events > 0) {
    std::cerr << "faults: " << summary.brief_report() << "\n";
  }
  if (!summary.trigger_report.empty()) std::cerr << "trigger: " << summary.trigger_report << "\n";
  std::cerr << "wrote " << options.out_path << ": " << rig.channels.size() << " channels, "
            << summary.scans << " scans";
  if (summary.polled_samples > 0) std::cerr << ", " << summary.polled_samples << " polled samples";
  std::cerr << " (" << summary.duration_s << " s), " << summary.events << " events\n";
}

}  // namespace

void add_record_command(CLI::App& app, Action& action) {
  auto record = std::make_shared<RecordCommandOptions>();
  CLI::App* record_command = app.add_subcommand(
      "record",
      "Record a session from a rig: the simulated bench (the rig's door opened and closed by "
      "the virtual hand, through its sensor models) or a comedi DAQ card (needs --duration-s)");
  record_command->add_option("--rig", record->rig_path,
                             "Rig file (TOML); default: the built-in simulated-dishwasher rig");
  record_command
      ->add_option("--duration-s", record->recording.duration_s,
                   "How long to record (from the trigger when the rig has a [recording] "
                   "table); default: the rig's hand cycles")
      ->check(number_range(0.001, 86400.0));
  record_command
      ->add_option("--max-wait-s", record->recording.max_wait_s,
                   "With a rig trigger: how long to wait, armed, for the start condition")
      ->capture_default_str()
      ->check(number_range(0.0, 86400.0));
  record_command->add_option("--out", record->out_path, "The new session file (HDF5)")->required();
  record_command->add_option("--operator", record->recording.operator_name, "Who records");
  record_command->add_option("--product", record->recording.product_id, "The door or product");
  record_command->add_option("--notes", record->recording.notes, "Free text kept in the session");
  record_command
      ->add_option("--flush-interval-s", record->recording.flush_interval_s,
                   "How often the recording journal is synced to disk: at most about this much "
                   "is lost if the machine dies (docs/crash-safety.md)")
      ->capture_default_str()
      ->check(number_range(0.001, 10.0));
  record_command->callback([record, &action] { action = [record] { run_record(*record); }; });
}

}  // namespace doorbench::app
