#pragma once
// What every calibration procedure shares: its error type and the facts about who
// calibrates what, which go into the record it makes.
#include <stdexcept>
#include <string>

#include "acquisition/rig/calibration_record.h"

namespace doorbench::calibration {

// A procedure that cannot give a trustworthy result (too few points, unstable readings,
// references out of range, no still period …). The message says what and what to do.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Who, when, which sensor and which version: copied into the record.
struct RecordHeader {
  std::string sensor_serial{};
  std::string operator_name{};
  std::string date_utc{};         // ISO 8601
  std::string valid_until_utc{};  // "" = no expiry
  int version = 1;
  std::string supersedes{};  // the record it replaces
  std::string notes{};
};

// Fills id (make_record_id), version, serial, operator, dates, supersedes and notes.
void apply_header(CalibrationRecord& record, const RecordHeader& header);

// The shortest text that reads back as the same double, and fixed-point text.
std::string shortest(double value);
std::string fixed(double value, int decimals);

}  // namespace doorbench::calibration
