#include "study/trials_table.h"

#include <fstream>
#include <iterator>
#include <sstream>

namespace doorbench::study {
namespace {

std::string located(std::string_view source, int line, std::string_view detail) {
  std::string text(source);
  if (line > 0) text.append(":").append(std::to_string(line));
  text.append(": ").append(detail);
  return text;
}

// Splits the text into records of fields, RFC 4180: quotes may hold commas and line breaks.
struct Record {
  std::vector<std::string> fields;
  int line = 0;
};

class RecordReader {
 public:
  RecordReader(std::string_view text, std::string_view source) : text_(text), source_(source) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") text_.remove_prefix(3);
  }

  // The next record; nullopt at the end. Blank lines are skipped.
  std::optional<Record> next() {
    while (at_ < text_.size() && (text_[at_] == '\n' || text_[at_] == '\r')) end_line();
    if (at_ >= text_.size()) return std::nullopt;
    Record record;
    record.line = line_;
    std::string field;
    while (true) {
      if (at_ < text_.size() && text_[at_] == '"') {
        read_quoted(field);
      } else {
        read_plain(field);
      }
      record.fields.push_back(std::move(field));
      field.clear();
      if (at_ < text_.size() && text_[at_] == ',') {
        ++at_;
        continue;
      }
      if (at_ < text_.size()) end_line();
      return record;
    }
  }

 private:
  void end_line() {
    if (text_[at_] == '\r' && at_ + 1 < text_.size() && text_[at_ + 1] == '\n') ++at_;
    ++at_;
    ++line_;
  }

  void read_plain(std::string& field) {
    while (at_ < text_.size() && text_[at_] != ',' && text_[at_] != '\n' && text_[at_] != '\r') {
      if (text_[at_] == '"') {
        throw TrialsTableError(source_, line_,
                               "a double quote inside an unquoted field (quote the whole field)");
      }
      field += text_[at_++];
    }
  }

  void read_quoted(std::string& field) {
    const int start_line = line_;
    ++at_;
    while (true) {
      if (at_ >= text_.size()) {
        throw TrialsTableError(source_, start_line, "a quoted field is not closed");
      }
      const char c = text_[at_++];
      if (c == '"') {
        if (at_ < text_.size() && text_[at_] == '"') {
          field += '"';
          ++at_;
          continue;
        }
        break;
      }
      if (c == '\n') ++line_;
      field += c;
    }
    if (at_ < text_.size() && text_[at_] != ',' && text_[at_] != '\n' && text_[at_] != '\r') {
      throw TrialsTableError(source_, line_, "text after a quoted field's closing quote");
    }
  }

  std::string_view text_;
  std::string source_;
  std::size_t at_ = 0;
  int line_ = 1;
};

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ",") + name;
  return text;
}

}  // namespace

TrialsTableError::TrialsTableError(std::string_view source, int line, std::string_view detail)
    : std::runtime_error(located(source, line, detail)), line_(line) {}

std::optional<std::size_t> TrialsTable::find_column(std::string_view name) const {
  for (std::size_t c = 0; c < column_names.size(); ++c) {
    if (column_names[c] == name) return c;
  }
  return std::nullopt;
}

const std::string& TrialsTable::value(std::size_t row, std::string_view name) const {
  const std::optional<std::size_t> column = find_column(name);
  if (!column) {
    throw TrialsTableError(source, row < line_numbers.size() ? line_numbers[row] : 0,
                           "no column '" + std::string(name) + "'");
  }
  return rows.at(row).at(*column);
}

TrialsTable parse_trials_table(std::string_view text, std::string_view source) {
  return parse_trials_table(text, source, kTrialsColumns);
}

TrialsTable parse_trials_table(std::string_view text, std::string_view source,
                               std::span<const std::string_view> required_columns) {
  RecordReader reader(text, source);
  TrialsTable table;
  table.source = std::string(source);
  const std::optional<Record> header = reader.next();
  if (!header) throw TrialsTableError(source, 0, "no header row (the file holds no text)");
  table.column_names = header->fields;
  for (std::size_t c = 0; c < table.column_names.size(); ++c) {
    for (std::size_t d = 0; d < c; ++d) {
      if (table.column_names[c] == table.column_names[d]) {
        throw TrialsTableError(source, header->line,
                               "column '" + table.column_names[c] + "' is named twice");
      }
    }
  }
  for (std::string_view required : required_columns) {
    if (!table.find_column(required)) {
      throw TrialsTableError(source, header->line,
                             "no column '" + std::string(required) +
                                 "' (the header has: " + joined(table.column_names) + ")");
    }
  }
  while (std::optional<Record> record = reader.next()) {
    if (record->fields.size() != table.column_names.size()) {
      throw TrialsTableError(source, record->line,
                             std::to_string(record->fields.size()) + " fields, the header has " +
                                 std::to_string(table.column_names.size()));
    }
    table.rows.push_back(std::move(record->fields));
    table.line_numbers.push_back(record->line);
  }
  return table;
}

TrialsTable read_trials_table(const std::filesystem::path& path) {
  return read_trials_table(path, kTrialsColumns);
}

TrialsTable read_trials_table(const std::filesystem::path& path,
                              std::span<const std::string_view> required) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw TrialsTableError(path.string(), 0, "cannot open for reading");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.empty()) throw TrialsTableError(path.string(), 0, "is empty");
  return parse_trials_table(text, path.string(), required);
}

std::string csv_field(std::string_view value) {
  const bool quote = value.find_first_of(",\"\r\n") != std::string_view::npos ||
                     (!value.empty() && (value.front() == ' ' || value.back() == ' '));
  if (!quote) return std::string(value);
  std::string text = "\"";
  for (char c : value) {
    if (c == '"') text += '"';
    text += c;
  }
  return text + "\"";
}

std::string csv_row(const std::vector<std::string>& fields) {
  std::string text;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) text += ',';
    text += csv_field(fields[i]);
  }
  return text + "\n";
}

}  // namespace doorbench::study
