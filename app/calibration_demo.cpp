#include "app/calibration_demo.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <ostream>
#include <sstream>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/calibration_store.h"
#include "acquisition/session/session_csv.h"
#include "calibration/demo_rig.h"
#include "calibration/gyro_calibration.h"
#include "calibration/inclinometer_calibration.h"
#include "calibration/load_cell_calibration.h"
#include "calibration/static_source.h"
#include "calibration/timing_calibration.h"
#include "core/units.h"
#include "sensors/rig_channel.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::app {
namespace {

namespace cal = calibration;
namespace fs = std::filesystem;

std::string f(double value, int decimals) {
  return cal::fixed(value, decimals);
}

// Removes the scratch folder however the demo ends.
struct Scratch {
  fs::path path;
  Scratch() {
    path = fs::temp_directory_path() / ("doorbench-calibration-demo-" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Scratch() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

cal::RecordHeader header(const CalibrationStore& store, const std::string& kind,
                         const std::string& serial, const std::string& supersedes) {
  cal::RecordHeader h;
  h.sensor_serial = serial;
  h.operator_name = "calibration demo";
  h.date_utc = "2026-11-21T10:00:00Z";
  h.version = store.next_version(kind, serial);
  h.supersedes = supersedes;
  return h;
}

// Errors of a session's physical values (as analysis reads them: session_to_recording,
// which also corrects delays) against the simulation's truth.
struct Errors {
  double force_rms_N = 0.0;         // during strokes (|F| > 1 N)
  double force_rest_mean_N = 0.0;   // unloaded, before the first stroke
  double angle_rms_deg = 0.0;       // inclinometer, where the door is within ±9°
  double rate_rest_mean_dps = 0.0;  // gyroscope at rest: its bias
  double rate_rms_dps = 0.0;        // gyroscope while moving, unsaturated
};

Errors errors_of(const fs::path& session_path) {
  const SessionReader session(session_path);
  const Recording r = session_to_recording(session);
  const std::vector<double> theta = session.read_group_dataset("truth", "theta_rad");
  const std::vector<double> omega = session.read_group_dataset("truth", "omega_rad_s");
  const std::vector<double> force = session.read_group_dataset("truth", "force_N");
  const std::vector<double>* inclinometer = nullptr;
  for (std::size_t k = 0; k < r.extra_names.size(); ++k) {
    if (r.extra_names[k].find("angle") != std::string::npos) inclinometer = &r.extra_columns[k];
  }
  // Unloaded: before the first stroke (later rests are signed by the last stroke's mounting).
  double first_stroke_s = r.time_s.empty() ? 0.0 : r.time_s.back();
  for (const SessionEvent& event : session.events()) {
    if (event.kind == "stroke_start") first_stroke_s = std::min(first_stroke_s, event.time_s);
  }
  Errors e;
  double fs2 = 0, fr = 0, a2 = 0, rr = 0, r2 = 0;
  int nf = 0, nfr = 0, na = 0, nr = 0, nm = 0;
  for (std::size_t i = 0; i < r.size() && i < theta.size(); ++i) {
    if (std::abs(force[i]) > 1.0) {
      fs2 += std::pow(r.force_N[i] - force[i], 2);
      ++nf;
    } else if (force[i] == 0.0 && r.time_s[i] < first_stroke_s) {
      fr += r.force_N[i];
      ++nfr;
    }
    if (inclinometer && std::abs(theta[i]) * kDegPerRad < 9.0) {
      a2 += std::pow(((*inclinometer)[i] - theta[i]) * kDegPerRad, 2);
      ++na;
    }
    const double rate_error = ((*r.rate_rad_s)[i] - omega[i]) * kDegPerRad;
    if (std::abs(omega[i]) * kDegPerRad < 0.01) {
      rr += rate_error;
      ++nr;
    } else if (std::abs(omega[i]) * kDegPerRad < 90) {
      r2 += rate_error * rate_error;
      ++nm;
    }
  }
  e.force_rms_N = std::sqrt(fs2 / std::max(nf, 1));
  e.force_rest_mean_N = fr / std::max(nfr, 1);
  e.angle_rms_deg = std::sqrt(a2 / std::max(na, 1));
  e.rate_rest_mean_dps = rr / std::max(nr, 1);
  e.rate_rms_dps = std::sqrt(r2 / std::max(nm, 1));
  return e;
}

// 1. Load cell: the guided procedure, a simulated operator pressing Enter; the record
// added to the store and what it found printed against the truth.
cal::LoadCellCalibration calibrate_demo_load_cell(const CalibrationStore& store,
                                                  const RigDefinition& rig, const RigChannel& lc,
                                                  std::ostream& out) {
  const auto lcp = cal::load_cell_parameters(lc);
  const double true_gain_N_per_V = 1.0 / lcp.volts_per_newton();
  const double true_offset_N = -lcp.zero_offset_N;
  const CalibrationRecord stale = store.get(lc.calibration);
  std::vector<double> masses{5, 10, 20, 30, 40};
  const auto plan = cal::load_cell_mass_points(masses);
  cal::SimulatedStaticSource lc_source(rig, lc, 11);
  const cal::GuidedOptions guided{.max_std_V = 1.0 / true_gain_N_per_V,
                                  .max_drift_V = 0.3 / true_gain_N_per_V,
                                  .display_per_V = true_gain_N_per_V,
                                  .display_unit = "N"};
  std::istringstream enter(std::string(plan.size(), '\n'));
  std::ostringstream dialogue;
  const auto lc_points = cal::run_guided_points(lc_source, plan, guided, enter, dialogue);
  cal::LoadCellCalibrationOptions lc_options;
  lc_options.full_scale_N = lcp.full_scale_N;
  const cal::LoadCellCalibration load_cell = cal::calibrate_load_cell(
      lc_points, lc_options, header(store, "load_cell", lc.serial, stale.id));
  store.add(load_cell.record);
  {
    std::istringstream lines(dialogue.str());
    std::string line;
    out << "\n1. Load cell " << lc.serial << ": guided, " << plan.size()
        << " points (masses loading, then unloading); the dialogue begins:\n";
    for (int i = 0; i < 5 && std::getline(lines, line); ++i) out << "     | " << line << "\n";
    out << "     | ...\n";
  }
  out << "   offset: last year's record " << f(stale.coefficients[0], 3) << " N, now "
      << f(load_cell.offset_N, 3) << " ± " << f(load_cell.offset_std_N, 3) << " N (truth "
      << f(true_offset_N, 3) << " N)\n";
  out << "   gain:   last year's record " << f(stale.coefficients[1], 4) << " N/V ("
      << f(100 * (stale.coefficients[1] / true_gain_N_per_V - 1), 2) << " %), now "
      << f(load_cell.gain_N_per_V, 4) << " ± " << f(load_cell.gain_std_N_per_V, 4) << " N/V ("
      << f(100 * (load_cell.gain_N_per_V / true_gain_N_per_V - 1), 3) << " %"
      << (load_cell.quadratic ? ": the slope at 0 N of the significant quadratic, which follows "
                                "the cell's bow of 4 × 5e-4 there"
                              : "")
      << ")\n";
  out << "   non-linearity " << f(load_cell.nonlinearity_percent_fs, 4) << " % FS, hysteresis "
      << f(load_cell.hysteresis_percent_fs, 4) << " % FS, "
      << (load_cell.quadratic ? "quadratic term significant" : "straight line") << "\n";
  return load_cell;
}

// 2. Inclinometer: reference angles on a (simulated) tilt table; the record added to the
// store and printed against the truth.
cal::InclinometerCalibration calibrate_demo_inclinometer(const CalibrationStore& store,
                                                         const RigDefinition& rig,
                                                         const RigChannel& inc, std::ostream& out) {
  const auto incp = cal::inclinometer_parameters(inc);
  std::vector<double> angles{-8, -4, 0, 4, 8};
  cal::SimulatedStaticSource inc_source(rig, inc, 12);
  // Initialised, not assigned field by field: GCC 12 takes the assignment of "°" to the
  // string for a read of uninitialised memory (-Wmaybe-uninitialized).
  const cal::GuidedOptions tilt{.max_std_V = 0.05 * incp.output_V_per_deg,
                                .max_drift_V = 0.02 * incp.output_V_per_deg,
                                .display_per_V = 1.0 / incp.output_V_per_deg,
                                .display_unit = "°"};
  std::istringstream enter2(std::string(angles.size(), '\n'));
  std::ostringstream dialogue2;
  const auto inc_points = cal::run_guided_points(inc_source, cal::inclinometer_angle_points(angles),
                                                 tilt, enter2, dialogue2);
  cal::InclinometerCalibrationOptions inc_options;
  inc_options.range_deg = incp.range_deg;
  const std::string nominal_inclinometer = sensors::nominal_calibration(inc).id;
  const cal::InclinometerCalibration inclinometer = cal::calibrate_inclinometer(
      inc_points, inc_options, header(store, "inclinometer", inc.serial, nominal_inclinometer));
  store.add(inclinometer.record);
  out << "\n2. Inclinometer " << inc.serial << ": guided, " << angles.size()
      << " reference angles (each point waits for a stable 1 s window: the 5 Hz filter settles)\n";
  out << "   offset: datasheet 0.000°, now " << f(inclinometer.offset_deg, 4) << " ± "
      << f(inclinometer.offset_std_deg, 4) << "° (truth " << f(incp.offset_deg, 4) << "°)\n";
  out << "   gain:   datasheet " << f(1 / incp.output_V_per_deg, 4) << " °/V, now "
      << f(inclinometer.gain_rad_per_V * kDegPerRad, 4) << " ± "
      << f(inclinometer.gain_std_rad_per_V * kDegPerRad, 4) << " °/V\n";
  return inclinometer;
}

// 3. A recording of 19 s on the simulated bench: three openings and closings.
void record_demo_recording(const RigDefinition& rig, const fs::path& session_path) {
  const DoorModel model = simulated_bench::simulated_door_model(rig);
  simulated_bench::SimulatedBench bench(rig, model, 19.0);
  SessionMetadata metadata;
  metadata.rig_name = rig.name;
  metadata.rig_definition = rig.text;
  metadata.operator_name = "calibration demo";
  RecordOptions record;
  record.duration_s = 19.0;
  record_session(bench, metadata, session_path, record);
}

struct FromRecording {
  cal::TimingCalibration timing;
  cal::GyroCalibration gyro;
};

// The inclinometer's delay, then the gyroscope, each from the recording, added to the
// store and applied to the session.
FromRecording calibrate_from_recording(const CalibrationStore& store, const fs::path& session_path,
                                       const RigChannel& inc, const RigChannel& gyr,
                                       const std::string& inclinometer_record_id) {
  FromRecording found;
  {
    const SessionReader session(session_path);
    found.timing =
        cal::calibrate_timing(session, inc.name, gyr.name, cal::TimingCalibrationOptions{},
                              header(store, "inclinometer", inc.serial, inclinometer_record_id));
  }
  store.add(found.timing.record);
  apply_calibration(session_path, inc.name, found.timing.record);
  {
    const SessionReader session(session_path);
    found.gyro = cal::calibrate_gyroscope(
        session, gyr.name, inc.name, cal::GyroCalibrationOptions{},
        header(store, "gyroscope", gyr.serial, session.channel(gyr.name).calibration_id));
  }
  store.add(found.gyro.record);
  apply_calibration(session_path, gyr.name, found.gyro.record);
  return found;
}

// What the recording gave against the truth, then the table of errors before and after.
void print_recording_results(const FromRecording& found, const RigDefinition& rig,
                             const RigChannel& inc, const RigChannel& gyr, const Errors& before,
                             const Errors& after, std::ostream& out) {
  const auto incp = cal::inclinometer_parameters(inc);
  const auto gyp = cal::gyroscope_parameters(gyr);
  const double pole = std::exp(-2 * std::numbers::pi * incp.bandwidth_hz / rig.sample_rate_hz);
  const double true_delay_s = pole / (1 - pole) / rig.sample_rate_hz;
  const cal::GyroCalibration& gyro = found.gyro;
  const cal::TimingCalibration& timing = found.timing;
  out << "\n3. From a recording (19 s, three openings and closings):\n";
  out << "   gyroscope " << gyr.serial << ": bias " << f(gyro.bias_dps, 4) << " ± "
      << f(gyro.bias_std_dps, 4) << " °/s from " << gyro.bias_periods
      << " still periods (truth starts at " << f(gyp.bias_dps, 4) << " °/s and wanders)\n";
  out << "     scale factor error " << f(100 * gyro.scale_factor_error, 2) << " ± "
      << f(100 * gyro.scale_factor_error_std, 2) << " % (truth "
      << f(100 * gyp.scale_factor_error, 2) << " %); " << gyro.saturated_samples
      << " saturated samples flagged\n";
  out << "   timing: the inclinometer lags " << f(1e3 * timing.alignment.delay_s, 2) << " ± "
      << f(1e3 * timing.alignment.delay_std_s, 2) << " ms (truth " << f(1e3 * true_delay_s, 2)
      << " ms; before: not corrected)\n";

  out << "\n   errors against the truth    before      after\n";
  auto line = [&](const char* what, double b, double a, const char* unit, int decimals) {
    char text[160];
    std::snprintf(text, sizeof text, "   %-26s %9s  %9s  %s\n", what, f(b, decimals).c_str(),
                  f(a, decimals).c_str(), unit);
    out << text;
  };
  line("force at rest (mean)", before.force_rest_mean_N, after.force_rest_mean_N, "N", 3);
  line("force in strokes (rms)", before.force_rms_N, after.force_rms_N, "N", 3);
  line("inclinometer, |θ| < 9° (rms)", before.angle_rms_deg, after.angle_rms_deg, "°", 4);
  line("rate at rest (mean)", before.rate_rest_mean_dps, after.rate_rest_mean_dps, "°/s", 4);
  line("rate moving (rms)", before.rate_rms_dps, after.rate_rms_dps, "°/s", 3);
  out << "   (after: the session's channels now use the new records; its raw samples are "
         "unchanged)\n";
}

}  // namespace

// The stages: the uncalibrated rig and its store, the load cell and the inclinometer
// guided, a recording, the timing and the gyroscope from it, and the errors against the
// truth before and after.
void run_calibration_demo(std::ostream& out) {
  const Scratch scratch;
  const CalibrationStore store(scratch.path / "calibrations");
  store.add(calibration_record_from_json(cal::uncalibrated_rig_load_cell_record_json(),
                                         "built-in load-cell record"));
  RigDefinition rig =
      parse_rig(cal::uncalibrated_rig_text(), "built-in rig simulated-uncalibrated", scratch.path);
  rig.calibration_store = store.directory();
  const RigChannel& lc = cal::find_rig_channel(rig, "load_cell", "");
  const RigChannel& inc = cal::find_rig_channel(rig, "inclinometer", "");
  const RigChannel& gyr = cal::find_rig_channel(rig, "gyroscope", "");

  out << "Calibration on the simulated bench " << rig.name
      << " (sensors off in known ways: rigs/simulated-uncalibrated.toml)\n";
  const cal::LoadCellCalibration load_cell = calibrate_demo_load_cell(store, rig, lc, out);
  const cal::InclinometerCalibration inclinometer =
      calibrate_demo_inclinometer(store, rig, inc, out);

  const fs::path session_path = scratch.path / "session.h5";
  record_demo_recording(rig, session_path);
  const Errors before = errors_of(session_path);
  apply_calibration(session_path, lc.name, load_cell.record);
  apply_calibration(session_path, inc.name, inclinometer.record);
  const FromRecording found =
      calibrate_from_recording(store, session_path, inc, gyr, inclinometer.record.id);
  const Errors after = errors_of(session_path);
  print_recording_results(found, rig, inc, gyr, before, after, out);
}

}  // namespace doorbench::app
