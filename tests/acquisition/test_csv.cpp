// The CSV exchange format of door-models.md §5.1: acquisition/session/csv_table.h and
// acquisition/recording_csv.h.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/csv_table.h"
#include "acquisition/session/recording_csv.h"
#include "core/number_format.h"
#include "core/units.h"

using namespace doorbench;

namespace {

// Same bits: tells -0.0 from 0.0, which == does not.
bool same_double(double a, double b) {
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}

// A file in the temporary directory, removed when the test ends.
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::string& stem)
      : path_(std::filesystem::temp_directory_path() /
              (stem + "-" + std::to_string(std::random_device{}()) + ".csv")) {}
  ~TemporaryFile() {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  const std::filesystem::path& path() const { return path_; }
  void write(const std::string& text) const {
    std::ofstream out(path_, std::ios::binary);
    out << text;
  }

 private:
  std::filesystem::path path_;
};

Recording parse(const std::string& text) {
  return parse_recording_csv(text, "run.csv");
}

Recording small_recording() {
  Recording recording;
  recording.handle_radius_m = 0.32;
  recording.sample_rate_hz = 1000;
  recording.metadata = {{"source", "simulator"}, {"", "free-form note"}};
  recording.time_s = {0.0, 0.001, 0.002};
  recording.force_N = {1.5, -2.25, 3.0};
  recording.angle_rad = std::vector<double>{0.0, 0.01, 0.02};
  recording.stroke = std::vector<int>{0, 1, 1};
  recording.extra_names = {"tau_Nm", "tau_u_Nm"};
  recording.extra_columns = {{0.1, 0.2, 0.3}, {-0.1, -0.2, -0.3}};
  return recording;
}

}  // namespace

TEST_CASE("a valid recording with metadata, notes and columns in unusual order", "[csv]") {
  const std::string text =
      "# source: LabVIEW rig 2\n"
      "# handle_radius_m: 0.31\n"
      "#sample_rate_hz:500\n"
      "# operator said the door was sticky\n"
      "\n"
      "stroke, rate_rad_s ,force_N,pot_V,time_s,angle_rad\n"
      "0,0.0,1.5,2.5,0.000,0.1\n"
      "1, -0.25 ,+2,2.75,0.002,1e-1\n"
      "\n"
      "1,0.5,3e0,3,0.004,.2\n"
      "\n";
  const Recording recording = parse(text);

  CHECK(recording.source == "run.csv");
  REQUIRE(recording.handle_radius_m.has_value());
  CHECK(*recording.handle_radius_m == 0.31);
  REQUIRE(recording.sample_rate_hz.has_value());
  CHECK(*recording.sample_rate_hz == 500.0);
  // The typed keys are moved out of the metadata; the note keeps an empty key.
  const CsvMetadata expected_metadata{{"source", "LabVIEW rig 2"},
                                      {"", "operator said the door was sticky"}};
  CHECK(recording.metadata == expected_metadata);

  REQUIRE(recording.size() == 3);
  CHECK(recording.time_s == std::vector<double>{0.0, 0.002, 0.004});
  CHECK(recording.force_N == std::vector<double>{1.5, 2.0, 3.0});
  REQUIRE(recording.angle_rad.has_value());
  CHECK(*recording.angle_rad == std::vector<double>{0.1, 0.1, 0.2});
  REQUIRE(recording.rate_rad_s.has_value());
  CHECK(*recording.rate_rad_s == std::vector<double>{0.0, -0.25, 0.5});
  REQUIRE(recording.stroke.has_value());
  CHECK(*recording.stroke == std::vector<int>{0, 1, 1});
  CHECK(recording.extra_names == std::vector<std::string>{"pot_V"});
  REQUIRE(recording.extra_columns.size() == 1);
  CHECK(recording.extra_columns[0] == std::vector<double>{2.5, 2.75, 3.0});
  CHECK(recording.line_numbers == std::vector<int>{7, 8, 10});
}

