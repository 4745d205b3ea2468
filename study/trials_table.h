#pragma once
// A campaign's trials table (docs/campaign.md): `trials.csv`, one row per trial in long
// format, readable by R's read.csv and Python's csv module without doorbench.
//
// The text is RFC 4180 CSV: a header row of column names, then one row per trial; a field
// that holds a comma, a double quote or a line break is quoted with double quotes (a quote
// inside doubled). The columns every reader relies on, in this spelling:
//
//   participant,block,trial,question,first,second,answer
//
// Other columns (times, session files, rendered parameters, ...) may follow in any order;
// a reader keeps them by name and ignores what it does not know.
//
// Errors: TrialsTableError, one line "SOURCE:LINE: detail" naming the file and the line
// (line 0 and "SOURCE: detail" when no line is to blame).
// Thread safety: free functions without shared state.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <ostream>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace doorbench::study {

// The columns a trials table must have, in this order at the start of a written table.
inline constexpr std::string_view kTrialsColumns[] = {"participant", "block",  "trial", "question",
                                                      "first",       "second", "answer"};

class TrialsTableError : public std::runtime_error {
 public:
  TrialsTableError(std::string_view source, int line, std::string_view detail);
  int line() const { return line_; }

 private:
  int line_;
};

struct TrialsTable {
  std::vector<std::string> column_names;       // as in the header, every column
  std::vector<std::vector<std::string>> rows;  // rows[r][c], one per data row
  std::vector<int> line_numbers;               // file line where each row starts, 1-based
  std::string source;                          // the file's path, for messages

  // The index of column `name`, or nullopt.
  std::optional<std::size_t> find_column(std::string_view name) const;
  // Row r's value in column `name`; throws TrialsTableError naming the row's line when the
  // table has no such column.
  const std::string& value(std::size_t row, std::string_view name) const;
};

// Parses `text`. Refused, each with its line: a missing header or a header without one of
// kTrialsColumns ("no column 'answer' (the header has: ...)"), a column named twice, a row
// with more or fewer fields than the header, an unterminated quote, a quote inside an
// unquoted field. Blank lines are skipped. A byte-order mark and CRLF line ends are read.
TrialsTable parse_trials_table(std::string_view text, std::string_view source);
// The same with other required columns (plan.csv's, study/campaign_plan.h).
TrialsTable parse_trials_table(std::string_view text, std::string_view source,
                               std::span<const std::string_view> required);

// Reads a file ("PATH: cannot open for reading", "PATH: is empty").
TrialsTable read_trials_table(const std::filesystem::path& path);
TrialsTable read_trials_table(const std::filesystem::path& path,
                              std::span<const std::string_view> required);

// One field as written: quoted when it holds ',', '"', '\r' or '\n' or starts or ends with a
// space; otherwise as is.
std::string csv_field(std::string_view value);
// One row: the fields joined with ',' and '\n' at the end.
std::string csv_row(const std::vector<std::string>& fields);

}  // namespace doorbench::study
