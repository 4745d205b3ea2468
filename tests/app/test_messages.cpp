// Messages name their file, and text from files reaches the terminal escaped. Sessions with broken
// times or names are made with h5py (Debian's python3-h5py), as a file from elsewhere would be.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "acquisition/session/printable.h"
#include "fixtures/temp_dir.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"

using doorbench::testing::read_file;

namespace {

using doorbench::testing::DoorbenchRun;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

// A session imported from a CSV whose times are not on a clock (explicit times).
std::filesystem::path imported_session(const TempDir& dir, const std::string& notes = "") {
  std::string csv = "time_s,force_N,rate_rad_s\n";
  for (int i = 0; i < 40; ++i) csv += std::to_string(0.01 * i + (i % 3) * 1e-4) + ",1,0\n";
  const auto csv_path = dir.write("in.csv", csv);
  const auto session = dir / "s.h5";
  const std::string args = "import " + csv_path.string() + " --out " + session.string() +
                           (notes.empty() ? "" : " --notes \"$(printf '" + notes + "')\"");
  const DoorbenchRun run = run_doorbench_shell(args, dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  return session;
}

// The last line of a command's stderr (fit says "preparing PATH" first).
std::string last_line(const std::string& text) {
  const auto end = text.size() > 0 && text.back() == '\n' ? text.size() - 1 : text.size();
  const auto start = text.rfind('\n', end > 0 ? end - 1 : 0);
  return text.substr(start == std::string::npos ? 0 : start + 1);
}

void h5py(const std::string& script, const TempDir& dir) {
  const auto file = dir.write("edit.py", "import h5py\n" + script + "\n");
  REQUIRE(std::system(("/usr/bin/python3 '" + file.string() + "'").c_str()) == 0);
}

}  // namespace

TEST_CASE("Messages: printable escapes control characters", "[messages]") {
  CHECK(doorbench::printable("plain text, ünïcode") == "plain text, ünïcode");
  CHECK(doorbench::printable("\x1b[2J\x1b]0;title\x07") == "\\e[2J\\e]0;title\\x07");
  CHECK(doorbench::printable("a\nb\tc\rd\\e\x7f") == "a\\nb\\tc\\rd\\e\\x7f");
  // Escaping twice changes nothing more.
  CHECK(doorbench::printable(doorbench::printable("\x1b[2J")) == "\\e[2J");
}

TEST_CASE("Messages: a parameter file's number beyond a double names file and line",
          "[messages][cli]") {
  const TempDir dir("messages_params");
  std::string text = read_file(DOORBENCH_SOURCE_DIR "/analysis/data/reference-door.json");
  const std::string before = "\"value\": 0.95,";
  const auto at = text.find(before);
  REQUIRE(at != std::string::npos);
  text.replace(at, before.size(), "\"value\": 1e999,");
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
  const auto params = dir.write("p.json", text);
  const DoorbenchRun run =
      run_doorbench_shell("simulate --model sensory --params " + params.string() +
                              " --hand open-close --duration-s 1 --out " + (dir / "r.csv").string(),
                          dir);
  CHECK(run.status == 1);
  CHECK(run.err == "doorbench: " + params.string() + ": line " + std::to_string(line) +
                       ": number overflow parsing '1e999' (beyond the range of a double)\n");
}

TEST_CASE("Messages: fit on a .h5 file that is not HDF5 says so", "[messages][cli]") {
  const TempDir dir("messages_not_hdf5");
  const auto fake = dir.write("random.h5", "time_s,force_N\n0,1,2\n");
  const DoorbenchRun run =
      run_doorbench_shell("fit " + fake.string() + " --out " + (dir / "out").string(), dir);
  CHECK(run.status == 1);
  CHECK(last_line(run.err) ==
        "doorbench: " + fake.string() +
            ": not an HDF5 file (a session starts with the HDF5 signature; a CSV "
            "recording is read only under another name)\n");
}

TEST_CASE("Messages: fit on a logger's own CSV names its columns and how to import it",
          "[messages][cli]") {
  const TempDir dir("messages_own_columns");
  dir.write("log.csv", "# operator: P03\nTime (s),Force (N),Angle (rad)\n0,1,0.1\n0.01,1,0.1\n");
  const DoorbenchRun run =
      run_doorbench_shell("fit log.csv --out out", dir, "env -C '" + dir.path.string() + "'");
  CHECK(run.status == 1);
  CHECK(last_line(run.err) ==
        "doorbench: log.csv:2: header lacks required column time_s; the file's columns: Time (s), "
        "Force (N), Angle (rad) (a file with its own column names is read through doorbench "
        "import FILE --map time=COLUMN,force=COLUMN,angle=COLUMN --out SESSION.h5 first: "
        "docs/csv-format.md)\n");
  CHECK_FALSE(std::filesystem::exists(dir / "out"));
}

TEST_CASE("Messages: a session's broken explicit times name the dataset and sample",
          "[messages][cli][session]") {
  const TempDir dir("messages_times");
  const auto session = imported_session(dir);
  h5py("f = h5py.File('" + session.string() +
           "', 'r+')\n"
           "t = f['channels/force/time_s']\n"
           "t[5] = float('nan')\n"
           "f.close()",
       dir);
  const DoorbenchRun run =
      run_doorbench_shell("export " + session.string() + " --csv " + (dir / "x.csv").string(), dir);
  CHECK(run.status == 1);
  CHECK(run.err == "doorbench: " + session.string() +
                       ": /channels/force/time_s: sample 5 (nan s) is not finite; times must be "
                       "finite and increasing\n");
  h5py("f = h5py.File('" + session.string() +
           "', 'r+')\n"
           "t = f['channels/force/time_s']\n"
           "t[5] = 0.02\n"
           "f.close()",
       dir);
  const DoorbenchRun decreasing =
      run_doorbench_shell("export " + session.string() + " --csv " + (dir / "x.csv").string(), dir);
  CHECK(decreasing.status == 1);
  CHECK(decreasing.err == "doorbench: " + session.string() +
                              ": /channels/force/time_s: sample 5 (0.02 s) is not after the one "
                              "before (0.0401 s); times must be finite and increasing\n");
}

TEST_CASE("Messages: control characters from files reach the terminal escaped", "[messages][cli]") {
  const TempDir dir("messages_control");
  SECTION("a CSV cell") {
    const auto csv = dir.write("esc.csv", "time_s,force_N,rate_rad_s\n0,1,0\n0.1,\x1b[2J,0\n");
    const DoorbenchRun run =
        run_doorbench_shell("fit " + csv.string() + " --out " + (dir / "out").string(), dir);
    CHECK(run.status == 1);
    CHECK(run.err.find('\x1b') == std::string::npos);
    CHECK(last_line(run.err) ==
          "doorbench: " + csv.string() + ":3: column force_N: '\\e[2J' is not a number\n");
  }
  SECTION("a session's notes and a channel name") {
    const auto session = imported_session(dir, "\\033]0;owned\\007");
    const DoorbenchRun info = run_doorbench_shell("info " + session.string(), dir);
    INFO(info.err);
    REQUIRE(info.status == 0);
    CHECK(info.out.find('\x1b') == std::string::npos);
    CHECK(info.out.find("  notes      \\e]0;owned\\x07\n") != std::string::npos);
    h5py("f = h5py.File('" + session.string() +
             "', 'r+')\n"
             "f.move('channels/rate', 'channels/r\\x1b[2J')\n"
             "f.close()",
         dir);
    const DoorbenchRun renamed = run_doorbench_shell("info " + session.string(), dir);
    CHECK(renamed.status == 1);
    CHECK(renamed.err == "doorbench: " + session.string() +
                             ": /channels/r\\e[2J: a channel name is letters, digits and _ only\n");
  }
}

TEST_CASE("Messages: a value longer than 80 characters is cut, with its size", "[messages]") {
  const std::string value(10000000, '7');
  const std::string cut = std::string(60, '7') + "... (10000000 characters)";
  CHECK(doorbench::shortened("x.csv:3: 'abc' is not a number") == "x.csv:3: 'abc' is not a number");
  CHECK(doorbench::shortened("x.csv:3: '" + value + "' is not a number") ==
        "x.csv:3: '" + cut + "' is not a number");
  CHECK(doorbench::shortened("name \"" + std::string(81, 'n') + "\" unknown") ==
        "name \"" + std::string(60, 'n') + "... (81 characters)\" unknown");
  CHECK(doorbench::shortened("unquoted " + value + " here") == "unquoted " + cut + " here");
  const std::string path = "/data/" + std::string(200, 'p') + ".csv: cannot open";
  CHECK(doorbench::shortened(path) == path);  // paths are not values
  // An apostrophe inside a word is not a quote: a long message with "file's" and
  // "recording's" between them is left whole (it was cut as a quoted value).
  const std::string english =
      "the door file's handle radius 0.58 m (/work/door/analysis/data/reference-door.json) "
      "differs from the recording's 0.8 m; the file's channels: Door/Force, Door/Angle";
  CHECK(doorbench::shortened(english) == english);
  CHECK(doorbench::shortened("the file's '" + value + "' value") ==
        "the file's '" + cut + "' value");
}

TEST_CASE("Messages: a 10 MB value in a file reaches stderr cut", "[messages][cli]") {
  const TempDir dir("long_value");
  const std::string value(10000000, '7');
  const auto csv = dir.write("long.csv", "# sample_rate_hz: x" + value + "\ntime_s,force_N\n0,1\n");
  const DoorbenchRun run = run_doorbench_shell(
      "import '" + csv.string() + "' --out '" + (dir / "s.h5").string() + "'", dir);
  CHECK(run.status != 0);
  INFO(run.err.substr(0, 400));
  CHECK(run.err.size() < 400);
  CHECK(run.err.find("x" + std::string(59, '7') + "... (10000001 characters)") !=
        std::string::npos);
}