TEST_CASE("optional columns may be absent", "[csv]") {
  const Recording recording = parse("time_s,force_N,rate_rad_s\n0,1,2\n");
  CHECK_FALSE(recording.angle_rad.has_value());
  CHECK_FALSE(recording.stroke.has_value());
  CHECK_FALSE(recording.handle_radius_m.has_value());
  CHECK_FALSE(recording.sample_rate_hz.has_value());
  CHECK(recording.extra_names.empty());
  CHECK(recording.metadata.empty());
  REQUIRE(recording.rate_rad_s.has_value());
  CHECK(*recording.rate_rad_s == std::vector<double>{2.0});
}

TEST_CASE("the generic table keeps names, metadata and line numbers", "[csv]") {
  const CsvTable table = parse_csv_table(
      "\xEF\xBB\xBF# a: 1\n# http-ish note without key value\n#\n x , y\n1,2\n\n3 ,\t4\n", "t.csv");
  CHECK(table.column_names == std::vector<std::string>{"x", "y"});
  CHECK(table.header_line == 4);
  CHECK(table.row_count() == 2);
  CHECK(table.line_numbers == std::vector<int>{5, 7});
  CHECK(table.columns[0] == std::vector<double>{1.0, 3.0});
  CHECK(table.columns[1] == std::vector<double>{2.0, 4.0});
  CHECK(table.find_column("y") == std::optional<std::size_t>(1));
  CHECK_FALSE(table.find_column("z").has_value());
  CHECK(table.metadata_value("a") == std::optional<std::string>("1"));
  CHECK_FALSE(table.metadata_value("b").has_value());
  CHECK_THROWS_AS(table.metadata_value(""), std::invalid_argument);
  const CsvMetadata expected{{"a", "1"}, {"", "http-ish note without key value"}, {"", ""}};
  CHECK(table.metadata == expected);
  CHECK(table.metadata_line_numbers == std::vector<int>{1, 2, 3});
}

TEST_CASE("a header without data rows is a valid table but not a recording", "[csv]") {
  CHECK(parse_csv_table("x,y\n", "t.csv").row_count() == 0);
  REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad\n\n"),
                      "run.csv: no data rows after the header");
}

TEST_CASE("CRLF line endings read like LF", "[csv]") {
  const std::string text =
      "# handle_radius_m: 0.3\r\n"
      "time_s,force_N,angle_rad,stroke\r\n"
      "0,1,0.5,0\r\n"
      "\r\n"
      "0.1,2,0.75,3\r\n";
  const Recording recording = parse(text);
  CHECK(*recording.handle_radius_m == 0.3);
  CHECK(recording.time_s == std::vector<double>{0.0, 0.1});
  CHECK(recording.force_N == std::vector<double>{1.0, 2.0});
  CHECK(*recording.stroke == std::vector<int>{0, 3});
  CHECK(recording.line_numbers == std::vector<int>{3, 5});
  // Errors on CRLF input count lines the same way.
  REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad\r\n0,1,2\r\n1,x,2\r\n"),
                      "run.csv:3: column force_N: 'x' is not a number");
}

TEST_CASE("numbers round-trip exactly", "[csv]") {
  const std::vector<double> values{0.1,
                                   1e-300,
                                   -2.5e17,
                                   1.0 / 3.0,
                                   -0.0,
                                   5e-324,
                                   std::numeric_limits<double>::max(),
                                   -std::numeric_limits<double>::min(),
                                   123456789.123456789,
                                   std::numbers::pi};
  for (const double value : values) {
    const std::string text = format_csv_number(value);
    const auto parsed = parse_csv_number(text);
    REQUIRE(parsed.has_value());
    CHECK(same_double(*parsed, value));
  }
  CHECK(format_csv_number(0.1) == "0.1");
  CHECK(format_csv_number(-2.5e17) == "-2.5e+17");
  CHECK(format_csv_number(3.0) == "3");
  CHECK_THROWS_AS(format_csv_number(std::nan("")), std::invalid_argument);
  CHECK_THROWS_AS(format_csv_number(INFINITY), std::invalid_argument);

  // Through a whole table as well.
  std::ostringstream out;
  const std::vector<double> times{0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0};
  write_csv(out, {{"k", "v"}}, {"t_s", "x_V"}, {&times, &values});
  const CsvTable table = parse_csv_table(out.str(), "out");
  REQUIRE(table.row_count() == values.size());
  for (std::size_t row = 0; row < values.size(); ++row) {
    CHECK(same_double(table.columns[1][row], values[row]));
  }
  CHECK(table.metadata == CsvMetadata{{"k", "v"}});
}

