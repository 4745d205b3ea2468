#pragma once
// A numeric CSV table: the text layer under the door recording format of
// door-models.md §5.1 (see docs/csv-format.md). Leading `# key: value` metadata lines,
// one header row of column names, then one row of numbers per line, comma-separated,
// `.` as decimal point. Nothing is guessed: every rule a text breaks is a CsvError that
// names the source and the line.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/time_text.h"

namespace doorbench {

// Text that breaks the format. what() is one line, "SOURCE:LINE: detail", or
// "SOURCE: detail" when no single line is to blame (line() is then 0).
class CsvError : public std::runtime_error {
 public:
  CsvError(std::string_view source, int line, std::string_view detail);

  const std::string& source() const { return source_; }
  int line() const { return line_; }
  const std::string& detail() const { return detail_; }

 private:
  std::string source_;
  int line_;
  std::string detail_;
};

using CsvMetadata = std::vector<std::pair<std::string, std::string>>;

struct CsvTable {
  // In file order. A `#` line that is not `# key: value` is a free-form note, kept here
  // with an empty key and its text (after `#`, trimmed) as value.
  CsvMetadata metadata;
  std::vector<int> metadata_line_numbers;  // file line of each metadata entry, 1-based
  int header_line = 0;                     // file line of the header row, 1-based
  std::vector<std::string> column_names;
  std::vector<std::vector<double>> columns;  // column-major: columns[c][row]
  std::vector<int> line_numbers;             // file line of each data row, 1-based
  // The first row's date and time in the dialect's date_time_column, when it holds one.
  std::optional<DateTimeText> first_date_time;

  std::optional<std::size_t> find_column(std::string_view name) const;
  // The value of metadata key `key` (keys are unique in a parsed table). Throws
  // std::invalid_argument for an empty key: notes have no key to look up.
  std::optional<std::string> metadata_value(std::string_view key) const;
  std::size_t row_count() const { return line_numbers.size(); }
};

// What an empty (or blank) data cell is. kRefuse: an error ("column X: empty cell"), for
// tables that must be complete (a grid to evaluate, a force to replay). kMissing: a missing
// sample, read as NaN (a recording's lost scans, docs/csv-format.md#missing-samples); the
// caller decides which columns may hold one.
enum class EmptyCells { kRefuse, kMissing };

// How a CSV from elsewhere separates its fields and writes its decimal point (doorbench
// import --separator, --decimal-comma): a spreadsheet in a European locale writes "1,5;2,25",
// LabVIEW's spreadsheet files separate with tabs. The default is the exchange format's: commas,
// and '.' as the decimal point.
struct CsvDialect {
  char separator = ',';        // ',', ';' or '\t'
  bool decimal_comma = false;  // ',' is the decimal point; a '.' in a cell is refused
  // A column that may hold dates and times (a logger's "2024-05-02 09:30:00.125") or times of
  // the day ("09:30:00.125"): when its first row's cell is one (parse_date_time), every cell must
  // be one of its kind, stating a zone as the first does, and each is read as seconds since the
  // first (CsvTable::first_date_time); a time of the day more than 12 h behind the row before
  // has passed midnight. Otherwise the column is numbers as any other. "": none.
  std::string date_time_column;
  // "" when usable, else what is wrong: "--decimal-comma needs --separator semicolon or tab (a
  // comma cannot both separate fields and mark decimals)".
  std::string validate() const;
};

// Parses `text`; `source` names it in error messages (usually the file's path). With a
// dialect other than the default, fields are split at its separator and, with decimal_comma,
// a cell's ',' is its decimal point ("column force: '1.234' holds a '.' (with --decimal-comma
// the decimal point is ',', and thousands separators are not read)"). Throws
// std::invalid_argument when the dialect is not valid.
CsvTable parse_csv_table(std::string_view text, std::string_view source,
                         EmptyCells empty_cells = EmptyCells::kRefuse,
                         const CsvDialect& dialect = {});

// Reads and parses a file; the path is the source in messages. A file that cannot be read
// throws CsvError "PATH: cannot open for reading".
CsvTable read_csv_file(const std::filesystem::path& path,
                       EmptyCells empty_cells = EmptyCells::kRefuse,
                       const CsvDialect& dialect = {});

// Parses `text` (spaces and tabs around it allowed) as a whole, finite double the way data
// cells are parsed; nullopt when it is anything else.
std::optional<double> parse_csv_number(std::string_view text);

// The shortest text that reads back as exactly `value`. Throws std::invalid_argument for
// NaN and infinities, which are not valid samples.
std::string format_csv_number(double value);

// Writes `# key: value` lines (`# text` for a note, i.e. an empty key), the header and
// one row per sample. Throws std::invalid_argument when the input could not be read back
// as given: column count or lengths that differ, a null column, no columns, names that
// are empty, duplicated, padded with spaces, numbers, the first starting with `#`, contain `,` `"`
// `;`, tabs or line breaks, invalid or duplicated metadata keys, values with line breaks
// or edge spaces, notes that would read back as metadata, infinities. A NaN is a missing
// sample and is written as an empty cell (read back as NaN with EmptyCells::kMissing).
void write_csv(std::ostream& out, const CsvMetadata& metadata,
               const std::vector<std::string>& column_names,
               const std::vector<const std::vector<double>*>& columns);
void write_csv(std::ostream& out, const CsvTable& table);

}  // namespace doorbench
