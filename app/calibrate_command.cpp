// doorbench calibrate loadcell|inclinometer|gyro|timing|geometry: the calibration
// procedures on the command line (docs/calibration.md). Load cell and inclinometer run a
// guided procedure on the live bench (prompts on stdout, answers on stdin); gyroscope and
// timing work from a recording (--from SESSION) or record one on the live bench first.
// Every result is a new record version in the calibration store.

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numbers>

#include "acquisition/rig/calibration_store.h"
#include "acquisition/session/output_file.h"
#include "acquisition/session/recording_csv.h"
#include "app/commands.h"
#include "app/number_options.h"
#include "app/session_recording.h"
#include "calibration/certificate.h"
#include "calibration/geometry_calibration.h"
#include "calibration/gyro_calibration.h"
#include "calibration/inclinometer_calibration.h"
#include "calibration/least_squares.h"
#include "calibration/load_cell_calibration.h"
#include "calibration/session_signals.h"
#include "calibration/static_source.h"
#include "calibration/timing_calibration.h"
#include "core/time_text.h"
#include "core/units.h"
#include "sensors/rig_channel.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::app {
namespace {

namespace cal = calibration;

// --valid-until: the calibration record's rule for a new record's expiry.
std::string valid_until_problem(const std::string& text) {
  return doorbench::new_valid_until_problem(text, utc_now_iso8601());
}

struct CalibrateOptions {
  std::string rig_path;
  std::string from_session;
  std::string channel;
  std::string store_dir;
  std::string operator_name;
  std::string valid_until;
  std::string certificate;
  bool overwrite = false;   // --certificate may replace an existing file
  std::string out_session;  // gyro/timing live: where the recording goes
  bool apply = false;       // --from: apply the new record to the session
  bool dry_run = false;     // do not store
  double window_s = 1.0;
  // load cell
  std::vector<double> masses_kg{5, 10, 20, 30, 40};
  std::vector<double> forces_N;
  bool tare = false;
  // inclinometer
  std::vector<double> angles_deg{-8, -4, 0, 4, 8};
  // gyro / timing
  std::string inclinometer_channel;
  double inclinometer_range_deg = 0.0;
  // geometry
  std::vector<double> radius_m;
  bool force_geometry = false;  // radii outside 0.05 to 2 m used, not refused
  std::vector<double> angle_deg;
  std::vector<double> check_reference_N, check_reading_N;
  std::string bench_name;
};

// The output rule for --certificate (docs/output-files.md), before the procedure, then it.
void checked(const CalibrateOptions& o, void (*procedure)(const CalibrateOptions&)) {
  if (!o.certificate.empty()) {
    std::vector<std::filesystem::path> inputs;
    if (!o.from_session.empty()) inputs.emplace_back(o.from_session);
    if (!o.rig_path.empty()) inputs.emplace_back(o.rig_path);
    check_output_file(o.certificate, inputs, o.overwrite);
  }
  procedure(o);
}

CalibrationStore store_of(const CalibrateOptions& o, const std::filesystem::path& base) {
  return CalibrationStore(calibration_store_directory(o.store_dir, base));
}

cal::RecordHeader header_for(const CalibrateOptions& o, const CalibrationStore& store,
                             const std::string& kind, const std::string& serial,
                             const std::string& supersedes) {
  cal::RecordHeader header;
  header.sensor_serial = serial;
  header.operator_name = o.operator_name;
  header.date_utc = utc_now_iso8601();
  header.valid_until_utc = o.valid_until;
  header.version = store.next_version(kind, serial);
  header.supersedes = supersedes;
  if (header.supersedes.empty()) {
    if (auto latest = store.latest(kind, serial)) header.supersedes = latest->id;
  }
  return header;
}

// Stores the record (unless --dry-run), writes the certificate, applies it to the session.
void finish(const CalibrateOptions& o, const CalibrationStore& store,
            const CalibrationRecord& record, const std::string& session_channel) {
  std::cout << to_json(record) << "\n";
  if (!o.dry_run) {
    const auto file = store.add(record);
    std::cerr << "stored " << record.id << " in " << file.string() << "\n";
  } else {
    std::cerr << "not stored (--dry-run)\n";
  }
  if (!o.certificate.empty()) {
    cal::write_certificate(o.certificate, record);
    std::cerr << "wrote the certificate " << o.certificate << "\n";
  }
  if (o.apply) {
    if (o.from_session.empty()) throw UsageError("--apply needs --from SESSION");
    const std::string previous = apply_calibration(o.from_session, session_channel, record);
    std::cerr << "applied " << record.id << " to channel " << session_channel << " of "
              << o.from_session << " (was " << previous << ")\n";
  }
}

cal::GuidedOptions guided_options(double window_s, double per_V, const std::string& unit,
                                  double max_std, double max_drift) {
  cal::GuidedOptions g;
  g.window_s = window_s;
  g.display_per_V = per_V;
  g.display_unit = unit;
  g.max_std_V = max_std / per_V;
  g.max_drift_V = max_drift / per_V;
  return g;
}

void run_load_cell(const CalibrateOptions& o) {
  if (!o.from_session.empty()) {
    if (!o.tare) {
      throw UsageError(
          "calibrate loadcell --from SESSION only tares (add --tare): a recording "
          "holds no reference loads");
    }
    const SessionReader session(o.from_session);
    const std::string channel = cal::find_session_channel(session, "load_cell", o.channel);
    const cal::ChannelSignal signal = cal::read_channel_signal(session, channel);
    if (!signal.record)
      throw cal::CalibrationError(o.from_session + ": channel " + channel +
                                  " has no record to tare");
    // The unloaded stretch: before the first stroke, less 0.1 s.
    double end_s = signal.time_s.empty() ? 0.0 : signal.time_s.back();
    for (const SessionEvent& e : session.events()) {
      if (e.kind == "stroke_start") end_s = std::min(end_s, e.time_s - 0.1);
    }
    std::vector<double> unloaded;
    for (std::size_t i = 0; i < signal.time_s.size() && signal.time_s[i] < end_s; ++i) {
      unloaded.push_back(signal.signal[i]);
    }
    if (unloaded.size() < 100) {
      throw cal::CalibrationError(o.from_session +
                                  ": fewer than 100 unloaded samples before the "
                                  "first stroke; the tare needs the cell at rest, unloaded");
    }
    const CalibrationStore store = store_of(o, std::filesystem::current_path());
    const cal::RecordHeader header =
        header_for(o, store, "load_cell", signal.info.sensor_serial, signal.record->id);
    const CalibrationRecord tared =
        cal::tare_load_cell(*signal.record, cal::mean_of(unloaded), cal::std_of(unloaded),
                            static_cast<int>(unloaded.size()), header);
    std::cerr << "tare: the unloaded cell read " << tared.quantity("tare_reading_before_N")->value
              << " N over " << unloaded.size() << " samples\n";
    finish(o, store, tared, channel);
    return;
  }
  RigDefinition rig = load_rig(o.rig_path);
  const RigChannel& channel = cal::find_rig_channel(rig, "load_cell", o.channel);
  const LoadCellParameters p = cal::load_cell_parameters(channel);
  const CalibrationStore store = store_of(o, rig.base_dir);
  std::unique_ptr<cal::StaticSignalSource> source = cal::live_source(rig, channel);
  const double per_V = 1.0 / p.volts_per_newton();
  const cal::GuidedOptions guided = guided_options(o.window_s, per_V, "N", 1.0, 0.3);
  if (o.tare) {
    std::optional<CalibrationRecord> current = store.latest("load_cell", channel.serial);
    if (!current) current = sensors::nominal_calibration(channel);
    const std::vector<cal::GuidedPoint> zero = cal::load_cell_force_points({});
    const auto points =
        cal::run_guided_points(*source, std::span(zero).first(1), guided, std::cin, std::cerr);
    const cal::RecordHeader header = header_for(o, store, "load_cell", channel.serial, current->id);
    finish(o, store,
           cal::tare_load_cell(*current, points[0].signal, points[0].signal_std, points[0].samples,
                               header),
           channel.name);
    return;
  }
  const std::vector<cal::GuidedPoint> plan = o.forces_N.empty()
                                                 ? cal::load_cell_mass_points(o.masses_kg)
                                                 : cal::load_cell_force_points(o.forces_N);
  const auto points = cal::run_guided_points(*source, plan, guided, std::cin, std::cerr);
  cal::LoadCellCalibrationOptions options;
  options.full_scale_N = p.full_scale_N;
  options.compression_only = p.compression_only != 0;
  options.references =
      o.forces_N.empty() ? "reference masses, g = 9.80665 m/s²" : "reference force standard";
  const cal::LoadCellCalibration result = cal::calibrate_load_cell(
      points, options, header_for(o, store, "load_cell", channel.serial, ""));
  std::cerr << result.brief_report();
  finish(o, store, result.record, channel.name);
}

// From a recording of the reference angles held in order (docs/calibration.md).
void run_inclinometer_from(const CalibrateOptions& o) {
  const CalibrationStore store = store_of(o, std::filesystem::current_path());
  std::string channel;
  cal::InclinometerCalibration result;
  {
    const SessionReader session(o.from_session);  // closed before the record is applied
    channel = cal::find_session_channel(session, "inclinometer", o.channel);
    const ChannelInfo& info = session.channel(channel);
    const cal::InclinometerRecordingPoints holds =
        cal::inclinometer_points_from_recording(session, channel, o.angles_deg);
    std::cerr << holds.brief_report();
    // The range and the nominal output: the session's rig, else --inclinometer-range-deg and
    // the channel's current record.
    cal::InclinometerCalibrationOptions options;
    options.references = "reference angles held in a recording (" + o.from_session + ")";
    const std::optional<RigDefinition> rig = cal::session_rig(session);
    const RigChannel* rc = rig ? rig->find_channel(channel) : nullptr;
    if (o.inclinometer_range_deg > 0) {
      options.range_deg = o.inclinometer_range_deg;
    } else if (rc) {
      options.range_deg = cal::inclinometer_parameters(*rc).range_deg;
    } else {
      throw UsageError(o.from_session + ": the session has no rig with inclinometer " + channel +
                       "; give its range with --inclinometer-range-deg");
    }
    if (rc) {
      options.output_V_per_deg = cal::inclinometer_parameters(*rc).output_V_per_deg;
    } else {
      for (const CalibrationRecord& r : session.calibrations()) {
        if (r.id == info.calibration_id && r.coefficients.size() >= 2 && r.coefficients[1] != 0) {
          options.output_V_per_deg = std::abs(1.0 / (r.coefficients[1] * kDegPerRad));
        }
      }
    }
    result = cal::calibrate_inclinometer(
        holds.points(), options,
        header_for(o, store, "inclinometer", info.sensor_serial, info.calibration_id));
  }
  std::cerr << result.brief_report();
  finish(o, store, result.record, channel);
}

void run_inclinometer(const CalibrateOptions& o) {
  if (!o.from_session.empty()) {
    run_inclinometer_from(o);
    return;
  }
  RigDefinition rig = load_rig(o.rig_path);
  const RigChannel& channel = cal::find_rig_channel(rig, "inclinometer", o.channel);
  const InclinometerParameters p = cal::inclinometer_parameters(channel);
  const CalibrationStore store = store_of(o, rig.base_dir);
  std::unique_ptr<cal::StaticSignalSource> source = cal::live_source(rig, channel);
  const cal::GuidedOptions guided =
      guided_options(o.window_s, 1.0 / p.output_V_per_deg, "°", 0.05, 0.02);
  const auto points = cal::run_guided_points(*source, cal::inclinometer_angle_points(o.angles_deg),
                                             guided, std::cin, std::cerr);
  cal::InclinometerCalibrationOptions options;
  options.range_deg = p.range_deg;
  options.output_V_per_deg = p.output_V_per_deg;
  const cal::InclinometerCalibration result = cal::calibrate_inclinometer(
      points, options, header_for(o, store, "inclinometer", channel.serial, ""));
  std::cerr << result.brief_report();
  finish(o, store, result.record, channel.name);
}

// Gyroscope and timing need a recording: --from, or one recorded now on the live bench.
std::string recording_for(CalibrateOptions& o) {
  if (!o.from_session.empty()) return o.from_session;
  if (o.out_session.empty()) {
    throw UsageError("give --from SESSION, or --out SESSION to record one on the live bench now");
  }
  const RigDefinition rig = load_rig(o.rig_path);
  std::cerr << "Recording on " << rig.name
            << ": open and close the door through the closed position a few times, letting it "
               "rest closed for 2 s between strokes (the simulated bench's virtual hand does it). "
               "Press Enter to start: "
            << std::flush;
  std::string answer;
  if (!std::getline(std::cin, answer))
    throw cal::CalibrationError("calibration aborted: the input ended");
  SessionRecordingOptions recording;
  recording.operator_name = o.operator_name;
  recording.notes = "recorded for calibration";
  record_simulated_session(rig, recording, o.out_session);
  o.from_session = o.out_session;
  return o.out_session;
}

// Gyroscope and timing share their frame: the recording (--from, or one recorded now), the
// session's channel of `sensor_kind`, a header that supersedes the channel's current record,
// and the record stored and applied. `calibrate` runs the procedure on the open session,
// which is closed again before the record is applied to it.
template <typename Result, typename Procedure>
void run_from_recording(CalibrateOptions o, const std::string& sensor_kind,
                        const Procedure& calibrate) {
  const std::string path = recording_for(o);
  const CalibrationStore store = store_of(o, std::filesystem::current_path());
  std::string channel;
  Result result;
  {
    const SessionReader session(path);
    channel = cal::find_session_channel(session, sensor_kind, o.channel);
    const ChannelInfo& info = session.channel(channel);
    result = calibrate(session, channel,
                       header_for(o, store, sensor_kind, info.sensor_serial, info.calibration_id));
  }
  std::cerr << result.brief_report();
  finish(o, store, result.record, channel);
}

void run_gyro(const CalibrateOptions& o) {
  run_from_recording<cal::GyroCalibration>(
      o, "gyroscope",
      [&o](const SessionReader& session, const std::string& channel,
           const cal::RecordHeader& header) {
        cal::GyroCalibrationOptions options;
        options.inclinometer_range_deg = o.inclinometer_range_deg;
        return cal::calibrate_gyroscope(session, channel, o.inclinometer_channel, options, header);
      });
}

void run_timing(const CalibrateOptions& o) {
  run_from_recording<cal::TimingCalibration>(
      o, "inclinometer",
      [&o](const SessionReader& session, const std::string& channel,
           const cal::RecordHeader& header) {
        cal::TimingCalibrationOptions options;
        options.gyro.inclinometer_range_deg = o.inclinometer_range_deg;
        return cal::calibrate_timing(session, channel, "", options, header);
      });
}

void run_geometry(const CalibrateOptions& o) {
  if (o.check_reference_N.size() != o.check_reading_N.size()) {
    throw UsageError("--check-reference-N and --check-reading-N need as many values each");
  }
  for (const double radius : o.radius_m) {
    if (std::string problem = handle_radius_problem(radius);
        !o.force_geometry && !problem.empty()) {
      throw UsageError("--radius-m: " + problem + "; give --force-geometry to use it anyway");
    }
  }
  cal::GeometryInputs inputs;
  inputs.handle_radius_m = o.radius_m;
  inputs.mounting_angle_deg = o.angle_deg;
  for (std::size_t i = 0; i < o.check_reference_N.size(); ++i) {
    inputs.tangential_checks_N.emplace_back(o.check_reference_N[i], o.check_reading_N[i]);
  }
  std::string bench = o.bench_name;
  std::filesystem::path base = std::filesystem::current_path();
  if (bench.empty()) {
    const RigDefinition rig = load_rig(o.rig_path);
    bench = rig.name;
    base = rig.base_dir;
  }
  const CalibrationStore store = store_of(o, base);
  const cal::GeometryCalibration result = cal::calibrate_geometry(
      inputs, cal::GeometryCalibrationOptions{}, header_for(o, store, "geometry", bench, ""));
  std::cerr << result.brief_report();
  finish(o, store, result.record, "");
}

void add_common(CLI::App* command, CalibrateOptions& o, bool live, bool from) {
  if (live) {
    command->add_option("--rig", o.rig_path,
                        "Rig file (TOML); default: the built-in simulated-dishwasher rig");
  }
  if (from) {
    command->add_option("--from", o.from_session, "Work from this recording (session file)");
    command->add_flag("--apply", o.apply, "Apply the new record to the --from session too");
  }
  command->add_option("--channel", o.channel, "The channel (default: the only one of its kind)");
  command->add_option("--calibrations", o.store_dir,
                      "Calibration store directory (default: $DOORBENCH_CALIBRATIONS, else "
                      "calibrations/ beside the rig file or in the working directory)");
  command->add_option("--operator", o.operator_name, "Who calibrates");
  command
      ->add_option("--valid-until", o.valid_until,
                   "Expiry, ISO 8601: YYYY-MM-DD or YYYY-MM-DDTHH:MM:SSZ (UTC), not before "
                   "today (default: none)")
      ->check(CLI::Validator(valid_until_problem, "DATE"));
  command->add_option("--certificate", o.certificate, "Write the certificate (HTML) here");
  command->add_flag("--overwrite", o.overwrite, "Replace an existing --certificate file");
  command->add_flag("--dry-run", o.dry_run, "Show the record, do not store it");
}

}  // namespace

