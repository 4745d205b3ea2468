#pragma once
// Raw channels to physical units on import (doorbench import --scale, --calibration;
// docs/tdms.md and docs/csv-format.md): a target (force, angle, rate, or an extra column with
// a unit suffix) whose channel holds a sensor's raw signal, volts from a bridge or an
// inclinometer, becomes a session channel that keeps the raw values and names the record
// that makes them physical, as a recorded session does (Recording::calibrations).
//
// Thread safety: free functions without shared state.
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/rig/calibration_store.h"
#include "acquisition/session/csv_table.h"
#include "acquisition/session/recording_csv.h"

namespace doorbench {

// One --scale TARGET=GAIN[,OFFSET] or --calibration TARGET=RECORD, its record read.
struct ImportConversion {
  std::string target;  // force, angle, rate, or an extra column name (incl_V)
  std::string given;   // the item as given, for messages
  // --calibration: the record (from the store, or its file). --scale: none, and
  // physical = offset + gain · raw.
  std::optional<CalibrationRecord> record;
  double gain = 1.0, offset = 0.0;
  // A conversion read off the unit a --map column's name states (stated_unit_factor), not
  // given: its record is "unit-TARGET" instead of "scale-TARGET".
  bool from_stated_unit = false;

  // The record for a channel whose raw values are in `input_unit` ("" when the channel states
  // none): --calibration's record, which must take that unit; --scale's linear record (id
  // "scale-TARGET", sensor_kind "scale", input unit the channel's or "unstated"). Throws
  // std::invalid_argument "TARGET: ..." naming the mismatch.
  CalibrationRecord record_for(const std::string& input_unit) const;
};

// The physical unit of a target: N, rad, rad/s, or the unit an extra column's name ends
// with ("V" for pot_V, "rad/s" for gyro_rad_s).
std::string import_target_unit(const std::string& target);
// The recording's column of a target: force_N, angle_rad, rate_rad_s, or the target itself.
std::string import_target_column(const std::string& target);

// The --scale and --calibration items ("force=2.5", "force=2.5,-0.1"; "force=ID", an id in
// `store`, or "force=FILE", a record's JSON file). Throws std::invalid_argument naming the
// item: malformed, a target that is not force, angle, rate or a name with a unit suffix, a
// target converted twice, a record that does not give the target's unit, no such record;
// std::runtime_error for a record file that cannot be read or parsed.
std::vector<ImportConversion> parse_import_conversions(const std::vector<std::string>& scales,
                                                       const std::vector<std::string>& calibrations,
                                                       const CalibrationStore& store);

// The conversion of `target`, or null.
const ImportConversion* find_conversion(const std::vector<ImportConversion>& conversions,
                                        const std::string& target);

// A CSV's raw columns: for each conversion, the column holding the target's raw signal is
// renamed in `table` to the target's column (force_V becomes force_N), so that the recording
// reads it there; returns the records by that column, for Recording::calibrations. The raw
// column is the target's column name with the unit the record takes (force_V for a record
// from V, inclinometer_angle_V for the target inclinometer_angle_rad); for a --scale, the one
// column of the target's stem with any unit suffix (force_V, or force_N itself). Throws
// CsvError at the header's line when there is none, or for a --scale more than one.
std::map<std::string, CalibrationRecord> take_raw_columns(
    CsvTable& table, const std::vector<ImportConversion>& conversions, std::string_view source);

// One item of `doorbench import --map` for a CSV file: TARGET=COLUMN (the syntax of
// acquisition/session/map_syntax.h; '/' needs no escape in a column's name).
struct CsvMapItem {
  std::string target;  // force, angle, rate, time, or an extra column name with a unit suffix
  std::string column;  // the header's name, unescaped
  std::string given;   // "--map TARGET=COLUMN", for messages
};
// "time=Time (s),force=Force (V)"; throws std::invalid_argument naming the item: not
// TARGET=COLUMN, a target that is not force, angle, rate, time or a name with a unit suffix, a
// target named twice.
std::vector<CsvMapItem> parse_csv_map(const std::string& text);

// The unit a CSV column's name states at its end in parentheses or brackets: "V" for
// "Force (V)", "deg/s" for "Rate [deg/s]"; "" when it states none.
std::string unit_stated_in_name(const std::string& column);

// The exact factor from a stated unit to a target's unit, for the units loggers write in
// place of the session's: ms and us to s, deg to rad, deg/s and rpm to rad/s, kN to N; none
// for any other pair (volts, counts, an unknown spelling: those need --scale or --calibration).
std::optional<double> stated_unit_factor(const std::string& stated, const std::string& unit);

// The symbol of a unit NI-DAQmx spells out in a TDMS channel's unit_string, by the names its
// unit constants carry (Newtons, Degrees, Radians, Degrees/s, Radians/s, RPM, Seconds): N, deg,
// rad, deg/s, rad/s, rpm, s. Any other text is returned as it is ("Volts" too: a calibration
// record names its input unit as the file does).
std::string unit_symbol(const std::string& spelling);

// The conversion a target's raw values stated in `stated` imply when no --scale or --calibration
// gives one: for force, angle or rate, a unit stated_unit_factor converts to the target's
// ("deg" for angle): physical = factor · raw, the session keeping the raw values in it (record
// unit-TARGET), `given` naming where the unit was stated, for messages. None for another target
// or unit.
std::optional<ImportConversion> stated_unit_conversion(const std::string& target,
                                                       const std::string& stated,
                                                       const std::string& given);

// `conversions` and, for each force, angle or rate the map names without one, a column whose
// name states a unit stated_unit_factor converts ("Angle (deg)"): its stated_unit_conversion.
std::vector<ImportConversion> with_stated_unit_conversions(
    const std::vector<ImportConversion>& conversions, const std::vector<CsvMapItem>& map);

// A file from elsewhere, its own columns named by the map: each mapped column of `table` is
// renamed to what the exchange format reads (time_s, force_N, angle_rad, rate_rad_s, the extra
// target itself) and the columns not mapped are left out, as a TDMS import takes only the
// channels mapped. The unit a mapped column's name states (unit_stated_in_name) must be its
// target's (s, N, rad, rad/s, the extra target's suffix): a column in degrees taken as the
// angle would be 57 times too large. A target converted by `conversions` (--scale,
// --calibration) takes its column as the raw signal: the column becomes STEM_UNIT (force_V)
// for take_raw_columns, UNIT the one its name states, else the record's input unit, else
// "unstated"; a record must take the unit the name states. Each mapped column's own name goes
// into the metadata as map_TARGET_column. A time column in ms or us is converted to seconds
// (stated_unit_factor). Throws CsvError at the header's line naming the item
// and ending with the file's columns: no such column, one column mapped to two targets, a
// unit that is not the target's or the record's.
void apply_csv_map(CsvTable& table, const std::vector<CsvMapItem>& map,
                   const std::vector<ImportConversion>& conversions, std::string_view source);

// A --map that is not TARGET=COLUMN,... (a usage error), its message ending with the file's
// columns.
class CsvMapSyntaxError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// The metadata key of the first row's date and time, when the --map time column holds dates and
// times or times of the day (CsvDialect::date_time_column), to the microsecond in one of three
// forms: "2024-05-02T08:30:00.125000Z" (UTC, the column stated a zone),
// "2024-05-02T09:30:00.125000" (the logger's clock, no zone), "09:30:00.125000" (no date).
inline constexpr const char* kFirstDateTimeKey = "map_time_first_date_time";

// What a --map time column of dates and times told about the recording's clock.
struct ImportedDateTimes {
  // The first row's date and time: in UTC with a Z when the column states a zone, else the
  // logger's own clock reading without one ("2024-05-02T09:30:00.125000"); the time of the day
  // alone ("09:30:00.125000") when the column states no date.
  std::string first;
  bool zone_stated = false;
  bool date_stated = true;
  // The recording states its start: its file's own metadata does, or the column's zone did.
  bool start_stated = false;