TEST_CASE("a recording round-trips through text", "[csv]") {
  Recording recording = small_recording();
  recording.time_s = {0.1, 0.2, 0.30000000000000004};
  recording.force_N = {1e-300, -2.5e17, -0.0};
  recording.rate_rad_s = std::vector<double>{1.0 / 3.0, 2.0 / 3.0, 1.0};

  std::ostringstream out;
  write_recording_csv(out, recording);
  const std::string text = out.str();
  CHECK(text.rfind("# handle_radius_m: 0.32\n"
                   "# sample_rate_hz: 1000\n"
                   "# source: simulator\n"
                   "# free-form note\n"
                   "time_s,force_N,angle_rad,rate_rad_s,stroke,tau_Nm,tau_u_Nm\n"
                   "0.1,1e-300,0,0.3333333333333333,0,0.1,-0.1\n",
                   0) == 0);

  const Recording back = parse_recording_csv(text, "mem");
  CHECK(back.handle_radius_m == recording.handle_radius_m);
  CHECK(back.sample_rate_hz == recording.sample_rate_hz);
  CHECK(back.metadata == recording.metadata);
  CHECK(back.time_s == recording.time_s);
  CHECK(back.force_N == recording.force_N);
  CHECK(std::signbit(back.force_N[2]));
  CHECK(back.angle_rad == recording.angle_rad);
  CHECK(back.rate_rad_s == recording.rate_rad_s);
  CHECK(back.stroke == recording.stroke);
  CHECK(back.extra_names == recording.extra_names);
  CHECK(back.extra_columns == recording.extra_columns);
  CHECK(back.line_numbers == std::vector<int>{6, 7, 8});
}