void add_calibrate_command(CLI::App& app, Action& action) {
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "Calibrate a sensor (guided on the live bench, or from a recording) and keep "
      "the record in the calibration store");
  calibrate->require_subcommand(1);
  auto o = std::make_shared<CalibrateOptions>();

  CLI::App* loadcell = calibrate->add_subcommand(
      "loadcell", "Load cell: reference masses (or forces) loading and unloading; or --tare");
  add_common(loadcell, *o, true, true);
  CLI::Option* masses =
      loadcell->add_option("--masses-kg", o->masses_kg, "Reference masses, comma-separated")
          ->delimiter(',');
  CLI::Option* forces =
      loadcell->add_option("--forces-N", o->forces_N, "Reference forces instead of masses")
          ->delimiter(',');
  // A tare loads nothing: masses or forces given with it would be ignored, so they are refused.
  loadcell
      ->add_flag("--tare", o->tare,
                 "Tare: a new version whose offset makes the unloaded cell read 0 (live, or "
                 "from the unloaded start of --from SESSION)")
      ->excludes(masses)
      ->excludes(forces);
  loadcell->add_option("--window-s", o->window_s, "Stable window averaged per point")
      ->check(number_range(0.01, 600.0));
  loadcell->callback([o, &action] { action = [o] { checked(*o, run_load_cell); }; });

  CLI::App* inclinometer = calibrate->add_subcommand(
      "inclinometer",
      "Inclinometer: offset and gain against reference angles across its range (guided, or "
      "--from a recording of the angles held in the order of --angles-deg)");
  add_common(inclinometer, *o, true, true);
  inclinometer->add_option("--angles-deg", o->angles_deg, "Reference angles, comma-separated")
      ->delimiter(',');
  inclinometer->add_option("--window-s", o->window_s, "Stable window averaged per point")
      ->check(number_range(0.01, 600.0));
  inclinometer->add_option("--inclinometer-range-deg", o->inclinometer_range_deg,
                           "With --from: the inclinometer's range when the session has no rig");
  inclinometer->callback([o, &action] { action = [o] { checked(*o, run_inclinometer); }; });

  CLI::App* gyro = calibrate->add_subcommand(
      "gyro", "Gyroscope: bias from still periods, drift, scale factor against the inclinometer");
  add_common(gyro, *o, true, true);
  gyro->add_option("--out", o->out_session, "Without --from: record the live bench here first");
  gyro->add_option("--inclinometer", o->inclinometer_channel, "The inclinometer channel");
  gyro->add_option("--inclinometer-range-deg", o->inclinometer_range_deg,
                   "The inclinometer's range when the session has no rig");
  gyro->callback([o, &action] { action = [o] { checked(*o, run_gyro); }; });

  CLI::App* timing = calibrate->add_subcommand(
      "timing",
      "Timing: the inclinometer's delay by cross-correlation with the integrated "
      "gyroscope; a new inclinometer record with delay_s");
  add_common(timing, *o, true, true);
  timing->add_option("--out", o->out_session, "Without --from: record the live bench here first");
  timing->add_option("--inclinometer-range-deg", o->inclinometer_range_deg,
                     "The inclinometer's range when the session has no rig");
  timing->callback([o, &action] { action = [o] { checked(*o, run_timing); }; });

  CLI::App* geometry = calibrate->add_subcommand(
      "geometry", "Geometry: handle radius and the load cell's mounting angle, with uncertainty");
  add_common(geometry, *o, true, false);
  geometry->add_option("--radius-m", o->radius_m, "Measurements of the handle radius")
      ->delimiter(',')
      ->required();
  geometry->add_flag("--force-geometry", o->force_geometry,
                     "Use --radius-m values outside 0.05 to 2 m");
  geometry->add_option("--angle-deg", o->angle_deg, "Measurements of the mounting angle")
      ->delimiter(',');
  geometry
      ->add_option("--check-reference-N", o->check_reference_N,
                   "Reference forces applied tangentially (estimates the angle)")
      ->delimiter(',');
  geometry->add_option("--check-reading-N", o->check_reading_N, "The load cell's readings")
      ->delimiter(',');
  geometry->add_option("--bench", o->bench_name, "The bench's name (default: the rig's)");
  geometry->callback([o, &action] { action = [o] { checked(*o, run_geometry); }; });
}

}  // namespace doorbench::app
