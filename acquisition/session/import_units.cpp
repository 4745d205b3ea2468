#include "acquisition/session/import_units.h"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "acquisition/session/map_syntax.h"
#include "acquisition/session/recording_csv.h"
#include "core/time_text.h"
#include "core/units.h"

namespace doorbench {

namespace {

// "TARGET=VALUE" split at its first '='; throws naming the option and the form.
std::pair<std::string, std::string> split_item(const std::string& item, const std::string& option,
                                               const std::string& form) {
  const std::size_t equals = item.find('=');
  if (equals == std::string::npos || equals == 0 || equals + 1 == item.size()) {
    throw std::invalid_argument(option + " item '" + item + "' is not " + form);
  }
  std::string target = item.substr(0, equals);
  if (target != "force" && target != "angle" && target != "rate" && !has_unit_suffix(target)) {
    throw std::invalid_argument(option + " target '" + target +
                                "' is not force, angle, rate or a column name with a unit suffix "
                                "(e.g. inclinometer_angle_rad)");
  }
  return {std::move(target), item.substr(equals + 1)};
}

ImportConversion parse_scale(const std::string& item) {
  const std::string form = "TARGET=GAIN[,OFFSET] (e.g. force=98.1,-0.5)";
  auto [target, value] = split_item(item, "--scale", form);
  const std::size_t comma = value.find(',');
  const std::optional<double> gain = parse_csv_number(value.substr(0, comma));
  const std::optional<double> offset = comma == std::string::npos
                                           ? std::optional<double>(0.0)
                                           : parse_csv_number(value.substr(comma + 1));
  if (!gain || !offset) throw std::invalid_argument("--scale item '" + item + "' is not " + form);
  if (*gain == 0.0) {
    throw std::invalid_argument(
        "--scale item '" + item + "': a gain of 0 makes every value " +
        value.substr(comma == std::string::npos ? value.size() : comma + 1));
  }
  ImportConversion conversion;
  conversion.target = std::move(target);
  conversion.given = "--scale " + item;
  conversion.gain = *gain;
  conversion.offset = *offset;
  return conversion;
}

// A record named by --calibration: a file when one is there, else an id in the store.
CalibrationRecord named_record(const std::string& name, const std::string& given,
                               const CalibrationStore& store) {
  std::error_code error;
  if (std::filesystem::is_regular_file(name, error)) {
    std::ifstream in(name, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) throw std::runtime_error(given + ": " + name + ": cannot read the record's file");
    return calibration_record_from_json(text.str(), name);
  }
  if (std::optional<CalibrationRecord> record = store.find(name)) return *record;
  std::string known;
  for (const CalibrationRecord& record : store.records()) {
    known += (known.empty() ? "" : ", ") + record.id;
  }
  throw std::invalid_argument(given + ": no file " + name + " and no record " + name +
                              " in the calibration store " + store.directory().string() + " (" +
                              (known.empty() ? "it has none" : "its records: " + known) + ")");
}

ImportConversion parse_calibration(const std::string& item, const CalibrationStore& store) {
  auto [target, name] =
      split_item(item, "--calibration", "TARGET=RECORD (a record's id in the store, or its file)");
  ImportConversion conversion;
  conversion.target = std::move(target);
  conversion.given = "--calibration " + item;
  conversion.record = named_record(name, conversion.given, store);
  const std::string unit = import_target_unit(conversion.target);
  if (const std::string problem = conversion.record->unit_problem("", unit); !problem.empty()) {
    throw std::invalid_argument(conversion.given + ": " + problem + " (" + conversion.target +
                                " is in " + unit + ")");
  }
  return conversion;
}

// The stem of a target's column, to which a raw column adds its own unit: "force" for
// force_N, "inclinometer_angle" for inclinometer_angle_rad.
std::string raw_column_stem(const std::string& target) {
  const std::string column = import_target_column(target);
  const std::string suffix = unit_column_suffix(import_target_unit(target));
  return column.substr(0, column.size() - suffix.size() - 1);
}

// The name apply_csv_map gives a mapped column: the target's column, or for a converted target
// its raw column (STEM_UNIT). Throws std::invalid_argument "is in 'U', not T" (with what to do)
// when the unit the column's name states is not the one the target or its record takes.
std::string mapped_column_name(const CsvMapItem& item, const std::string& stated,
                               const ImportConversion* conversion) {
  if (conversion == nullptr) {
    const bool time = item.target == "time";
    const std::string unit = time ? "s" : import_target_unit(item.target);
    if (!stated.empty() && stated != unit && !(time && stated_unit_factor(stated, unit))) {
      throw std::invalid_argument(
          "is in '" + stated + "', not " + unit +
          (time ? " (the time is read in s, ms or us: convert the column)"
                : " (convert it: --calibration " + item.target + "=RECORD or --scale " +
                      item.target +
                      "=GAIN[,OFFSET]; or map it as an extra column whose name ends "
                      "in its unit)"));
    }
    return time ? std::string(kTimeColumn) : import_target_column(item.target);
  }
  std::string unit = stated;
  if (conversion->record) {
    conversion->record_for(stated);  // throws when the record takes another unit
    unit = conversion->record->input_unit;
  }
  return raw_column_stem(item.target) + "_" + unit_column_suffix(unit.empty() ? "unstated" : unit);
}

}  // namespace

std::string csv_column_list(const CsvTable& table) {
  std::string list;
  for (const std::string& name : table.column_names) list += (list.empty() ? "" : ", ") + name;
  return list;
}

std::vector<CsvMapItem> parse_csv_map(const std::string& text) {
  std::vector<CsvMapItem> map;
  std::vector<std::string> targets;
  for (const MapItemText& given : split_map_items(text)) {
    if (given.target.empty() || given.text.empty()) {
      throw std::invalid_argument("--map item '" + given.item +
                                  "' is not TARGET=COLUMN (e.g. force=Force (N))");
    }
    check_map_target(given.target, targets);
    targets.push_back(given.target);
    map.push_back({given.target, unescaped(given.text), "--map " + given.item});
  }
  return map;
}

std::optional<double> stated_unit_factor(const std::string& stated, const std::string& unit) {
  struct Factor {
    const char* from;
    const char* to;
    double factor;
  };
  static constexpr Factor kFactors[] = {
      {"ms", "s", 1e-3},
      {"us", "s", 1e-6},
      {"deg", "rad", kRadPerDeg},
      {"deg/s", "rad/s", kRadPerDeg},
      {"rpm", "rad/s", 2.0 * std::numbers::pi / 60.0},
      {"kN", "N", 1e3},
  };
  for (const Factor& entry : kFactors) {
    if (stated == entry.from && unit == entry.to) return entry.factor;
  }
  return std::nullopt;
}

std::string unit_symbol(const std::string& spelling) {
  static constexpr std::pair<const char*, const char*> kSymbols[] = {
      {"Newtons", "N"},       {"Degrees", "deg"}, {"Radians", "rad"}, {"Degrees/s", "deg/s"},
      {"Radians/s", "rad/s"}, {"RPM", "rpm"},     {"Seconds", "s"},
  };
  for (const auto& [name, symbol] : kSymbols) {
    if (spelling == name) return symbol;
  }
  return spelling;
}

std::optional<ImportConversion> stated_unit_conversion(const std::string& target,
                                                       const std::string& stated,
                                                       const std::string& given) {
  if (target != "force" && target != "angle" && target != "rate") return std::nullopt;
  const std::optional<double> factor = stated_unit_factor(stated, import_target_unit(target));
  if (!factor) return std::nullopt;
  ImportConversion conversion;
  conversion.target = target;
  conversion.given = given;
  conversion.gain = *factor;
  conversion.from_stated_unit = true;
  return conversion;
}

std::vector<ImportConversion> with_stated_unit_conversions(
    const std::vector<ImportConversion>& conversions, const std::vector<CsvMapItem>& map) {
  std::vector<ImportConversion> all = conversions;
  for (const CsvMapItem& item : map) {
    if (find_conversion(conversions, item.target) != nullptr) continue;
    if (auto conversion = stated_unit_conversion(item.target, unit_stated_in_name(item.column),
                                                 item.given + ", the unit its name states")) {
      all.push_back(std::move(*conversion));
    }
  }
  return all;
}

std::string unit_stated_in_name(const std::string& column) {
  if (column.empty()) return "";
  const char close = column.back();
  const char open = close == ')' ? '(' : close == ']' ? '[' : '\0';
  const std::size_t at = open == '\0' ? std::string::npos : column.rfind(open);
  if (at == std::string::npos) return "";
  std::string unit = column.substr(at + 1, column.size() - at - 2);
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  while (!unit.empty() && blank(unit.back())) unit.pop_back();
  while (!unit.empty() && blank(unit.front())) unit.erase(0, 1);
  return unit;
}

void apply_csv_map(CsvTable& table, const std::vector<CsvMapItem>& map,
                   const std::vector<ImportConversion>& conversions, std::string_view source) {
  const auto error = [&](const CsvMapItem& item, const std::string& what) {
    return CsvError(source, table.header_line,
                    item.given + ": " + what + "; the file's columns: " + csv_column_list(table));
  };
  std::vector<std::size_t> mapped_at;  // the column of each item
  std::vector<std::string> names;      // the name each takes
  for (const CsvMapItem& item : map) {
    const std::optional<std::size_t> at = table.find_column(item.column);
    if (!at) throw error(item, "no column '" + item.column + "'");
    for (std::size_t k = 0; k < mapped_at.size(); ++k) {
      if (mapped_at[k] == *at) {
        throw error(item, "column '" + item.column + "' is mapped to " + map[k].target +
                              " already (one column, one target)");
      }
    }
    try {
      names.push_back(mapped_column_name(item, unit_stated_in_name(item.column),
                                         find_conversion(conversions, item.target)));
    } catch (const std::invalid_argument& problem) {
      throw error(item, "column '" + item.column + "' " + problem.what());
    }
    mapped_at.push_back(*at);
  }
  std::vector<std::vector<double>> columns;
  for (std::size_t k = 0; k < map.size(); ++k) {
    columns.push_back(std::move(table.columns[mapped_at[k]]));
    if (map[k].target == "time") {
      const double factor = stated_unit_factor(unit_stated_in_name(map[k].column), "s").value_or(1);
      for (double& value : columns.back()) value *= factor;
    }
    table.metadata.emplace_back("map_" + map[k].target + "_column", map[k].column);
    table.metadata_line_numbers.push_back(0);  // not a line of the file
  }
  table.column_names = std::move(names);
  table.columns = std::move(columns);
}

namespace {

// recording_from_table_with_columns with the columns to name given: import's are the file's
// own names, from before --map renamed them.
Recording recording_from_table_naming(const CsvTable& table, std::string_view source,
                                      const std::string& columns, std::string_view hint) {
  try {
    return recording_from_table(table, source);
  } catch (const CsvError& error) {
    if (error.line() != table.header_line) throw;
    throw CsvError(source, error.line(),
                   error.detail() + "; the file's columns: " + columns + " " + std::string(hint));
  }
}

}  // namespace

Recording recording_from_table_with_columns(const CsvTable& table, std::string_view source,
                                            std::string_view hint) {
  return recording_from_table_naming(table, source, csv_column_list(table), hint);
}

namespace {

// The dialect with the --map time column as its date-time column. A map that does not parse is
// reported later, with the file's columns.
CsvDialect with_date_time_column(const CsvDialect& dialect, const std::string& map_text) {
  CsvDialect out = dialect;
  try {
    for (const CsvMapItem& item : parse_csv_map(map_text)) {
      if (item.target == "time") out.date_time_column = item.column;
    }
  } catch (const std::invalid_argument&) {
  }
  return out;
}

// The first date and time of the table's time column, kept in its metadata to the microsecond:
// in UTC ("2024-05-02T09:30:00.125000Z"), also as the start when the file states none; without a
// zone, the clock's own reading without the Z; a time of the day alone as "09:30:00.125000".
void keep_first_date_time(CsvTable& table) {
  const DateTimeText& first = *table.first_date_time;
  std::int64_t seconds = first.seconds;
  auto microseconds = static_cast<std::int64_t>(std::llround(first.fraction_s * 1e6));
  if (microseconds == 1000000) {
    ++seconds;
    microseconds = 0;
  }
  std::string text = iso8601_utc_text(seconds, microseconds, 6);
  if (first.zone_known && !table.metadata_value(kStartTimeKey)) {
    table.metadata.emplace_back(kStartTimeKey, text);
    table.metadata_line_numbers.push_back(0);  // not a line of the file
  }
  if (!first.zone_known) text.pop_back();                    // the Z
  if (!first.date_known) text.erase(0, text.find('T') + 1);  // 1970-01-01T of the clock alone
  table.metadata.emplace_back(kFirstDateTimeKey, text);
  table.metadata_line_numbers.push_back(0);
}

}  // namespace

std::optional<ImportedDateTimes> imported_date_times(const Recording& recording) {
  std::optional<ImportedDateTimes> out;
  bool start_stated = false;
  for (const auto& [key, value] : recording.metadata) {
    if (key == kFirstDateTimeKey && !value.empty()) {
      out = ImportedDateTimes{value, value.ends_with('Z'), value.find('-') != std::string::npos,
                              false};
    }
    if (key == kStartTimeKey && !value.empty()) start_stated = true;
  }
  if (out) out->start_stated = start_stated;
  return out;
}

Recording read_csv_import(const std::filesystem::path& path, const std::string& map_text,
                          const std::vector<ImportConversion>& conversions,
                          const CsvDialect& dialect) {
  CsvTable table =
      read_csv_file(path, EmptyCells::kMissing, with_date_time_column(dialect, map_text));
  if (table.first_date_time) keep_first_date_time(table);
  const std::string source = path.string();
  const std::string columns = csv_column_list(table);
  std::vector<CsvMapItem> map;
  try {
    map = parse_csv_map(map_text);
  } catch (const std::invalid_argument& error) {
    if (!map_text.empty()) {
      throw CsvMapSyntaxError(std::string(error.what()) + "; the file's columns: " + columns);
    }
  }
  const std::vector<ImportConversion> all = with_stated_unit_conversions(conversions, map);
  if (!map.empty()) apply_csv_map(table, map, all, source);
  std::map<std::string, CalibrationRecord> records = take_raw_columns(table, all, source);
  Recording recording = recording_from_table_naming(table, source, columns, kCsvMapHint);
  recording.calibrations = std::move(records);
  return recording;
}

CalibrationRecord ImportConversion::record_for(const std::string& input_unit) const {
  if (record) {
    if (!input_unit.empty() && record->input_unit != input_unit) {
      throw std::invalid_argument("is in '" + input_unit + "', but record " + record->id +
                                  " takes " + record->input_unit + " (" + given + ")");
    }
    return *record;
  }
  return linear_record((from_stated_unit ? "unit-" : "scale-") + target,
                       input_unit.empty() ? "unstated" : input_unit, import_target_unit(target),
                       gain, offset, "doorbench import " + given);
}

std::string import_target_unit(const std::string& target) {
  if (target == "force") return "N";
  if (target == "angle") return "rad";
  if (target == "rate") return "rad/s";
  return unit_of_column(target);
}

std::string import_target_column(const std::string& target) {
  if (target == "force") return std::string(kForceColumn);
  if (target == "angle") return std::string(kAngleColumn);
  if (target == "rate") return std::string(kRateColumn);
  return target;
}

std::vector<ImportConversion> parse_import_conversions(const std::vector<std::string>& scales,
                                                       const std::vector<std::string>& calibrations,
                                                       const CalibrationStore& store) {
  std::vector<ImportConversion> conversions;
  for (const std::string& item : scales) conversions.push_back(parse_scale(item));
  for (const std::string& item : calibrations) {
    conversions.push_back(parse_calibration(item, store));
  }
  for (std::size_t i = 0; i < conversions.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (conversions[j].target == conversions[i].target) {
        throw std::invalid_argument(conversions[i].given + ": " + conversions[i].target +
                                    " is converted already (" + conversions[j].given + ")");
      }
    }
  }
  return conversions;
}

