#include "acquisition/session/csv_table.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <system_error>
#include <unordered_set>

#include "acquisition/session/lfs_pointer.h"
#include "acquisition/session/printable.h"

namespace doorbench {
namespace {

constexpr std::string_view kUtf8ByteOrderMark = "\xEF\xBB\xBF";
// Cell text quoted in a message is cut here so that a runaway cell keeps the message short.
constexpr std::size_t kMaxQuotedChars = 40;

bool is_blank_char(char c) {
  return c == ' ' || c == '\t';
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && is_blank_char(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_blank_char(text.back())) text.remove_suffix(1);
  return text;
}

std::string quoted(std::string_view text) {
  // Built with append: GCC 12 warns falsely (-Wrestrict) on "'" + std::string(...).
  // Control characters are shown escaped (acquisition/session/printable.h).
  std::string result("'");
  if (text.size() <= kMaxQuotedChars) return result.append(printable(text)).append("'");
  return result.append(printable(text.substr(0, kMaxQuotedChars))).append("...'");
}

bool is_metadata_key_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-' || c == '.';
}

bool is_metadata_key(std::string_view key) {
  return !key.empty() && std::all_of(key.begin(), key.end(), is_metadata_key_char);
}

// The text after a line's `#`: `key: value` when the part before the first colon is one
// word of key characters, otherwise a note (empty key, whole text as value).
std::pair<std::string_view, std::string_view> split_comment(std::string_view comment) {
  comment = trim(comment);
  const auto colon = comment.find(':');
  if (colon != std::string_view::npos) {
    const std::string_view key = trim(comment.substr(0, colon));
    if (is_metadata_key(key)) return {key, trim(comment.substr(colon + 1))};
  }
  return {std::string_view(), comment};
}

enum class CellProblem { kNone, kEmpty, kNotANumber, kOutOfRange, kNotFinite };

// Parses one cell (spaces and tabs around it allowed) as a whole double. A leading '+' is accepted
// (some programs write it); std::from_chars alone would refuse it.
CellProblem parse_cell(std::string_view cell, double& value) {
  cell = trim(cell);
  if (cell.empty()) return CellProblem::kEmpty;
  if (cell.size() > 1 && cell.front() == '+' &&
      (cell[1] == '.' || (cell[1] >= '0' && cell[1] <= '9'))) {
    cell.remove_prefix(1);
  }
  const char* const end = cell.data() + cell.size();
  const auto [stop, error] = std::from_chars(cell.data(), end, value, std::chars_format::general);
  if (error == std::errc::result_out_of_range && stop == end) return CellProblem::kOutOfRange;
  if (error != std::errc() || stop != end) return CellProblem::kNotANumber;
  if (!std::isfinite(value)) return CellProblem::kNotFinite;
  return CellProblem::kNone;
}

// Walks the text line by line, counting lines from 1 and removing "\r" of "\r\n".
class LineReader {
 public:
  LineReader(std::string_view text, std::string_view source) : rest_(text), source_(source) {
    if (rest_.substr(0, kUtf8ByteOrderMark.size()) == kUtf8ByteOrderMark) {
      rest_.remove_prefix(kUtf8ByteOrderMark.size());
    }
  }

  bool next(std::string_view& line) {
    if (rest_.empty()) return false;
    const auto newline = rest_.find('\n');
    line = rest_.substr(0, newline);
    rest_.remove_prefix(newline == std::string_view::npos ? rest_.size() : newline + 1);
    ++line_number_;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    // A lone carriage return would end up inside a cell or name; old Mac files have them.
    if (line.find('\r') != std::string_view::npos) {
      throw CsvError(source_, line_number_,
                     "carriage return inside the line (line endings must be \\n or \\r\\n)");
    }
    return true;
  }

  int line_number() const { return line_number_; }
  std::string_view rest() const { return rest_; }

 private:
  std::string_view rest_;
  std::string_view source_;
  int line_number_ = 0;
};

bool is_comment(std::string_view line) {
  line = trim(line);
  return !line.empty() && line.front() == '#';
}

// The first control character of `text` (bytes 0x00-0x1f but the tab, and 0x7f), if any.
std::size_t control_character_at(std::string_view text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if ((byte < 0x20 && byte != '\t') || byte == 0x7f) return i;
  }
  return std::string_view::npos;
}