TEST_CASE("table format errors name the source and line", "[csv][errors]") {
  SECTION("field count") {
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad\n0,1,2\n0.1,1\n"),
                        "run.csv:3: expected 3 fields, found 2");
    // A decimal comma shows up as a field-count error.
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad\n0,1,5,2\n"),
                        "run.csv:2: expected 3 fields, found 4");
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad\n0,1,2,\n"),
                        "run.csv:2: expected 3 fields, found 4");
  }
  SECTION("bad row after metadata and blank lines") {
    const std::string text =
        "# source: spreadsheet\n"
        "\n"
        "# handle_radius_m: 0.3\n"
        "time_s,force_N,angle_rad\n"
        "0,1,2\n"
        "\n"
        "0.1,abc,2\n";
    REQUIRE_THROWS_WITH(parse(text), "run.csv:7: column force_N: 'abc' is not a number");
  }
  SECTION("cells") {
    const std::string header = "time_s,force_N,angle_rad\n0,1,2\n";
    REQUIRE_THROWS_WITH(parse(header + "1,,2\n"), "run.csv:3: column force_N: empty cell");
    REQUIRE_THROWS_WITH(parse(header + "1,  ,2\n"), "run.csv:3: column force_N: empty cell");
    REQUIRE_THROWS_WITH(parse(header + "1,2,nan\n"),
                        "run.csv:3: column angle_rad: 'nan' is not a finite number");
    REQUIRE_THROWS_WITH(parse(header + "1,-inf,2\n"),
                        "run.csv:3: column force_N: '-inf' is not a finite number");
    REQUIRE_THROWS_WITH(parse(header + "1,1e400,2\n"),
                        "run.csv:3: column force_N: '1e400' is out of range for a double");
    REQUIRE_THROWS_WITH(parse(header + "1,2 3,2\n"),
                        "run.csv:3: column force_N: '2 3' is not a number");
    REQUIRE_THROWS_WITH(parse(header + "1,0x10,2\n"),
                        "run.csv:3: column force_N: '0x10' is not a number");
    REQUIRE_THROWS_WITH(parse(header + "1,\"2\",2\n"),
                        "run.csv:3: column force_N: '\"2\"' is not a number");
    REQUIRE_THROWS_WITH(parse(header + "1,+-2,2\n"),
                        "run.csv:3: column force_N: '+-2' is not a number");
  }
  SECTION("header") {
    REQUIRE_THROWS_WITH(parse("# a: 1\ntime_s,force_N,time_s\n"),
                        "run.csv:2: duplicate column name 'time_s'");
    REQUIRE_THROWS_WITH(parse("time_s,,force_N\n"), "run.csv:1: column 2 name '' is empty");
    REQUIRE_THROWS_WITH(parse("0,1,2\n"),
                        "run.csv:1: column 1 name '0' is a number (is the header row missing?)");
    REQUIRE_THROWS_WITH(parse("time_s;force_N;angle_rad\n"),
                        "run.csv:1: column 1 name 'time_s;force_N;angle_rad' contains ';' or a "
                        "tab (fields must be separated by commas; doorbench import reads other "
                        "separators with --separator)");
    REQUIRE_THROWS_WITH(
        parse("\"time_s\",force_N\n"),
        "run.csv:1: column 1 name '\"time_s\"' contains '\"' (quoted fields are not supported)");
  }
  SECTION("no header") {
    REQUIRE_THROWS_WITH(parse(""), "run.csv: no header row");
    REQUIRE_THROWS_WITH(parse("# source: x\n\n"), "run.csv: no header row");
  }
  SECTION("metadata") {
    REQUIRE_THROWS_WITH(parse("# source: a\n# source: b\ntime_s,force_N,angle_rad\n0,1,2\n"),
                        "run.csv:2: duplicate metadata key 'source' (first on line 1)");
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad\n0,1,2\n# late: 1\n"),
                        "run.csv:3: '#' line after the header (metadata must come before the "
                        "header row)");
  }
  SECTION("control characters in metadata and names") {
    // A NUL would cut the value where the session stores it ("Ann"): refused where it is.
    const std::string nul = std::string("# source: x\n# operator: Ann") + '\0' +
                            "Bob\ntime_s,force_N,angle_rad\n0,1,2\n";
    REQUIRE_THROWS_WITH(parse(nul),
                        "run.csv:2: control character \\x00 at column 16 of a metadata line "
                        "(metadata is kept as text: remove it from the file)");
    REQUIRE_THROWS_WITH(parse("# note \x1b[2J\ntime_s,force_N,angle_rad\n0,1,2\n"),
                        "run.csv:1: control character \\e at column 8 of a metadata line "
                        "(metadata is kept as text: remove it from the file)");
    REQUIRE_THROWS_WITH(parse("time_s,force\x01N,angle_rad\n0,1,2\n"),
                        "run.csv:1: column 2 name 'force\\x01N' contains the control "
                        "character \\x01");
    // A tab is a blank, not a control character.
    const Recording tabbed = parse("# operator:\tAnn\ntime_s,force_N,angle_rad\n0,1,2\n");
    REQUIRE(tabbed.metadata.size() == 1);
    CHECK(tabbed.metadata[0].second == "Ann");
  }
  SECTION("stray carriage return") {
    REQUIRE_THROWS_WITH(
        parse("time_s,force_N,angle_rad\r0,1,2\r"),
        "run.csv:1: carriage return inside the line (line endings must be \\n or \\r\\n)");
  }
}

