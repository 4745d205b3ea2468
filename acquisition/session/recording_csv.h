#pragma once
// Door recordings as CSV text, door-models.md §5.1 (user documentation: docs/csv-format.md).
// Columns by name in any order: time_s (required, strictly increasing), force_N (required),
// angle_rad and/or rate_rad_s (at least one), stroke (optional; integer id of the opening
// or closing a row belongs to, 0 = between strokes), and extra channels whose names end in
// a unit suffix (`_V`, `_deg`, `tau_Nm`, ...). Every broken rule is a CsvError naming the
// source and line; nothing is guessed.
#include <cstddef>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/csv_table.h"

namespace doorbench {

struct Recording {
  // Where the recording was read from (a path, or the name given to the parser); used in
  // messages, never written. The producing program goes into metadata key `source`.
  std::string source;
  // Metadata lines in file order, notes with an empty key (see CsvTable::metadata), except
  // handle_radius_m and sample_rate_hz, which live in the typed fields below.
  CsvMetadata metadata;
  std::optional<double> handle_radius_m;  // metadata; positive when present (see below)
  std::optional<double> sample_rate_hz;   // metadata; positive when present
  std::vector<double> time_s, force_N;
  std::optional<std::vector<double>> angle_rad, rate_rad_s;  // at least one present
  std::optional<std::vector<int>> stroke;                    // values >= 0
  // Further channels in file order; every name ends in a unit suffix, e.g. tau_Nm.
  std::vector<std::string> extra_names;
  std::vector<std::vector<double>> extra_columns;
  // File line of each sample, 1-based; empty for a recording built in memory.
  std::vector<int> line_numbers;
  // Columns that hold a sensor's raw signal (import --scale, --calibration), by column name:
  // such a column's values are in its record's input_unit, and its physical values (in the
  // unit its name ends with) are record.apply(value). A session made of the recording keeps
  // the raw values and the record, as a recorded session does. Empty: every column is physical.
  std::map<std::string, CalibrationRecord> calibrations;

  std::size_t size() const { return time_s.size(); }
};

// Column names with a fixed meaning in a recording.
inline constexpr std::string_view kTimeColumn = "time_s";
inline constexpr std::string_view kForceColumn = "force_N";
inline constexpr std::string_view kAngleColumn = "angle_rad";
inline constexpr std::string_view kRateColumn = "rate_rad_s";
inline constexpr std::string_view kStrokeColumn = "stroke";
inline constexpr std::string_view kHandleRadiusKey = "handle_radius_m";
inline constexpr std::string_view kSampleRateKey = "sample_rate_hz";
// The recording's start, ISO 8601 UTC (export writes it; import takes it as the session's).
inline constexpr const char* kStartTimeKey = "start_time_utc";

// Where a door handle can be: kHandleRadiusMinM to kHandleRadiusMaxM from the hinge axis.
// A recording's, a geometry calibration's or a door file's radius outside is most likely a
// unit or typing error; the verbs refuse it unless told to use it anyway.
inline constexpr double kHandleRadiusMinM = 0.05;
inline constexpr double kHandleRadiusMaxM = 2.0;
// "" when `radius_m` is where a door handle can be; else "R m (from ORIGIN) is outside 0.05
// to 2 m, where a door handle is" (R as printf's %.6g; without "(from ORIGIN)" when `origin`
// is empty).
std::string handle_radius_problem(double radius_m, const std::string& origin = "");

// A door's angle spans less than a turn, turns at less than two turns a second, and is sampled
// faster than every half second: a recording beyond one of these most likely holds a unit read
// as another (degrees as radians, milliseconds as seconds).
inline constexpr double kAngleSpanMaxRad = 2.0 * std::numbers::pi;
inline constexpr double kRateMaxRadPerS = 4.0 * std::numbers::pi;
inline constexpr double kSampleIntervalMaxS = 0.5;
// The recording's units in doubt, one sentence each, in the physical values (a column a record
// converts through Recording::calibrations is judged after the record): "angle_rad spans 0 to
// 80 rad, more than a turn: an angle in degrees read as radians? (...)"; the same for
// |rate_rad_s| above kRateMaxRadPerS and a median step of time_s above kSampleIntervalMaxS.
// Empty when none is in doubt. Missing samples (NaN) are left out.
std::vector<std::string> unit_doubts(const Recording& recording);
// What a verb puts before each of unit_doubts in a warning: "warning: units in doubt: ...".
inline constexpr std::string_view kUnitDoubtWarning = "units in doubt: ";

// True when `name` ends in a unit suffix: an underscore with text on both sides ("tau_Nm").
bool has_unit_suffix(std::string_view name);
// The unit a column's name ends with: the compound units "_rad_s", "_deg_s", "_m_s" (as
// rad/s, deg/s, m/s) and "_N_m" (N*m) first, else the text after the last underscore.
std::string unit_of_column(const std::string& column);
// A unit as a column name's suffix: '/', '*', ' ' and '^' as '_' ("rad/s" gives "rad_s").
std::string unit_column_suffix(const std::string& unit);

// `source` names the text in messages (usually its path). With EmptyCells::kMissing an
// empty cell of force_N, angle_rad, rate_rad_s or an extra column is a missing sample
// (NaN: a lost scan, a gap); time_s and stroke are never missing ("column time_s: empty
// cell"). With kRefuse (for a force to replay) every empty cell is an error.
Recording parse_recording_csv(std::string_view text, std::string_view source,
                              EmptyCells empty_cells = EmptyCells::kRefuse);
Recording recording_from_table(const CsvTable& table, std::string_view source);
// Errors name the path; "PATH: cannot open for reading" when the file cannot be read.
Recording read_recording_csv(const std::filesystem::path& path,
                             EmptyCells empty_cells = EmptyCells::kRefuse);

// Writes typed metadata (handle_radius_m, sample_rate_hz), the other metadata, then the
// columns time_s, force_N, angle_rad, rate_rad_s, stroke (those present) and the extra
// columns. Numbers are written so that reading gives back identical doubles; a NaN (a
// missing sample) is an empty cell. Throws
// std::invalid_argument when the recording breaks a rule the reader enforces (sizes,
// order of time_s, stroke ids, names, non-finite values, empty recording, ...).
void write_recording_csv(std::ostream& out, const Recording& recording);
// Writes the file whole or not at all (acquisition/session/output_file.h: through a temporary file
// renamed into place); throws OutputError "PATH: cannot write: SYSTEM ERROR". It does not
// check whether `path` exists: callers apply the output rule (check_output_file) first.
void write_recording_csv_file(const std::filesystem::path& path, const Recording& recording);

}  // namespace doorbench
