#include "calibration/procedure.h"

#include <charconv>
#include <cstdio>

#include "acquisition/rig/calibration_store.h"

namespace doorbench::calibration {

void apply_header(CalibrationRecord& record, const RecordHeader& header) {
  record.sensor_serial = header.sensor_serial;
  record.version = header.version;
  record.id = make_record_id(record.sensor_kind, header.sensor_serial, header.version);
  record.operator_name = header.operator_name;
  record.date_utc = header.date_utc;
  record.valid_until_utc = header.valid_until_utc;
  record.supersedes = header.supersedes;
  if (!header.notes.empty()) {
    record.notes = record.notes.empty() ? header.notes : header.notes + " " + record.notes;
  }
}

std::string shortest(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return std::string(text, result.ptr);
}

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

}  // namespace doorbench::calibration