// The dialects of CSV files from elsewhere: a spreadsheet's semicolons with decimal commas,
// LabVIEW's tabs. Each reads as the same table in the exchange format does, and a file read in
// the wrong dialect is refused with a hint, word for word.
TEST_CASE("CSV dialects: semicolons with decimal commas, and tabs", "[csv][errors]") {
  using doorbench::CsvDialect;
  using doorbench::parse_csv_table;
  const CsvDialect semicolon{';', true, ""}, tab{'\t', false, ""};
  const doorbench::CsvTable comma_table =
      parse_csv_table("# a: 1,5\nTime (s),Force (N)\n0,1.5\n0.001,-2.25e-3\n", "run.csv");
  const doorbench::CsvTable semicolon_table =
      parse_csv_table("# a: 1,5\r\nTime (s);Force (N)\r\n0;1,5\r\n0,001 ; -2,25e-3\r\n", "run.csv",
                      doorbench::EmptyCells::kRefuse, semicolon);
  const doorbench::CsvTable tab_table =
      parse_csv_table("# a: 1,5\nTime (s)\tForce (N)\n0\t1.5\n0.001\t-2.25e-3\n", "run.csv",
                      doorbench::EmptyCells::kRefuse, tab);
  for (const doorbench::CsvTable* table : {&semicolon_table, &tab_table}) {
    CHECK(table->column_names == comma_table.column_names);
    CHECK(table->columns == comma_table.columns);
    CHECK(table->metadata == comma_table.metadata);
    CHECK(table->line_numbers == comma_table.line_numbers);
  }
  // A missing sample is an empty cell in any dialect.
  const doorbench::CsvTable missing =
      parse_csv_table("t_s;f_N\n0;\n", "run.csv", doorbench::EmptyCells::kMissing, semicolon);
  CHECK(std::isnan(missing.columns[1][0]));
  REQUIRE_THROWS_WITH(
      parse_csv_table("t_s;f_N\n0;1.234,5\n", "run.csv", doorbench::EmptyCells::kRefuse, semicolon),
      "run.csv:2: column f_N: '1.234,5' holds a '.' (with --decimal-comma the decimal point is "
      "',', and thousands separators are not read)");
  REQUIRE_THROWS_WITH(parse_csv_table("t_s;f_N\n0;1,5\n", "run.csv", doorbench::EmptyCells::kRefuse,
                                      CsvDialect{';', false, ""}),
                      "run.csv:2: column f_N: '1,5' is not a number (a decimal comma? give "
                      "--decimal-comma)");
  REQUIRE_THROWS_WITH(
      parse_csv_table("t_s\tf_N\n0\t1\n", "run.csv", doorbench::EmptyCells::kRefuse, semicolon),
      "run.csv:1: column 1 name 't_s\\tf_N' contains a tab (fields are separated by ';' here, as "
      "--separator says)");
  REQUIRE_THROWS_WITH(
      parse_csv_table("t_s;f_N\n0;1\n", "run.csv", doorbench::EmptyCells::kRefuse, tab),
      "run.csv:1: column 1 name 't_s;f_N' contains ';' (fields are separated by a tab here, as "
      "--separator says)");
  REQUIRE_THROWS_WITH(parse_csv_table("t_s,f_N\n", "run.csv", doorbench::EmptyCells::kRefuse,
                                      CsvDialect{',', true, ""}),
                      "--decimal-comma needs --separator semicolon or tab (a comma cannot both "
                      "separate fields and mark decimals)");
}

