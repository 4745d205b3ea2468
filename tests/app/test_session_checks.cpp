// A session is checked as a whole when `info` reads it: a channel cut short, a
// calibration record that is missing and times that go backwards are each named on a
// "problem:" line, and a session that cannot be used as it is ends with exit status 1.
// The damage is done with h5py (Debian's python3-h5py), as a file from elsewhere would be.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

namespace {

using doorbench::testing::DoorbenchRun;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

void h5py(const std::string& script, const TempDir& dir) {
  const auto file = dir.write("edit.py", "import h5py\n" + script + "\n");
  REQUIRE(std::system(("/usr/bin/python3 '" + file.string() + "'").c_str()) == 0);
}

// The lines of `text` that start with `prefix`, joined.
std::string lines_starting(const std::string& text, const std::string& prefix) {
  std::string found;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    if (text.compare(start, prefix.size(), prefix) == 0) {
      found += text.substr(start, end - start) + "\n";
    }
    start = end + 1;
  }
  return found;
}

}  // namespace

TEST_CASE("Session checks: info names a channel cut short and a missing calibration record",
          "[session][cli]") {
  const TempDir dir("session_checks");
  const auto session = dir / "s.h5";
  REQUIRE(doorbench::testing::record_built_in_session(session, 2.0, 3, "sensory") == 2000);
  const DoorbenchRun whole = run_doorbench_shell("info '" + session.string() + "'", dir);
  REQUIRE(whole.status == 0);
  CHECK(lines_starting(whole.out, "problem:").empty());

  // The force channel cut to half its length (1000 of 2000 samples at 1 kHz); the rate
  // channel, sampled 20 us after the force in each scan, ends last.
  h5py("f = h5py.File('" + session.string() +
           "', 'r+')\n"
           "raw = f['channels/force/raw'][:1000]\n"
           "attrs = dict(f['channels/force/raw'].attrs)\n"
           "del f['channels/force/raw']\n"
           "d = f['channels/force'].create_dataset('raw', data=raw)\n"
           "for k, v in attrs.items(): d.attrs[k] = v\n"
           "f.close()",
       dir);
  const DoorbenchRun cut = run_doorbench_shell("info '" + session.string() + "'", dir);
  CHECK(cut.status == 0);  // usable: export leaves cells empty, fit uses the common time
  CHECK(lines_starting(cut.out, "problem:") ==
        "problem: channel force has 1000 samples and ends at 1 s, 1.00002 s before rate (export "
        "leaves its cells empty from there; fit uses only the time where every channel has "
        "samples)\n");

  // And the force's calibration record removed.
  h5py("f = h5py.File('" + session.string() +
           "', 'r+')\n"
           "del f['calibrations/' + f['channels/force'].attrs['calibration_id']]\n"
           "f.close()",
       dir);
  const DoorbenchRun missing = run_doorbench_shell("info '" + session.string() + "'", dir);
  CHECK(missing.status == 1);
  CHECK(lines_starting(missing.out, "problem:") ==
        "problem: channel force uses calibration record nominal-SIM-LC445-0001, which is not in "
        "the session: its values cannot be calibrated (export and fit refuse the session)\n"
        "problem: channel force has 1000 samples and ends at 1 s, 1.00002 s before rate (export "
        "leaves its cells empty from there; fit uses only the time where every channel has "
        "samples)\n");
  CHECK(missing.err ==
        "doorbench: " + session.string() + ": cannot be used as it is (1 problem above)\n");
}

