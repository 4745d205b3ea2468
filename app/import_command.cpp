// doorbench import: a session of a recording from elsewhere (CSV exchange format, TDMS).
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

struct ImportOptions {
  std::string csv_path;
  std::string out_path;
  std::string operator_name, product_id, notes;
  std::string tdms_map;  // TDMS files: TARGET=GROUP/CHANNEL,... (acquisition/session/tdms.h)
  bool keep_raw = false;  // TDMS files: the DAQmx scalers' raw values beside the scaled ones
};

// A TDMS file (by its .tdms extension, any case) through --map, else the CSV exchange format.
Recording read_import(const ImportOptions& options) {
  std::string extension = std::filesystem::path(options.csv_path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".tdms_index") {
    std::string data = options.csv_path;
    data.resize(data.size() - std::string("_index").size());
    throw TdmsError(options.csv_path +
                    ": this is a TDMS index file (.tdms_index); import the .tdms file itself (" +
                    data + ")");
  }
  if (extension != ".tdms") {
    if (!options.tdms_map.empty()) throw UsageError("--map is for TDMS files (*.tdms)");
    if (options.keep_raw) throw UsageError("--keep-raw is for TDMS files (*.tdms)");
    return read_recording_csv(options.csv_path, EmptyCells::kMissing);  // empty: lost samples
  }
  // The file first: a missing or malformed --map is answered with the channels to map.
  const TdmsFile file = read_tdms(options.csv_path);
  if (options.tdms_map.empty()) {
    throw UsageError(
        "a TDMS file needs --map force=GROUP/CHANNEL,angle=GROUP/CHANNEL (or rate=); the file's "
        "channels: " +
        tdms_channel_list(file));
  }
  std::vector<TdmsMapItem> map;
  try {
    map = parse_tdms_map(options.tdms_map);
  } catch (const std::invalid_argument& error) {
    throw UsageError(std::string(error.what()) + "; the file's channels: " +
                     tdms_channel_list(file));
  }
  return tdms_to_recording(file, map, options.csv_path, options.keep_raw);
}

void run_import(const ImportOptions& options) {
  check_output_session(options.out_path, {options.csv_path});
  const Recording recording = read_import(options);
  // The recording's own rig, operator, product and start (an exported session's) unless
  // given; else "imported" and now.
  auto from_csv = [&recording](const char* key, const std::string& otherwise) {
    for (const auto& [k, value] : recording.metadata) {
      if (k == key && !value.empty()) return value;
    }
    return otherwise;
  };
  SessionMetadata metadata;
  metadata.rig_name = from_csv(kCsvRigKey, "imported");
  metadata.operator_name =
      options.operator_name.empty() ? from_csv(kCsvOperatorKey, "") : options.operator_name;
  metadata.product_id =
      options.product_id.empty() ? from_csv(kCsvProductKey, "") : options.product_id;
  // A TDMS file's wf_start_time (its first sample's time) is the start when it has one.
  metadata.start_time_utc =
      from_csv(kCsvStartKey, from_csv("tdms_wf_start_time", utc_now_iso8601()));
  metadata.software_version = std::string("doorbench ") + DOORBENCH_VERSION;
  metadata.notes = options.notes.empty() ? "imported from " + options.csv_path : options.notes;
  recording_to_session(recording, options.out_path, metadata);
  std::cerr << "wrote " << options.out_path << ": " << recording.size() << " samples\n";
}

}  // namespace

void add_import_command(CLI::App& app, Action& action) {
  auto import = std::make_shared<ImportOptions>();
  CLI::App* import_command = app.add_subcommand(
      "import",
      "Make a session of a recording from elsewhere: the CSV exchange format, or a TDMS file "
      "(LabVIEW, SignalExpress, DAQmx logging) with --map (docs/tdms.md)");
  import_command
      ->add_option("CSV", import->csv_path, "Recording (CSV exchange format, or *.tdms with --map)")
      ->required();
  import_command->add_option("--out", import->out_path, "The new session file (HDF5)")->required();
  import_command->add_option("--operator", import->operator_name, "Who recorded it");
  import_command->add_option("--product", import->product_id, "The door or product");
  import_command->add_option("--notes", import->notes, "Free text kept in the session");
  import_command->add_option("--map", import->tdms_map,
                             "TDMS channels: force=GROUP/CHANNEL,angle=GROUP/CHANNEL[,rate=...]"
                             "[,time=...][,NAME_UNIT=...]");
  import_command->add_flag("--keep-raw", import->keep_raw,
                           "TDMS files: also each mapped channel's DAQmx raw values as stored "
                           "(ADC counts), as columns TARGET_raw");
  import_command->callback([import, &action] { action = [import] { run_import(*import); }; });
}

}  // namespace doorbench::app
