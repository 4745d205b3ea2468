#pragma once
// A calibration record: how one sensor's signal (volts at the DAQ, or whatever its raw
// unit is) maps to a physical value, with who, when, how and how well. Sessions carry
// every record they use, in full; raw samples never change, physical values are computed
// on read from raw and the record.
//
// This library holds only the record (no dependency on sessions) so that acquisition can
// store records; calibration procedures, which read sessions, come in their own library.
#include <string>
#include <string_view>
#include <vector>

namespace doorbench::calibration {

struct CalibrationRecord {
  std::string id;           // unique, e.g. "loadcell-LC445-0193-2026-11-21"
  int version = 1;          // a newer calibration of the same sensor gets a new id
  std::string sensor_kind;  // load_cell | inclinometer | gyroscope | ...
  std::string sensor_serial;
  std::string input_unit = "V";  // what the polynomial takes
  std::string unit;              // what it gives: N, rad, rad/s
  // physical = Σ coefficients[k] · input^k (at least offset and gain).
  std::vector<double> coefficients;
  double standard_uncertainty = 0.0;  // in `unit`
  std::string method;                 // "nominal (datasheet)", "multi-point", ...
  std::string date_utc;               // ISO 8601
  std::string operator_name;
  std::string valid_until_utc;  // empty: no expiry
  std::string notes;

  double apply(double input) const;

  // Empty when usable, else a one-line message naming the field.
  std::string validate() const;
};

// JSON text of a record and back; parsing errors name `source` and the field.
std::string to_json(const CalibrationRecord& record);
CalibrationRecord calibration_record_from_json(std::string_view json_text, std::string_view source);

}  // namespace doorbench::calibration