TEST_CASE("recording rule errors name the source and line", "[csv][errors]") {
  SECTION("required columns, reported at the header's line") {
    REQUIRE_THROWS_WITH(parse("# a: 1\n\ntime_s,angle_rad\n0,1\n"),
                        "run.csv:3: header lacks required column force_N");
    REQUIRE_THROWS_WITH(parse("force_N,angle_rad\n0,1\n"),
                        "run.csv:1: header lacks required column time_s");
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_deg\n0,1,2\n"),
                        "run.csv:1: header has neither angle_rad nor rate_rad_s");
  }
  SECTION("time_s strictly increasing") {
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad\n0,1,2\n0.5,1,2\n\n0.5,1,2\n"),
                        "run.csv:5: time_s 0.5 is not after the previous row's 0.5");
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad\n0,1,2\n-0.25,1,2\n"),
                        "run.csv:3: time_s -0.25 is not after the previous row's 0");
  }
  SECTION("stroke ids") {
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad,stroke\n0,1,2,0\n1,1,2,1.5\n"),
                        "run.csv:3: stroke 1.5 is not a non-negative integer");
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad,stroke\n0,1,2,-1\n"),
                        "run.csv:2: stroke -1 is not a non-negative integer");
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad,stroke\n0,1,2,1e10\n"),
                        "run.csv:2: stroke 1e+10 is not a non-negative integer");
  }
  SECTION("unit suffix of extra columns") {
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad,foo\n0,1,2,3\n"),
                        "run.csv:1: column 'foo' has no unit suffix (e.g. foo_V)");
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad,foo_\n0,1,2,3\n"),
                        "run.csv:1: column 'foo_' has no unit suffix (e.g. foo_V)");
    REQUIRE_THROWS_WITH(parse("time_s,force_N,angle_rad,_V\n0,1,2,3\n"),
                        "run.csv:1: column '_V' has no unit suffix (e.g. _V_V)");
  }
  SECTION("typed metadata") {
    const std::string body = "time_s,force_N,angle_rad\n0,1,2\n";
    REQUIRE_THROWS_WITH(parse("# source: x\n# handle_radius_m: x\n" + body),
                        "run.csv:2: metadata handle_radius_m: 'x' is not a positive number");
    REQUIRE_THROWS_WITH(parse("# handle_radius_m: 0\n" + body),
                        "run.csv:1: metadata handle_radius_m: '0' is not a positive number");
    REQUIRE_THROWS_WITH(parse("# handle_radius_m: 0.3 m\n" + body),
                        "run.csv:1: metadata handle_radius_m: '0.3 m' is not a positive number");
    REQUIRE_THROWS_WITH(parse("\n# sample_rate_hz: -1000\n" + body),
                        "run.csv:2: metadata sample_rate_hz: '-1000' is not a positive number");
    REQUIRE_THROWS_WITH(parse("# sample_rate_hz:\n" + body),
                        "run.csv:1: metadata sample_rate_hz: '' is not a positive number");
  }
}

TEST_CASE("CsvError carries its parts", "[csv][errors]") {
  try {
    parse("time_s,force_N,angle_rad\n0,1\n");
    FAIL("no exception");
  } catch (const CsvError& error) {
    CHECK(error.source() == "run.csv");
    CHECK(error.line() == 2);
    CHECK(error.detail() == "expected 3 fields, found 2");
  }
  const CsvError without_line("a.csv", 0, "no header row");
  CHECK(std::string(without_line.what()) == "a.csv: no header row");
  CHECK(without_line.line() == 0);
}

TEST_CASE("files on disk", "[csv][file]") {
  SECTION("read a file") {
    const TemporaryFile file("doorbench-test-csv");
    file.write("# handle_radius_m: 0.25\ntime_s,force_N,rate_rad_s\n0,1,2\n0.5,3,4\n");
    const Recording recording = read_recording_csv(file.path());
    CHECK(recording.source == file.path().string());
    CHECK(*recording.handle_radius_m == 0.25);
    CHECK(recording.time_s == std::vector<double>{0.0, 0.5});
    CHECK(*recording.rate_rad_s == std::vector<double>{2.0, 4.0});
    CHECK(read_csv_file(file.path()).row_count() == 2);
  }
  SECTION("errors name the path") {
    const TemporaryFile file("doorbench-test-csv");
    file.write("time_s,force_N,rate_rad_s\n0,1,2\n0,3,4\n");
    REQUIRE_THROWS_WITH(read_recording_csv(file.path()),
                        file.path().string() + ":3: time_s 0 is not after the previous row's 0");
  }
  SECTION("write then read") {
    const TemporaryFile file("doorbench-test-csv");
    const Recording recording = small_recording();
    write_recording_csv_file(file.path(), recording);
    const Recording back = read_recording_csv(file.path());
    CHECK(back.time_s == recording.time_s);
    CHECK(back.extra_columns == recording.extra_columns);
    CHECK(back.metadata == recording.metadata);
  }
  SECTION("missing file") {
    const std::filesystem::path missing =
        std::filesystem::temp_directory_path() / "doorbench-no-such-dir" / "missing.csv";
    REQUIRE_THROWS_WITH(read_recording_csv(missing),
                        missing.string() + ": cannot open for reading");
    REQUIRE_THROWS_WITH(read_csv_file(missing), missing.string() + ": cannot open for reading");
    REQUIRE_THROWS_WITH(write_recording_csv_file(missing, small_recording()),
                        missing.string() + ": cannot write: No such file or directory");
  }
  SECTION("a directory") {
    const auto directory = std::filesystem::temp_directory_path();
    REQUIRE_THROWS_WITH(read_csv_file(directory),
                        directory.string() + ": is a directory, not a file");
  }
}

