#pragma once
// A calibration record: how one sensor's signal (volts at the DAQ, or whatever its raw
// unit is) maps to a physical value, with who, when, how and how well. Sessions carry
// every record they use, in full; raw samples never change, physical values are computed
// on read from raw and the record.
//
// A record is versioned: a newer calibration of the same sensor is a new record with a
// new id and a higher version (`supersedes` names the one it replaces); records are never
// edited once stored. Besides the polynomial it keeps the procedure's evidence: the
// reference points with their residuals, named results with their uncertainties, the
// channel's delay (corrected on read) and the range in which it holds.
//
// This library holds only the record and the store (no dependency on sessions) so that
// acquisition can store records; the procedures, which read sessions, are in
// doorbench_calibration.
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace doorbench {

// One reference point of a multi-point calibration.
struct CalibrationPoint {
  double reference = 0.0;   // the reference value, in the record's `unit`
  double signal = 0.0;      // the mean reading, in `input_unit`
  double signal_std = 0.0;  // the readings' standard deviation over the window
  int samples = 0;          // readings averaged
  double residual = 0.0;    // calibrated(signal) − reference, in `unit`
  std::string branch;       // "loading" | "unloading" | "" (no direction)
};

// A named result of the procedure (gain, offset, bias, drift, delay, non-linearity …).
struct CalibrationQuantity {
  std::string name;  // with its unit in the name where it has one: "gain_N_per_V"
  double value = 0.0;
  double standard_uncertainty = 0.0;  // 0 when not estimated
  std::string unit;
};

struct CalibrationRecord {
  std::string id;           // unique, e.g. "load_cell-LC445-0193-v2"
  int version = 1;          // a newer calibration of the same sensor gets a new id
  std::string sensor_kind;  // load_cell | inclinometer | gyroscope | geometry | ...
  std::string sensor_serial;
  std::string input_unit = "V";  // what the polynomial takes
  std::string unit;              // what it gives: N, rad, rad/s
  // physical = Σ coefficients[k] · input^k (at least offset and gain).
  std::vector<double> coefficients;
  double standard_uncertainty = 0.0;  // in `unit`
  std::string method;                 // "nominal (datasheet)", "multi-point", ...
  std::string date_utc;               // ISO 8601
  std::string operator_name;
  std::string valid_until_utc;  // empty: no expiry; else ISO 8601 (validate() checks it)
  std::string notes;

  // --- added with the calibration procedures (all optional in JSON) ---
  std::string supersedes{};  // id of the record this one replaces ("" for a first one)
  std::string references{};  // what the references were: masses and their class, tilt table …
  std::vector<CalibrationPoint> points{};
  std::vector<CalibrationQuantity> quantities{};
  // The channel's samples describe the physical quantity delay_s earlier than their time
  // stamps (a low-pass sensor lags); readers shift them back by this much.
  double delay_s = 0.0;
  double delay_standard_uncertainty_s = 0.0;
  // The physical range (in `unit`) in which the calibration holds; ±inf: not stated.
  double valid_min = -std::numeric_limits<double>::infinity();
  double valid_max = std::numeric_limits<double>::infinity();

  double apply(double input) const;
  // The quantity of that name, or nullptr.
  const CalibrationQuantity* quantity(std::string_view name) const;
  // "" when the record takes `input` (its input_unit; an empty `input` is not checked) and
  // gives `output` (its unit); else why not: "record ID gives rad, not N".
  std::string unit_problem(std::string_view input, std::string_view output) const;

  // Empty when usable, else a one-line message naming the field: "calibration record ID:
  // valid_until_utc: TEXT is not an ISO 8601 date (...)" for an expiry that is neither ""
  // nor an ISO 8601 date or UTC time on the calendar.
  std::string validate() const;
};

// The expiry of a record being made at `now_utc` (ISO 8601): "" when `valid_until` is an
// ISO 8601 date (YYYY-MM-DD) or UTC time (YYYY-MM-DDTHH:MM[:SS[.fraction]]Z) on the
// calendar and not before now_utc's day; else why not ("TEXT is before today (DAY): the
// record would have expired when made").
std::string new_valid_until_problem(const std::string& valid_until, const std::string& now_utc);

// A linear record given by hand, physical = offset + gain · input (import --scale): method
// `method`, dated now, sensor_kind "scale". Throws std::invalid_argument for a gain or offset
// that is not finite, or a gain of 0.
CalibrationRecord linear_record(std::string id, std::string input_unit, std::string unit,
                                double gain, double offset, std::string method);

// JSON text of a record and back; parsing errors name `source` and the field, and a record
// that validate() refuses is refused with `source` before its message.
std::string to_json(const CalibrationRecord& record);
CalibrationRecord calibration_record_from_json(std::string_view json_text, std::string_view source);

}  // namespace doorbench