const ImportConversion* find_conversion(const std::vector<ImportConversion>& conversions,
                                        const std::string& target) {
  for (const ImportConversion& conversion : conversions) {
    if (conversion.target == target) return &conversion;
  }
  return nullptr;
}

std::map<std::string, CalibrationRecord> take_raw_columns(
    CsvTable& table, const std::vector<ImportConversion>& conversions, std::string_view source) {
  std::map<std::string, CalibrationRecord> records;
  for (const ImportConversion& conversion : conversions) {
    const std::string column = import_target_column(conversion.target);
    const std::string stem = raw_column_stem(conversion.target);
    std::vector<std::size_t> raw;  // the columns that can hold the target's raw signal
    for (std::size_t c = 0; c < table.column_names.size(); ++c) {
      const std::string& name = table.column_names[c];
      const std::string unit =
          conversion.record ? conversion.record->input_unit : unit_of_column(name);
      if (has_unit_suffix(name) && name == stem + "_" + unit_column_suffix(unit)) raw.push_back(c);
    }
    if (raw.empty()) {
      const std::string wanted =
          conversion.record ? stem + "_" + unit_column_suffix(conversion.record->input_unit)
                            : stem + "_UNIT";
      throw CsvError(source, table.header_line,
                     conversion.given + ": no column " + wanted + " (the raw " + conversion.target +
                         "); the columns: " + csv_column_list(table));
    }
    if (raw.size() > 1) {
      throw CsvError(source, table.header_line,
                     conversion.given + ": columns " + table.column_names[raw[0]] + " and " +
                         table.column_names[raw[1]] + " could both be the raw " +
                         conversion.target + " (keep one); the columns: " + csv_column_list(table));
    }
    const std::string raw_name = table.column_names[raw.front()];
    if (raw_name != column && table.find_column(column)) {
      throw CsvError(source, table.header_line,
                     conversion.given + ": the raw column " + raw_name + " would become " + column +
                         ", which the file has already");
    }
    records.emplace(column, conversion.record_for(unit_of_column(raw_name)));
    table.column_names[raw.front()] = column;
  }
  return records;
}

}  // namespace doorbench