void read_metadata_line(std::string_view line, int line_number, std::string_view source,
                        CsvTable& table) {
  // Metadata is text: a NUL would cut it where it is stored (a session's attributes), other
  // control characters would reach terminals. Refused where they are, not cut or dropped.
  if (const std::size_t at = control_character_at(line); at != std::string_view::npos) {
    throw CsvError(source, line_number,
                   "control character " + printable(line.substr(at, 1)) + " at column " +
                       std::to_string(at + 1) +
                       " of a metadata line (metadata is kept as text: remove it from the "
                       "file)");
  }
  line = trim(line);
  const auto [key, value] = split_comment(line.substr(1));
  if (!key.empty()) {
    for (std::size_t i = 0; i < table.metadata.size(); ++i) {
      if (table.metadata[i].first == key) {
        throw CsvError(source, line_number,
                       "duplicate metadata key '" + std::string(key) + "' (first on line " +
                           std::to_string(table.metadata_line_numbers[i]) + ")");
      }
    }
  }
  table.metadata.emplace_back(std::string(key), std::string(value));
  table.metadata_line_numbers.push_back(line_number);
}

// The separator as messages name it.
std::string separator_name(char separator) {
  return separator == '\t' ? "a tab" : std::string("'") + separator + "'";
}

// What is wrong with a column name, or an empty string when nothing is.
std::string column_name_problem(std::string_view name, const CsvDialect& dialect) {
  if (name.empty()) return "is empty";
  if (name.find('"') != std::string_view::npos) {
    return "contains '\"' (quoted fields are not supported)";
  }
  if (dialect.separator == ',') {
    if (name.find(';') != std::string_view::npos || name.find('\t') != std::string_view::npos) {
      return "contains ';' or a tab (fields must be separated by commas; doorbench import reads "
             "other separators with --separator)";
    }
  } else {
    for (const char other : {';', '\t'}) {
      if (other != dialect.separator && name.find(other) != std::string_view::npos) {
        return "contains " + separator_name(other) + " (fields are separated by " +
               separator_name(dialect.separator) + " here, as --separator says)";
      }
    }
  }
  if (const std::size_t at = control_character_at(name); at != std::string_view::npos) {
    return "contains the control character " + printable(name.substr(at, 1));
  }
  if (parse_csv_number(name)) return "is a number (is the header row missing?)";
  return {};
}

