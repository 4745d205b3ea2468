// calibrate --valid-until is checked where it enters (`--valid-until notadate` is refused,
// not stored): an ISO 8601 date or UTC time on the calendar, not before today; else
// exit 2 naming the option, word for word. A good one passes on to the verb (here: a
// --from session that does not exist, exit 1).
#include <catch2/catch.hpp>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

using doorbench::testing::DoorbenchRun;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

TEST_CASE("calibrate --valid-until: a date on the calendar, not before today, or exit 2",
          "[cli][usage][calibration]") {
  const TempDir dir("valid_until");
  const std::string missing = (dir / "missing.h5").string();
  const auto run = [&](const std::string& date) {
    return run_doorbench_shell(
        "calibrate gyro --dry-run --from '" + missing + "' --valid-until '" + date + "'", dir);
  };
  const std::string form =
      " is not an ISO 8601 date (YYYY-MM-DD, or YYYY-MM-DDTHH:MM:SSZ in UTC) (see doorbench "
      "calibrate gyro --help)\n";
  for (const std::string bad :
       {"notadate", "2099-1-01", "2099-12-31T24:00:00Z", "2099-12-31T23:59:59",
        "2099-12-31T23:59:59.Z", "2099-12-31T", "2099-12-31 23:59:59Z", "20991231"}) {
    const DoorbenchRun refused = run(bad);
    INFO(bad);
    CHECK(refused.status == 2);
    CHECK(refused.err == "doorbench: --valid-until: " + bad + form);
  }
  const DoorbenchRun not_a_day = run("2099-02-29");  // 2099 is no leap year
  CHECK(not_a_day.status == 2);
  CHECK(not_a_day.err ==
        "doorbench: --valid-until: 2099-02-29 is not a day of the calendar "
        "(see doorbench calibrate gyro --help)\n");
  const DoorbenchRun past = run("2020-01-01");
  CHECK(past.status == 2);
  CHECK_THAT(past.err, Catch::StartsWith("doorbench: --valid-until: 2020-01-01 is before today ("));
  CHECK_THAT(past.err, Catch::EndsWith("): the record would have expired when made (see doorbench "
                                       "calibrate gyro --help)\n"));
  for (const std::string good : {"2096-02-29", "2099-12-31T23:59Z", "2099-12-31T23:59:59Z",
                                 "2099-12-31T23:59:59.123456789Z"}) {
    const DoorbenchRun accepted = run(good);
    INFO(good);
    CHECK(accepted.status == 1);
    CHECK(accepted.err == "doorbench: " + missing + ": no such file\n");
  }
}