TEST_CASE("writers reject what could not be read back", "[csv][write]") {
  std::ostringstream out;
  const std::vector<double> a{1.0, 2.0}, b{3.0}, bad{1.0, NAN};
  CHECK_THROWS_AS(write_csv(out, {}, {"a_V", "b_V"}, {&a, &b}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {}, {"a_V"}, {&a, &a}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {}, {"a_V"}, {nullptr}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {}, {}, {}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {}, {"a_V"}, {&bad}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {}, {"a,b"}, {&a}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {}, {" a"}, {&a}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {}, {"#a"}, {&a}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {}, {"a", "a"}, {&a, &a}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {{"bad key", "v"}}, {"a"}, {&a}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {{"k", "two\nlines"}}, {"a"}, {&a}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {{"k", "1"}, {"k", "2"}}, {"a"}, {&a}), std::invalid_argument);
  CHECK_THROWS_AS(write_csv(out, {{"", "key: value"}}, {"a"}, {&a}), std::invalid_argument);
  CHECK(out.str().empty());  // nothing written by a rejected call
  REQUIRE_THROWS_WITH(write_csv(out, {}, {"a_V", "b_V"}, {&a, &b}),
                      "write_csv: column 'b_V' has 1 values, column 'a_V' has 2");

  auto rejects = [](const Recording& recording) {
    std::ostringstream sink;
    CHECK_THROWS_AS(write_recording_csv(sink, recording), std::invalid_argument);
  };
  Recording recording = small_recording();
  recording.time_s[2] = recording.time_s[1];
  rejects(recording);
  recording = small_recording();
  recording.force_N.pop_back();
  rejects(recording);
  recording = small_recording();
  recording.angle_rad.reset();
  rejects(recording);
  recording = small_recording();
  (*recording.stroke)[0] = -1;
  rejects(recording);
  recording = small_recording();
  recording.extra_names[0] = "tau";
  rejects(recording);
  recording = small_recording();
  recording.extra_names[0] = "force_N";
  rejects(recording);
  recording = small_recording();
  recording.extra_columns.pop_back();
  rejects(recording);
  recording = small_recording();
  recording.metadata.emplace_back("handle_radius_m", "0.3");
  rejects(recording);
  recording = small_recording();
  recording.handle_radius_m = 0.0;
  rejects(recording);
  recording = small_recording();
  recording.force_N[1] = INFINITY;
  rejects(recording);
  rejects(Recording{});
}

TEST_CASE("a large table parses completely", "[csv]") {
  constexpr int kRows = 20000;
  std::vector<std::vector<double>> columns(10, std::vector<double>(kRows));
  std::vector<std::string> names;
  for (int c = 0; c < 10; ++c) {
    names.push_back("ch" + std::to_string(c) + "_V");
    for (int row = 0; row < kRows; ++row) columns[c][row] = std::sin(0.001 * row + c) * 1e3;
  }
  std::vector<const std::vector<double>*> pointers;
  for (const auto& column : columns) pointers.push_back(&column);
  std::ostringstream out;
  write_csv(out, {}, names, pointers);
  const CsvTable table = parse_csv_table(out.str(), "big");
  REQUIRE(table.row_count() == kRows);
  CHECK(table.columns == columns);
  CHECK(table.line_numbers.back() == kRows + 1);
}

