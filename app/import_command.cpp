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
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include "acquisition/record/recorder.h"
#include "acquisition/record/recovery.h"
#include "acquisition/rig/calibration_store.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/import_units.h"
#include "acquisition/session/output_file.h"
#include "acquisition/session/printable.h"
#include "acquisition/session/recording_csv.h"
#include "acquisition/session/resample.h"
#include "acquisition/session/session_csv.h"
#include "acquisition/session/tdms.h"
#include "app/commands.h"
#include "app/csv_metadata_keys.h"
#include "app/limit_watcher.h"
#include "app/number_options.h"
#include "app/session_recording.h"
#include "calibration/range_warnings.h"
#include "core/number_format.h"
#include "core/time_text.h"
#include "sensors/comedi_backend.h"
#include "sensors/modbus_source.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::app {
namespace {

struct ImportOptions {
  std::string csv_path;
  std::string out_path;
  std::string operator_name, product_id, notes;
  // TDMS files: TARGET=GROUP/CHANNEL,... (acquisition/session/tdms.h); CSV files:
  // TARGET=COLUMN,... (acquisition/session/import_units.h).
  std::string map;
  bool keep_raw = false;  // TDMS files: the DAQmx scalers' raw values beside the scaled ones
  std::string separator = "comma";  // CSV files: comma, semicolon or tab
  bool decimal_comma = false;       // CSV files: ',' is the decimal point
  double resample_hz = 0.0;         // > 0: the recording on a uniform clock of this rate
  double rate_hz = 0.0;             // TDMS files: > 0, the rate of channels without wf_increment
  std::string start_time;           // the session's start (ISO 8601 UTC); "": the file's, else now
  // Raw channels to physical units (acquisition/session/import_units.h).
  std::vector<std::string> scales, calibrations;
  std::string store_dir;  // --calibrations: the store --calibration's ids are in
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
  std::vector<ImportConversion> conversions;
  try {
    conversions =
        parse_import_conversions(options.scales, options.calibrations,
                                 CalibrationStore(calibration_store_directory(
                                     options.store_dir, std::filesystem::current_path())));
  } catch (const std::invalid_argument& error) {
    throw UsageError(error.what());
  }
  if (extension != ".tdms") {
    if (options.keep_raw) throw UsageError("--keep-raw is for TDMS files (*.tdms)");
    CsvDialect dialect;
    dialect.separator = options.separator == "semicolon" ? ';'
                        : options.separator == "tab"     ? '\t'
                                                         : ',';
    dialect.decimal_comma = options.decimal_comma;
    if (const std::string problem = dialect.validate(); !problem.empty()) throw UsageError(problem);
    if (options.rate_hz > 0) {
      throw UsageError("--rate-hz is for TDMS files (*.tdms): a CSV's time_s gives the time");
    }
    try {
      return read_csv_import(options.csv_path, options.map, conversions, dialect);
    } catch (const CsvMapSyntaxError& error) {
      throw UsageError(error.what());
    }
  }
  if (options.separator != "comma" || options.decimal_comma) {
    throw UsageError("--separator and --decimal-comma are for CSV files");
  }
  // The file first: a missing or malformed --map is answered with the channels to map.
  const TdmsFile file = read_tdms(options.csv_path);
  if (options.map.empty()) {
    throw UsageError(
        "a TDMS file needs --map force=GROUP/CHANNEL,angle=GROUP/CHANNEL (or rate=); the file's "
        "channels: " +
        tdms_channel_list(file));
  }
  std::vector<TdmsMapItem> map;
  try {
    map = parse_tdms_map(options.map);
  } catch (const std::invalid_argument& error) {
    throw UsageError(std::string(error.what()) +
                     "; the file's channels: " + tdms_channel_list(file));
  }
  TdmsImportOptions tdms_options;
  tdms_options.keep_raw = options.keep_raw;
  tdms_options.rate_hz = options.rate_hz;
  tdms_options.conversions = std::move(conversions);
  return tdms_to_recording(file, map, options.csv_path, tdms_options);
}

void run_import(const ImportOptions& options) {
  check_output_session(options.out_path, {options.csv_path});
  const Recording recording = options.resample_hz > 0
                                  ? resample_recording(read_import(options), options.resample_hz)
                                  : read_import(options);
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
      !options.start_time.empty()
          ? options.start_time
          : from_csv(kCsvStartKey, from_csv("tdms_wf_start_time", utc_now_iso8601()));
  metadata.software_version = std::string("doorbench ") + DOORBENCH_VERSION;
  metadata.notes = options.notes.empty() ? "imported from " + options.csv_path : options.notes;
  std::string how;  // the line resample_recording() added last
  for (const auto& [key, value] : recording.metadata) {
    if (options.resample_hz > 0 && key == kResampledMetadataKey) how = value;
  }
  if (!how.empty()) metadata.notes += "; resampled " + how;
  for (const auto& [column, record] : recording.calibrations) {
    metadata.notes += "; " + column + " through " + record.id + " (" + record.input_unit + " to " +
                      record.unit + ", " + record.method + ")";
  }
  recording_to_session(recording, options.out_path, metadata);
  std::cerr << "wrote " << options.out_path << ": " << recording.size() << " samples"
            << (how.empty() ? "" : ", resampled " + how) << "\n";
  for (const auto& [column, record] : recording.calibrations) {
    std::cerr << "  " << column << ": raw " << printable(record.input_unit)
              << " kept, physical through " << printable(record.id) << " ("
              << printable(record.method) << ")\n";
  }
  for (const std::string& doubt : unit_doubts(recording)) {
    std::cerr << "warning: " << kUnitDoubtWarning << doubt << "\n";
  }
  if (const auto dates = imported_date_times(recording)) {
    const char* lacks = dates->date_stated ? "no time zone" : "no date";
    std::cerr << "  time_s: " << (dates->date_stated ? "dates and times" : "times of the day")
              << " read as seconds since the first, " << dates->first
              << (dates->zone_stated ? "" : std::string(" (") + lacks + " stated)") << "\n";
    if (dates->start_unknown(!options.start_time.empty())) {
      std::cerr << "warning: the time column states " << lacks
                << ", so the session's start is the import's time; give the recording's with "
                   "--start-time (ISO 8601 UTC)\n";
    }
  }
}

}  // namespace