// A channel cut short (never the common rows alone without a word, by `export` or `fit`):
// export goes on to the longest channel's end with the short
// channel's cells empty and says so; fit and loop warn that only the time every channel
// covers is fitted, on stderr and in report.md.
TEST_CASE("Session checks: export leaves a channel cut short empty, fit says what it fits",
          "[session][cli]") {
  const TempDir dir("session_cut_short");
  const auto session = dir / "s.h5";
  REQUIRE(doorbench::testing::record_built_in_session(session, 6.0, 3, "sensory") == 6000);
  h5py("f = h5py.File('" + session.string() +
           "', 'r+')\n"
           "raw = f['channels/force/raw'][:3000]\n"
           "attrs = dict(f['channels/force/raw'].attrs)\n"
           "del f['channels/force/raw']\n"
           "d = f['channels/force'].create_dataset('raw', data=raw)\n"
           "for k, v in attrs.items(): d.attrs[k] = v\n"
           "f.close()",
       dir);

  const auto csv = dir / "s.csv";
  const DoorbenchRun exported =
      run_doorbench_shell("export '" + session.string() + "' --csv '" + csv.string() + "'", dir);
  CHECK(exported.status == 0);
  CHECK(exported.err == "wrote " + csv.string() +
                            ": 6000 rows; cells left empty where a channel ends early: force "
                            "from 3 s (3000 of 6000 rows)\n");
  std::ifstream in(csv);
  std::string line;
  std::vector<std::string> rows;
  bool metadata_says = false;
  while (std::getline(in, line)) {
    if (line == "# cut_short: force from 3 s (3000 of 6000 rows)") metadata_says = true;
    if (!line.empty() && line[0] != '#') rows.push_back(line);
  }
  CHECK(metadata_says);
  REQUIRE(rows.size() == 6001);  // the header and every scan
  CHECK(rows[0] == "time_s,force_N,rate_rad_s,stroke,inclinometer_angle_rad");
  const auto force_cell = [](const std::string& row) {
    const std::size_t first = row.find(',');
    return row.substr(first + 1, row.find(',', first + 1) - first - 1);
  };
  CHECK_FALSE(force_cell(rows[3000]).empty());  // the force's last sample, at 2.999 s
  CHECK(rows[3001].rfind("3,,", 0) == 0);       // 3 s: the force's cell empty, the rest kept
  CHECK(force_cell(rows[6000]).empty());
  CHECK_FALSE(rows[6000].ends_with(","));

  const auto out = dir / "fit";
  const DoorbenchRun fit =
      run_doorbench_shell("fit '" + session.string() + "' --out '" + out.string() + "'", dir);
  const std::string warning =
      "warning: a channel ends before the others: force from 3 s (3000 of 6000 rows); only the "
      "time where every channel has samples is fitted";
  CHECK(lines_starting(fit.err, "warning: a channel") == warning + "\n");
  REQUIRE(fit.status == 0);
  std::ifstream report_file(out / "report.md");
  std::stringstream report;
  report << report_file.rdbuf();
  CHECK_THAT(report.str(), Catch::Contains("\n\n" + warning + ".\n\n"));
}

// The calibration record a channel names, missing: info names it (above), export and fit
// refuse the session with the same words (exit 1), before writing anything.
TEST_CASE(
    "Session checks: export and fit refuse a session whose calibration record is "
    "missing, word for word",
    "[session][cli]") {
  const TempDir dir("session_missing_record");
  const auto session = dir / "s.h5";
  REQUIRE(doorbench::testing::record_built_in_session(session, 2.0, 3, "sensory") == 2000);
  h5py("f = h5py.File('" + session.string() +
           "', 'r+')\n"
           "del f['calibrations/' + f['channels/force'].attrs['calibration_id']]\n"
           "f.close()",
       dir);
  const std::string refusal = "doorbench: " + session.string() +
                              ": channel force uses calibration record nominal-SIM-LC445-0001, "
                              "which is not in the session\n";
  const auto csv = dir / "s.csv";
  const DoorbenchRun exported =
      run_doorbench_shell("export '" + session.string() + "' --csv '" + csv.string() + "'", dir);
  CHECK(exported.status == 1);
  CHECK(exported.err == refusal);
  CHECK_FALSE(std::filesystem::exists(csv));
  const auto out = dir / "fit";
  const DoorbenchRun fit =
      run_doorbench_shell("fit '" + session.string() + "' --out '" + out.string() + "'", dir);
  CHECK(fit.status == 1);
  CHECK(fit.err == "preparing " + session.string() + "\n" + refusal);
  CHECK_FALSE(std::filesystem::exists(out / "result.json"));
}
