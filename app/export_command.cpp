// doorbench export: a session as CSV in the exchange format.
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
#include "app/csv_metadata_keys.h"
#include "app/limit_watcher.h"
#include "app/session_recording.h"
#include "calibration/range_warnings.h"
#include "sensors/comedi_backend.h"
#include "sensors/modbus_source.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::app {
namespace {

// A metadata value on one line: line breaks become spaces.
std::string one_line(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

struct ExportOptions {
  std::string session_path;
  std::string csv_path;
  bool overwrite = false;
};

void run_export(const ExportOptions& options) {
  const std::string& session_path = options.session_path;
  const std::string& csv_path = options.csv_path;
  check_output_file(csv_path, {session_path}, options.overwrite);
  const SessionReader session(session_path);
  Recording recording = session_to_recording(session);
  // Who, what and when, so that import gives them back (docs/csv-format.md).
  const SessionMetadata& m = session.metadata();
  for (const auto& [key, value] : {std::pair<std::string, std::string>{kCsvRigKey, m.rig_name},
                                   {kCsvOperatorKey, m.operator_name},
                                   {kCsvProductKey, m.product_id},
                                   {kCsvStartKey, m.start_time_utc}}) {
    if (!value.empty()) recording.metadata.emplace_back(key, one_line(value));
  }
  write_recording_csv_file(csv_path, recording);
  std::cerr << "wrote " << csv_path << ": " << recording.size() << " rows";
  // A channel cut short (session_to_recording): the rows go on, its cells empty.
  for (const auto& [key, value] : recording.metadata) {
    if (key == kCutShortKey)
      std::cerr << "; cells left empty where a channel ends early: " << value;
  }
  std::cerr << "\n";
}

}  // namespace

void add_export_command(CLI::App& app, Action& action) {
  auto export_options = std::make_shared<ExportOptions>();
  CLI::App* export_command = app.add_subcommand(
      "export",
      "Write a session as CSV (the exchange format: physical units, strokes marked, the force "
      "signed by the load cell's mounting)");
  export_command->add_option("SESSION", export_options->session_path, "Session file (HDF5)")
      ->required();
  export_command->add_option("--csv", export_options->csv_path, "The CSV file to write")
      ->required();
  export_command->add_flag("--overwrite", export_options->overwrite,
                           "Replace an existing CSV file");
  export_command->callback(
      [export_options, &action] { action = [export_options] { run_export(*export_options); }; });
}

}  // namespace doorbench::app