void add_import_command(CLI::App& app, Action& action) {
  auto import = std::make_shared<ImportOptions>();
  CLI::App* import_command = app.add_subcommand(
      "import",
      "Make a session of a recording from elsewhere: the CSV exchange format (or any CSV with "
      "--map naming its columns), or a TDMS file (LabVIEW, SignalExpress, DAQmx logging) with "
      "--map (docs/tdms.md)");
  import_command->add_option("CSV", import->csv_path, "Recording (CSV, or *.tdms with --map)")
      ->required();
  import_command->add_option("--out", import->out_path, "The new session file (HDF5)")->required();
  import_command->add_option("--operator", import->operator_name, "Who recorded it");
  import_command->add_option("--product", import->product_id, "The door or product");
  import_command->add_option("--notes", import->notes, "Free text kept in the session");
  import_command->add_option("--map", import->map,
                             "The file's own channels: force=GROUP/CHANNEL,angle=GROUP/CHANNEL"
                             "[,rate=...][,time=...][,NAME_UNIT=...] for TDMS; "
                             "time=COLUMN,force=COLUMN,angle=COLUMN[,...] for CSV (a CSV's "
                             "other columns are left out; a unit its name states in ms, kN, "
                             "deg, deg/s or rpm is converted)");
  import_command
      ->add_option("--separator", import->separator,
                   "CSV files: what separates the fields: comma (the exchange format), semicolon "
                   "or tab (docs/csv-format.md)")
      ->check(CLI::IsMember({"comma", "semicolon", "tab"}))
      ->capture_default_str();
  import_command->add_flag("--decimal-comma", import->decimal_comma,
                           "CSV files: ',' is the decimal point (1,5 for 1.5), with --separator "
                           "semicolon or tab");
  import_command->add_flag("--keep-raw", import->keep_raw,
                           "TDMS files: also each mapped channel's DAQmx raw values as stored "
                           "(ADC counts), as columns TARGET_raw");
  import_command
      ->add_option("--resample-hz", import->resample_hz,
                   "Put the recording on a uniform clock of this rate: slower, each sample the "
                   "mean over its interval; faster, linear interpolation (e.g. a 100 kHz "
                   "recording at 1000 Hz for fit; docs/csv-format.md)")
      ->check(number_range(1.0, 1e6));
  import_command
      ->add_option("--rate-hz", import->rate_hz,
                   "TDMS files: the sample rate of channels without waveform timing (no "
                   "wf_increment), Hz (docs/tdms.md)")
      ->check(number_range(1e-6, 1e7));
  import_command
      ->add_option("--start-time", import->start_time,
                   "The session's start, the time of the first sample, ISO 8601 UTC "
                   "(2024-05-02T09:30:00Z); default: the file's (wf_start_time, "
                   "start_time_utc), else now")
      ->check(CLI::Validator(iso8601_utc_problem, "TIME"));
  import_command
      ->add_option(
          "--scale", import->scales,
          "A target's channel is a raw signal: physical = GAIN * raw + OFFSET, e.g. "
          "force=98.1,-0.5 (raw values kept; the session names the scale); repeat per target")
      ->allow_extra_args(false);
  import_command
      ->add_option(
          "--calibration", import->calibrations,
          "A target's channel is a raw signal that a calibration record makes physical: "
          "TARGET=ID (in the store) or TARGET=FILE.json, e.g. force=load_cell-LC1-v2 (raw values "
          "and the record kept); repeat per target")
      ->allow_extra_args(false);
  import_command->add_option("--calibrations", import->store_dir,
                             "The calibration store of --calibration's ids (default: "
                             "$DOORBENCH_CALIBRATIONS, else ./calibrations)");
  import_command->callback([import, &action] { action = [import] { run_import(*import); }; });
}

}  // namespace doorbench::app