void read_header(std::string_view line, int line_number, std::string_view source,
                 const CsvDialect& dialect, CsvTable& table) {
  table.header_line = line_number;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(dialect.separator, start);
    const std::string_view name = trim(line.substr(start, comma - start));
    const std::string problem = column_name_problem(name, dialect);
    if (!problem.empty()) {
      throw CsvError(source, line_number,
                     "column " + std::to_string(table.column_names.size() + 1) + " name " +
                         quoted(name) + " " + problem);
    }
    if (std::find(table.column_names.begin(), table.column_names.end(), name) !=
        table.column_names.end()) {
      throw CsvError(source, line_number, "duplicate column name '" + std::string(name) + "'");
    }
    table.column_names.emplace_back(name);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

// A cell with a decimal comma as parse_cell reads it ("1,5" as "1.5"); false when it holds a
// '.', which the dialect does not read (a thousands separator, or a file of the other kind).
bool with_decimal_point(std::string_view cell, std::string& out) {
  if (cell.find('.') != std::string_view::npos) return false;
  out.assign(cell);
  std::replace(out.begin(), out.end(), ',', '.');
  return true;
}

constexpr double kSecondsPerDay = 86400.0;

// A cell of the dialect's date-time column (CsvDialect::date_time_column): true when it is a
// date and time, appended as seconds since the first row's; false when it and the first row's are
// not (then it is a number). Throws CsvError for a column that mixes the two, or zones.
bool read_date_time_cell(std::string_view cell, std::size_t column, int line_number,
                         std::string_view source, CsvTable& table) {
  const std::string& name = table.column_names[column];
  const std::optional<DateTimeText> when = parse_date_time(cell);
  const bool first_row = table.line_numbers.empty();
  if (first_row && when) table.first_date_time = when;
  if (!table.first_date_time) {
    if (!when) return false;
    throw CsvError(source, line_number,
                   "column " + name + ": " + quoted(trim(cell)) +
                       " is a date and time, but the first row's is a number");
  }
  const DateTimeText& first = *table.first_date_time;
  if (!first.date_known && (!when || when->date_known)) {
    throw CsvError(source, line_number,
                   "column " + name + ": " + quoted(trim(cell)) +
                       " is not a time of the day without a date as the first row's "
                       "(hh:mm:ss.fff)");
  }
  if (!when || when->zone_known != first.zone_known || when->date_known != first.date_known) {
    throw CsvError(
        source, line_number,
        "column " + name + ": " + quoted(trim(cell)) + " is not a date and time " +
            (first.zone_known ? "with a time zone (Z or +hh:mm)" : "without a time zone") +
            " as the first row's (YYYY-MM-DD hh:mm:ss.fff)");
  }
  double since_first_s =
      static_cast<double>(when->seconds - first.seconds) + (when->fraction_s - first.fraction_s);
  // A time of the day that falls more than 12 h behind the row before has passed midnight.
  std::vector<double>& times = table.columns[column];
  if (!first.date_known && !times.empty()) {
    while (since_first_s < times.back() - kSecondsPerDay / 2) since_first_s += kSecondsPerDay;
  }
  times.push_back(since_first_s);
  return true;
}

void read_data_row(std::string_view line, int line_number, std::string_view source,
                   EmptyCells empty_cells, const CsvDialect& dialect, CsvTable& table) {
  const std::size_t column_count = table.column_names.size();
  const std::size_t field_count = 1 + std::count(line.begin(), line.end(), dialect.separator);
  if (field_count != column_count) {
    throw CsvError(source, line_number,
                   "expected " + std::to_string(column_count) + " fields, found " +
                       std::to_string(field_count));
  }
  std::size_t start = 0;
  std::string decimal_point_cell;
  for (std::size_t column = 0; column < column_count; ++column) {
    const auto comma = line.find(dialect.separator, start);
    const std::string_view cell = line.substr(start, comma - start);
    // A date and time's fraction is after a '.' whatever the dialect's decimal point.
    if (!dialect.date_time_column.empty() &&
        table.column_names[column] == dialect.date_time_column &&
        read_date_time_cell(cell, column, line_number, source, table)) {
      start = comma + 1;
      continue;
    }
    if (dialect.decimal_comma && !with_decimal_point(cell, decimal_point_cell)) {
      throw CsvError(source, line_number,
                     "column " + table.column_names[column] + ": " + quoted(trim(cell)) +
                         " holds a '.' (with --decimal-comma the decimal point is ',', and "
                         "thousands separators are not read)");
    }
    double value = 0.0;
    CellProblem problem =
        parse_cell(dialect.decimal_comma ? std::string_view(decimal_point_cell) : cell, value);
    if (problem == CellProblem::kEmpty && empty_cells == EmptyCells::kMissing) {
      value = std::numeric_limits<double>::quiet_NaN();  // a missing sample
      problem = CellProblem::kNone;
    }
    if (problem != CellProblem::kNone) {
      std::string detail = "column " + table.column_names[column] + ": ";
      switch (problem) {
        case CellProblem::kEmpty:
          detail += "empty cell";
          break;
        case CellProblem::kOutOfRange:
          detail += quoted(trim(cell)) + " is out of range for a double";
          break;
        case CellProblem::kNotFinite:
          detail += quoted(trim(cell)) + " is not a finite number";
          break;
        default:
          detail += quoted(trim(cell)) + " is not a number";
          if (dialect.separator != ',' && !dialect.decimal_comma &&
              cell.find(',') != std::string_view::npos) {
            detail += " (a decimal comma? give --decimal-comma)";
          }
          break;
      }
      throw CsvError(source, line_number, detail);
    }
    table.columns[column].push_back(value);
    start = comma + 1;
  }
  table.line_numbers.push_back(line_number);
}

[[noreturn]] void reject(const std::string& message) {
  throw std::invalid_argument("write_csv: " + message);
}

// Messages are built on every call, so per-value checks use `if (...) reject(...)`.
void require(bool condition, const std::string& message) {
  if (!condition) reject(message);
}

bool has_line_break(std::string_view text) {
  return text.find('\n') != std::string_view::npos || text.find('\r') != std::string_view::npos;
}

void check_metadata_for_writing(const CsvMetadata& metadata) {
  std::unordered_set<std::string_view> keys;
  for (const auto& [key, value] : metadata) {
    require(!has_line_break(key) && !has_line_break(value),
            "metadata '" + key + "' has a line break");
    require(trim(value) == value, "metadata '" + key + "' value has leading or trailing spaces");
    if (key.empty()) {
      require(split_comment(value).first.empty(),
              "note '" + value + "' would read back as `key: value` metadata");
    } else {
      require(is_metadata_key(key),
              "metadata key '" + key + "' must consist of letters, digits, '_', '-' and '.'");
      require(keys.insert(key).second, "duplicate metadata key '" + key + "'");
    }
  }
}

void check_columns_for_writing(const std::vector<std::string>& column_names,
                               const std::vector<const std::vector<double>*>& columns) {
  require(!column_names.empty(), "no columns");
  require(column_names.size() == columns.size(), std::to_string(column_names.size()) +
                                                     " column names but " +
                                                     std::to_string(columns.size()) + " columns");
  std::unordered_set<std::string_view> names;
  for (std::size_t c = 0; c < column_names.size(); ++c) {
    const std::string& name = column_names[c];
    const std::string problem = column_name_problem(name, CsvDialect{});
    require(problem.empty(), "column name '" + name + "' " + problem);
    require(trim(name) == name, "column name '" + name + "' has leading or trailing spaces");
    require(name.find(',') == std::string::npos && !has_line_break(name),
            "column name '" + name + "' contains ',' or a line break");
    // Only the first: a header line starting with '#' would read back as metadata. A later
    // name may start with '#', as the reader accepts it (found by fuzz/csv.cpp).
    require(c > 0 || name.front() != '#',
            "first column name '" + name + "' starts with '#' (the header would read as metadata)");
    require(names.insert(name).second, "duplicate column name '" + name + "'");
    require(columns[c] != nullptr, "column '" + name + "' is null");
    require(columns[c]->size() == columns[0]->size(),
            "column '" + name + "' has " + std::to_string(columns[c]->size()) +
                " values, column '" + column_names[0] + "' has " +
                std::to_string(columns[0]->size()));
    for (std::size_t row = 0; row < columns[c]->size(); ++row) {
      if (std::isinf((*columns[c])[row]) ||
          (column_names.size() == 1 && std::isnan((*columns[c])[row]))) {  // a blank line
        reject("column '" + name + "' row " + std::to_string(row) + " is not finite");
      }
    }
  }
}

}  // namespace

