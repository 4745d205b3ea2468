#include "acquisition/session/recording_csv.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "acquisition/session/output_file.h"
#include "core/number_format.h"
#include "core/percentile.h"
#include "core/units.h"

namespace doorbench {
namespace {

constexpr std::array<std::string_view, 5> kKnownColumns = {kTimeColumn, kForceColumn, kAngleColumn,
                                                           kRateColumn, kStrokeColumn};

bool is_known_column(std::string_view name) {
  for (const auto known : kKnownColumns) {
    if (name == known) return true;
  }
  return false;
}

bool is_typed_metadata_key(std::string_view key) {
  return key == kHandleRadiusKey || key == kSampleRateKey;
}

// The stroke id in `value`, or nullopt when it is not an integer in [0, INT_MAX].
std::optional<int> stroke_id(double value) {
  if (!(value >= 0.0) || value > std::numeric_limits<int>::max() || std::floor(value) != value) {
    return std::nullopt;
  }
  return static_cast<int>(value);
}

std::string unit_suffix_example(std::string_view name) {
  while (!name.empty() && name.back() == '_') name.remove_suffix(1);
  return std::string(name.empty() ? "x" : name) + "_V";
}

[[noreturn]] void reject(const std::string& message) {
  throw std::invalid_argument("write_recording_csv: " + message);
}

// Messages are built on every call, so per-sample checks use `if (...) reject(...)`.
void require(bool condition, const std::string& message) {
  if (!condition) reject(message);
}

void require_length(std::string_view name, std::size_t length, std::size_t expected) {
  require(length == expected, std::string(name) + " has " + std::to_string(length) +
                                  " values, time_s has " + std::to_string(expected));
}

void check_recording_for_writing(const Recording& recording) {
  if (!recording.calibrations.empty()) {
    reject("the recording holds raw columns (" + recording.calibrations.begin()->first +
           " through its record); a CSV holds physical values");
  }
  const std::size_t size = recording.time_s.size();
  require(size > 0, "no samples (a recording needs at least one row)");
  require_length(kForceColumn, recording.force_N.size(), size);
  require(recording.angle_rad || recording.rate_rad_s, "neither angle_rad nor rate_rad_s");
  if (recording.angle_rad) require_length(kAngleColumn, recording.angle_rad->size(), size);
  if (recording.rate_rad_s) require_length(kRateColumn, recording.rate_rad_s->size(), size);
  if (recording.stroke) {
    require_length(kStrokeColumn, recording.stroke->size(), size);
    for (std::size_t row = 0; row < size; ++row) {
      if ((*recording.stroke)[row] < 0) {
        reject("stroke " + std::to_string((*recording.stroke)[row]) + " in row " +
               std::to_string(row) + " is negative");
      }
    }
  }
  for (std::size_t row = 0; row < size; ++row) {
    if (!std::isfinite(recording.time_s[row])) {
      reject("time_s in row " + std::to_string(row) + " is not finite");
    }
    if (row > 0 && !(recording.time_s[row] > recording.time_s[row - 1])) {
      reject("time_s " + format_csv_number(recording.time_s[row]) + " in row " +
             std::to_string(row) + " is not after the previous row's " +
             format_csv_number(recording.time_s[row - 1]));
    }
  }
  require(recording.extra_names.size() == recording.extra_columns.size(),
          std::to_string(recording.extra_names.size()) + " extra names but " +
              std::to_string(recording.extra_columns.size()) + " extra columns");
  for (std::size_t extra = 0; extra < recording.extra_names.size(); ++extra) {
    const std::string& name = recording.extra_names[extra];
    require(!is_known_column(name), "extra column '" + name + "' has the name of a main column");
    require(has_unit_suffix(name), "extra column '" + name + "' has no unit suffix (e.g. " +
                                       unit_suffix_example(name) + ")");
    require_length(name, recording.extra_columns[extra].size(), size);
  }
  for (const auto& [key, value] : recording.metadata) {
    require(!is_typed_metadata_key(key),
            "metadata holds '" + key + "'; set the Recording field of that name instead");
  }
  for (const auto& [key, value] : {std::pair{kHandleRadiusKey, recording.handle_radius_m},
                                   std::pair{kSampleRateKey, recording.sample_rate_hz}}) {
    require(!value || (std::isfinite(*value) && *value > 0.0),
            std::string(key) + " is not a positive number");
  }
}

}  // namespace

std::string handle_radius_problem(double radius_m, const std::string& origin) {
  if (radius_m >= kHandleRadiusMinM && radius_m <= kHandleRadiusMaxM) return "";
  return printf_text("%.6g m", radius_m) + (origin.empty() ? "" : " (from " + origin + ")") +
         " is outside " + format_number(kHandleRadiusMinM) + " to " +
         format_number(kHandleRadiusMaxM) + " m, where a door handle is";
}

namespace {

// The finite physical values of a column: through its record when Recording::calibrations has
// one.
std::vector<double> physical_values(const Recording& recording, std::string_view column,
                                    const std::vector<double>& values) {
  const auto record = recording.calibrations.find(std::string(column));
  std::vector<double> out;
  out.reserve(values.size());
  for (const double value : values) {
    const double physical =
        record == recording.calibrations.end() ? value : record->second.apply(value);
    if (std::isfinite(physical)) out.push_back(physical);
  }
  return out;
}

}  // namespace

std::vector<std::string> unit_doubts(const Recording& recording) {
  std::vector<std::string> doubts;
  if (recording.angle_rad) {
    const std::vector<double> angle =
        physical_values(recording, kAngleColumn, *recording.angle_rad);
    const auto [low, high] = std::minmax_element(angle.begin(), angle.end());
    if (low != angle.end() && *high - *low > kAngleSpanMaxRad) {
      doubts.push_back(
          "angle_rad spans " + format_significant(*low, 4) + " to " + format_significant(*high, 4) +
          " rad, more than a turn: an angle in degrees read as radians? (import "
          "converts it: --scale angle=" +
          format_significant(kRadPerDeg, 6) + ", or a --map column whose name ends in (deg))");
    }
  }
  if (recording.rate_rad_s) {
    double fastest_rad_s = 0.0;
    for (const double rate : physical_values(recording, kRateColumn, *recording.rate_rad_s)) {
      fastest_rad_s = std::max(fastest_rad_s, std::abs(rate));
    }
    if (fastest_rad_s > kRateMaxRadPerS) {
      doubts.push_back("|rate_rad_s| reaches " + format_significant(fastest_rad_s, 4) +
                       " rad/s, more than two turns a second: a rate in deg/s read as rad/s? "
                       "(import converts it: --scale rate=" +
                       format_significant(kRadPerDeg, 6) +
                       ", or a --map column whose name ends in (deg/s))");
    }
  }
  const double step_s = median_interval_s(recording.time_s);
  if (step_s > kSampleIntervalMaxS) {
    doubts.push_back("time_s steps " + format_significant(step_s, 4) +
                     " s from sample to sample (the median), too slow to follow a door: a time "
                     "in ms read as seconds? (import converts a --map time column whose name "
                     "ends in (ms))");
  }
  return doubts;
}

bool has_unit_suffix(std::string_view name) {
  const auto underscore = name.rfind('_');
  return underscore != std::string_view::npos && underscore > 0 && underscore + 1 < name.size();
}

std::string unit_column_suffix(const std::string& unit) {
  std::string suffix;
  for (char c : unit) suffix += (c == '/' || c == '*' || c == ' ' || c == '^') ? '_' : c;
  return suffix;
}

std::string unit_of_column(const std::string& column) {
  for (const char* compound : {"_rad_s", "_deg_s", "_m_s", "_N_m"}) {
    const std::string ending(compound);
    if (column.size() > ending.size() &&
        column.compare(column.size() - ending.size(), ending.size(), ending) == 0) {
      std::string unit = ending.substr(1);
      std::replace(unit.begin(), unit.end(), '_', unit == "N_m" ? '*' : '/');
      return unit;
    }
  }
  return column.substr(column.rfind('_') + 1);
}

Recording recording_from_table(const CsvTable& table, std::string_view source) {
  Recording recording;
  recording.source = std::string(source);

  // Metadata first: it comes first in the file, so errors are reported in file order.
  for (std::size_t i = 0; i < table.metadata.size(); ++i) {
    const auto& [key, value] = table.metadata[i];
    if (!is_typed_metadata_key(key)) {
      recording.metadata.push_back(table.metadata[i]);
      continue;
    }
    const std::optional<double> number = parse_csv_number(value);
    if (!number || !(*number > 0.0)) {
      const int line = i < table.metadata_line_numbers.size() ? table.metadata_line_numbers[i] : 0;
      throw CsvError(source, line,
                     "metadata " + key + ": '" + value + "' is not a positive number");
    }
    (key == kHandleRadiusKey ? recording.handle_radius_m : recording.sample_rate_hz) = *number;
  }

  const auto time_column = table.find_column(kTimeColumn);
  const auto force_column = table.find_column(kForceColumn);
  const auto angle_column = table.find_column(kAngleColumn);
  const auto rate_column = table.find_column(kRateColumn);
  const auto stroke_column = table.find_column(kStrokeColumn);
  for (const auto& [column, name] :
       {std::pair{time_column, kTimeColumn}, std::pair{force_column, kForceColumn}}) {
    if (!column) {
      throw CsvError(source, table.header_line,
                     "header lacks required column " + std::string(name));
    }
  }
  if (!angle_column && !rate_column) {
    throw CsvError(source, table.header_line, "header has neither angle_rad nor rate_rad_s");
  }
  for (std::size_t c = 0; c < table.column_names.size(); ++c) {
    const std::string& name = table.column_names[c];
    if (is_known_column(name)) continue;
    if (!has_unit_suffix(name)) {
      throw CsvError(
          source, table.header_line,
          "column '" + name + "' has no unit suffix (e.g. " + unit_suffix_example(name) + ")");
    }
    recording.extra_names.push_back(name);
    recording.extra_columns.push_back(table.columns[c]);
  }

  if (table.row_count() == 0) throw CsvError(source, 0, "no data rows after the header");
  const std::vector<double>& time_s = table.columns[*time_column];
  for (std::size_t row = 0; row < table.row_count(); ++row) {
    const int line = table.line_numbers[row];
    for (const auto& [column, name] :
         {std::pair{time_column, kTimeColumn}, std::pair{stroke_column, kStrokeColumn}}) {
      if (column && std::isnan(table.columns[*column][row])) {  // only as a missing sample
        throw CsvError(source, line,
                       "column " + std::string(name) + ": empty cell (" + std::string(name) +
                           " is never missing)");
      }
    }
    if (row > 0 && !(time_s[row] > time_s[row - 1])) {
      throw CsvError(source, line,
                     "time_s " + format_csv_number(time_s[row]) +
                         " is not after the previous row's " + format_csv_number(time_s[row - 1]));
    }
    if (stroke_column && !stroke_id(table.columns[*stroke_column][row])) {
      throw CsvError(source, line,
                     "stroke " + format_csv_number(table.columns[*stroke_column][row]) +
                         " is not a non-negative integer");
    }
  }

  recording.time_s = time_s;
  recording.force_N = table.columns[*force_column];
  if (angle_column) recording.angle_rad = table.columns[*angle_column];
  if (rate_column) recording.rate_rad_s = table.columns[*rate_column];
  if (stroke_column) {
    recording.stroke.emplace();
    recording.stroke->reserve(table.row_count());
    for (const double value : table.columns[*stroke_column]) {
      recording.stroke->push_back(*stroke_id(value));
    }
  }
  recording.line_numbers = table.line_numbers;
  return recording;
}

Recording parse_recording_csv(std::string_view text, std::string_view source,
                              EmptyCells empty_cells) {
  return recording_from_table(parse_csv_table(text, source, empty_cells), source);
}

Recording read_recording_csv(const std::filesystem::path& path, EmptyCells empty_cells) {
  return recording_from_table(read_csv_file(path, empty_cells), path.string());
}

void write_recording_csv(std::ostream& out, const Recording& recording) {
  check_recording_for_writing(recording);

  CsvMetadata metadata;
  if (recording.handle_radius_m) {
    metadata.emplace_back(kHandleRadiusKey, format_csv_number(*recording.handle_radius_m));
  }
  if (recording.sample_rate_hz) {
    metadata.emplace_back(kSampleRateKey, format_csv_number(*recording.sample_rate_hz));
  }
  metadata.insert(metadata.end(), recording.metadata.begin(), recording.metadata.end());

  std::vector<std::string> names{std::string(kTimeColumn), std::string(kForceColumn)};
  std::vector<const std::vector<double>*> columns{&recording.time_s, &recording.force_N};
  if (recording.angle_rad) {
    names.emplace_back(kAngleColumn);
    columns.push_back(&*recording.angle_rad);
  }
  if (recording.rate_rad_s) {
    names.emplace_back(kRateColumn);
    columns.push_back(&*recording.rate_rad_s);
  }
  std::vector<double> stroke_values;  // write_csv takes doubles; ids up to 2^31 are exact
  if (recording.stroke) {
    stroke_values.assign(recording.stroke->begin(), recording.stroke->end());
    names.emplace_back(kStrokeColumn);
    columns.push_back(&stroke_values);
  }
  for (std::size_t extra = 0; extra < recording.extra_names.size(); ++extra) {
    names.push_back(recording.extra_names[extra]);
    columns.push_back(&recording.extra_columns[extra]);
  }
  write_csv(out, metadata, names, columns);
}

void write_recording_csv_file(const std::filesystem::path& path, const Recording& recording) {
  // Checked before the file is created, so a bad recording leaves no half-written file.
  check_recording_for_writing(recording);
  write_file_atomically(path, [&](std::ostream& out) { write_recording_csv(out, recording); });
}

}  // namespace doorbench