  // Without a stated start the session's start would be the import's time, unless the user
  // gives one (--start-time): true when that is what happens.
  bool start_unknown(bool start_time_given) const { return !start_stated && !start_time_given; }
};

// The recording's ImportedDateTimes (kFirstDateTimeKey, kStartTimeKey), as read_csv_import kept
// them; none when its time column held numbers.
std::optional<ImportedDateTimes> imported_date_times(const Recording& recording);

// A CSV file as `doorbench import` reads it: in `dialect`, empty cells as lost samples, its own
// columns named by `map_text` (parse_csv_map, apply_csv_map; empty: the exchange format's names),
// raw columns through `conversions` (take_raw_columns). Throws CsvMapSyntaxError for a malformed
// map, CsvError and std::invalid_argument as those functions do; a column the
// recording lacks or cannot take ("header lacks required column time_s") is reported at the
// header's line with the file's own columns and how --map names them. A --map time column of
// dates and times is read as seconds since its first row's (CsvDialect::date_time_column), which
// goes into the metadata (kFirstDateTimeKey) and, when it states a zone and the file states no
// start, as the start (kStartTimeKey).
Recording read_csv_import(const std::filesystem::path& path, const std::string& map_text,
                          const std::vector<ImportConversion>& conversions,
                          const CsvDialect& dialect = {});

// The columns of a table, for messages: "time_s, force_V, angle_rad".
std::string csv_column_list(const CsvTable& table);

// recording_from_table, except that a column the recording lacks or cannot take at the header's
// line is rethrown as a CsvError that adds the file's own columns and then `hint` ("header lacks
// required column time_s; the file's columns: Time (s), Load (N) HINT"): a file with its own
// column names is what the reader most likely has.
Recording recording_from_table_with_columns(const CsvTable& table, std::string_view source,
                                            std::string_view hint);

// The hints for a file whose columns are not the exchange format's: `doorbench import`'s
// (--map names them), and that of a command that reads only the exchange format (import first).
inline constexpr std::string_view kCsvMapHint =
    "(--map time=COLUMN,force=COLUMN,angle=COLUMN names a file's own columns: "
    "docs/csv-format.md)";
inline constexpr std::string_view kCsvImportFirstHint =
    "(a file with its own column names is read through doorbench import FILE --map "
    "time=COLUMN,force=COLUMN,angle=COLUMN --out SESSION.h5 first: docs/csv-format.md)";

}  // namespace doorbench