namespace {

// Built with append: GCC 12 warns falsely (-Wrestrict) on the chained operator+ form.
std::string located_message(std::string_view source, int line, std::string_view detail) {
  std::string message(source);
  if (line > 0) message.append(":").append(std::to_string(line));
  message.append(": ").append(detail);
  return message;
}

}  // namespace

CsvError::CsvError(std::string_view source, int line, std::string_view detail)
    : std::runtime_error(located_message(source, line, detail)),
      source_(source),
      line_(line > 0 ? line : 0),
      detail_(detail) {}

std::optional<std::size_t> CsvTable::find_column(std::string_view name) const {
  const auto found = std::find(column_names.begin(), column_names.end(), name);
  if (found == column_names.end()) return std::nullopt;
  return static_cast<std::size_t>(found - column_names.begin());
}

std::optional<std::string> CsvTable::metadata_value(std::string_view key) const {
  if (key.empty()) throw std::invalid_argument("CsvTable::metadata_value: empty key");
  for (const auto& [entry_key, value] : metadata) {
    if (entry_key == key) return value;
  }
  return std::nullopt;
}

std::optional<double> parse_csv_number(std::string_view text) {
  double value = 0.0;
  if (parse_cell(text, value) != CellProblem::kNone) return std::nullopt;
  return value;
}

