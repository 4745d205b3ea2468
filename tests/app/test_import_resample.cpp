// import --resample-hz (the way for a recording at a rate the preprocessing cannot use):
// the recording on a uniform clock of the given rate, slower by the mean
// of the samples nearest each new time, faster by linear interpolation, a gap left missing;
// checked through export, word for word.
#include <catch2/catch.hpp>
#include <fstream>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

namespace {

using doorbench::testing::DoorbenchRun;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

// The data rows (no # lines) of a CSV file, each ending in a line break.
std::string data_rows(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line, rows;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') rows += line + "\n";
  }
  return rows;
}

}  // namespace

TEST_CASE("import --resample-hz: the mean over each new interval, or linear interpolation",
          "[cli][import]") {
  const TempDir dir("import_resample");
  // 1 kHz, force = i N and rate = i/4 rad/s at i ms, samples 6 to 11 lost (a gap), stroke 1
  // from 10 ms.
  std::string csv = "# handle_radius_m: 0.5\ntime_s,force_N,rate_rad_s,stroke\n";
  for (int i = 0; i < 20; ++i) {
    if (i > 5 && i < 12) continue;
    csv += std::to_string(i / 1000.0) + "," + std::to_string(i) + "," + std::to_string(i / 4.0) +
           "," + (i >= 10 ? "1" : "0") + "\n";
  }
  const auto source = dir.write("run.csv", csv);
  const auto import_and_export = [&](const std::string& rate) {
    const auto session = dir / ("run-" + rate + ".h5");
    const DoorbenchRun imported =
        run_doorbench_shell("import '" + source.string() + "' --resample-hz " + rate + " --out '" +
                                session.string() + "'",
                            dir);
    REQUIRE(imported.status == 0);
    const auto exported = dir / ("run-" + rate + ".csv");
    REQUIRE(run_doorbench_shell(
                "export '" + session.string() + "' --csv '" + exported.string() + "'", dir)
                .status == 0);
    return std::make_pair(imported.err, data_rows(exported));
  };

  // 250 Hz: the new times 0, 4, ..., 16 ms (to the recording's last time, 19 ms), each the
  // mean of the samples within 2 ms of it (a tie to the later); 8 ms has none (the gap).
  const auto [slow_err, slow] = import_and_export("250");
  CHECK(slow_err == "wrote " + (dir / "run-250.h5").string() +
                        ": 5 samples, resampled from 1000 Hz (1 / the median interval) to 250 "
                        "Hz, each sample the mean over its interval\n");
  CHECK(slow ==
        "time_s,force_N,rate_rad_s,stroke\n"
        "0,0.5,0.125,0\n"         // 0, 1 ms
        "0.004,3.5,0.875,0\n"     // 2 to 5 ms
        "0.008,,,0\n"             // none: missing, the stroke of 5 ms
        "0.012,12.5,3.125,1\n"    // 12, 13 ms
        "0.016,15.5,3.875,1\n");  // 14 to 17 ms

  // 2 kHz: linear interpolation, missing across the gap (more than 3 median intervals).
  const auto [fast_err, fast] = import_and_export("2000");
  CHECK(fast_err == "wrote " + (dir / "run-2000.h5").string() +
                        ": 39 samples, resampled from 1000 Hz (1 / the median interval) to 2000 "
                        "Hz, linear interpolation\n");
  CHECK(fast.rfind("time_s,force_N,rate_rad_s,stroke\n"
                   "0,0,0,0\n"
                   "5e-04,0.5,0.125,0\n"
                   "0.001,1,0.25,0\n",
                   0) == 0);
  CHECK(fast.find("\n0.005,5,1.25,0\n0.0055,,,0\n") != std::string::npos);
  CHECK(fast.find("\n0.0115,,,0\n0.012,12,3,1\n0.0125,12.5,3.125,1\n") != std::string::npos);
  CHECK(fast.ends_with("\n0.019,19,4.75,1\n"));

  // Not a rate: a usage error naming the option.
  const DoorbenchRun zero = run_doorbench_shell(
      "import '" + source.string() + "' --resample-hz 0 --out '" + (dir / "z.h5").string() + "'",
      dir);
  CHECK(zero.status == 2);
  CHECK_THAT(zero.err, Catch::StartsWith("doorbench: --resample-hz: "));
}