TEST_CASE("a parsed table writes back to the same table", "[csv][write]") {
  const CsvTable table = parse_csv_table("# k: v\n# note\nb_V,a_deg\n0.1,2\n-3e-5,4\n", "t.csv");
  std::ostringstream out;
  write_csv(out, table);
  CHECK(out.str() == "# k: v\n# note\nb_V,a_deg\n0.1,2\n-3e-05,4\n");
  const CsvTable back = parse_csv_table(out.str(), "back");
  CHECK(back.metadata == table.metadata);
  CHECK(back.column_names == table.column_names);
  CHECK(back.columns == table.columns);
}

TEST_CASE("unit suffixes", "[csv]") {
  CHECK(has_unit_suffix("tau_Nm"));
  CHECK(has_unit_suffix("tau_u_Nm"));
  CHECK(has_unit_suffix("pot_V"));
  CHECK_FALSE(has_unit_suffix("foo"));
  CHECK_FALSE(has_unit_suffix("foo_"));
  CHECK_FALSE(has_unit_suffix("_V"));
  CHECK_FALSE(has_unit_suffix(""));
}

// A door's recording in degrees, deg/s or milliseconds read as radians, rad/s or seconds is
// told by its physical values, word for word; a column a record converts is judged after it.
TEST_CASE("units in doubt: an angle beyond a turn, a rate beyond two turns a second, a slow clock",
          "[csv][errors]") {
  Recording door;
  for (int i = 0; i <= 100; ++i) {
    const double t_s = 0.01 * i;
    door.time_s.push_back(t_s);
    door.force_N.push_back(1.0);
    door.angle_rad = door.angle_rad.value_or(std::vector<double>{});
    door.angle_rad->push_back(1.5 * t_s);  // 0 to 1.5 rad: a door
    door.rate_rad_s = door.rate_rad_s.value_or(std::vector<double>{});
    door.rate_rad_s->push_back(i == 50 ? std::nan("") : 1.5);
  }
  CHECK(unit_doubts(door).empty());

  Recording degrees = door;
  for (double& angle : *degrees.angle_rad) angle /= kRadPerDeg;  // 0 to 85.94
  for (double& rate : *degrees.rate_rad_s) rate = -rate / kRadPerDeg;
  for (double& t : degrees.time_s) t *= 1000.0;
  const std::vector<std::string> doubts = unit_doubts(degrees);
  REQUIRE(doubts.size() == 3);
  CHECK(doubts[0] ==
        "angle_rad spans 0 to 85.94 rad, more than a turn: an angle in degrees read as radians? "
        "(import converts it: --scale angle=" +
            format_significant(kRadPerDeg, 6) +
            ", or a --map column whose name ends in "
            "(deg))");
  CHECK(doubts[1] ==
        "|rate_rad_s| reaches 85.94 rad/s, more than two turns a second: a rate in deg/s read as "
        "rad/s? (import converts it: --scale rate=" +
            format_significant(kRadPerDeg, 6) +
            ", or a --map column whose name ends "
            "in (deg/s))");
  CHECK(doubts[2] ==
        "time_s steps 10 s from sample to sample (the median), too slow to follow a door: a "
        "time in ms read as seconds? (import converts a --map time column whose name ends in "
        "(ms))");

  // The same degrees through the records that make them radians: no doubt left.
  Recording converted = degrees;
  converted.time_s = door.time_s;
  converted.calibrations["angle_rad"] =
      linear_record("unit-angle", "deg", "rad", kRadPerDeg, 0.0, "unit");
  converted.calibrations["rate_rad_s"] =
      linear_record("unit-rate", "deg/s", "rad/s", kRadPerDeg, 0.0, "unit");
  CHECK(unit_doubts(converted).empty());

  // Just inside each limit.
  Recording edge = door;
  (*edge.angle_rad)[7] = -0.5;
  (*edge.angle_rad)[9] = kAngleSpanMaxRad - 0.5;
  (*edge.rate_rad_s)[3] = -kRateMaxRadPerS;
  CHECK(unit_doubts(edge).empty());
  (*edge.rate_rad_s)[3] = -1.001 * kRateMaxRadPerS;
  CHECK(unit_doubts(edge).size() == 1);
}