std::string format_csv_number(double value) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument("format_csv_number: value is not finite");
  }
  char buffer[32];  // the shortest round-trip form of a double needs at most 24
  const auto [end, error] = std::to_chars(std::begin(buffer), std::end(buffer), value);
  if (error != std::errc()) throw std::logic_error("format_csv_number: buffer too small");
  return std::string(buffer, end);
}

std::string CsvDialect::validate() const {
  if (separator != ',' && separator != ';' && separator != '\t') {
    return "the separator must be ',', ';' or a tab";
  }
  if (decimal_comma && separator == ',') {
    return "--decimal-comma needs --separator semicolon or tab (a comma cannot both separate "
           "fields and mark decimals)";
  }
  return {};
}

CsvTable parse_csv_table(std::string_view text, std::string_view source, EmptyCells empty_cells,
                         const CsvDialect& dialect) {
  if (const std::string problem = dialect.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  if (const std::string pointer = lfs_pointer_description(text); !pointer.empty()) {
    throw CsvError(source, 0, pointer);
  }
  CsvTable table;
  LineReader reader(text, source);
  std::string_view line;
  // Metadata and blank lines up to the header.
  while (true) {
    if (!reader.next(line)) throw CsvError(source, 0, "no header row");
    if (trim(line).empty()) continue;
    if (!is_comment(line)) break;
    read_metadata_line(line, reader.line_number(), source, table);
  }
  read_header(line, reader.line_number(), source, dialect, table);

  // Reserving for every remaining line saves the columns' regrowth on big files.
  const auto lines_left =
      static_cast<std::size_t>(std::count(reader.rest().begin(), reader.rest().end(), '\n')) + 1;
  table.columns.resize(table.column_names.size());
  for (auto& column : table.columns) column.reserve(lines_left);
  table.line_numbers.reserve(lines_left);

  while (reader.next(line)) {
    // Blank lines carry no data, so skipping them drops nothing; they may be anywhere.
    if (trim(line).empty()) continue;
    if (is_comment(line)) {
      throw CsvError(source, reader.line_number(),
                     "'#' line after the header (metadata must come before the header row)");
    }
    read_data_row(line, reader.line_number(), source, empty_cells, dialect, table);
  }
  return table;
}

CsvTable read_csv_file(const std::filesystem::path& path, EmptyCells empty_cells,
                       const CsvDialect& dialect) {
  const std::string source = path.string();
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    throw CsvError(source, 0, "is a directory, not a file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CsvError(source, 0, "cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw CsvError(source, 0, "read error");
  return parse_csv_table(text.str(), source, empty_cells, dialect);
}

void write_csv(std::ostream& out, const CsvMetadata& metadata,
               const std::vector<std::string>& column_names,
               const std::vector<const std::vector<double>*>& columns) {
  check_metadata_for_writing(metadata);
  check_columns_for_writing(column_names, columns);

  std::string text;
  for (const auto& [key, value] : metadata) {
    text += key.empty() ? "# " + value : "# " + key + ":" + (value.empty() ? "" : " " + value);
    text += '\n';
  }
  for (std::size_t c = 0; c < column_names.size(); ++c) {
    if (c > 0) text += ',';
    text += column_names[c];
  }
  text += '\n';
  out << text;

  // Rows go out in blocks so that big tables need neither one huge string nor a write
  // per number.
  constexpr std::size_t kBlockChars = 1 << 16;
  text.clear();
  char number[32];
  const std::size_t row_count = columns[0]->size();
  for (std::size_t row = 0; row < row_count; ++row) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c > 0) text += ',';
      const double value = (*columns[c])[row];
      if (std::isnan(value)) continue;  // a missing sample: an empty cell
      const auto [end, error] = std::to_chars(std::begin(number), std::end(number), value);
      if (error != std::errc()) throw std::logic_error("write_csv: number buffer too small");
      text.append(number, end);
    }
    text += '\n';
    if (text.size() >= kBlockChars) {
      out << text;
      text.clear();
    }
  }
  out << text;
  if (!out) throw std::runtime_error("write_csv: writing to the output stream failed");
}

void write_csv(std::ostream& out, const CsvTable& table) {
  std::vector<const std::vector<double>*> columns;
  for (const auto& column : table.columns) columns.push_back(&column);
  write_csv(out, table.metadata, table.column_names, columns);
}

}  // namespace doorbench
