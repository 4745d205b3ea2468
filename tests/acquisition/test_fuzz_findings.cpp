// What the fuzz targets found (fuzz/, docs/fuzzing.md), each kept as a test of the error it
// must now give. Found by fuzz_journal with its checksums made right:
//  1. a journal header whose channel names a calibration record the header does not hold
//     made recovery throw std::invalid_argument from the session writer (not a
//     JournalError naming the journal);
//  2. a scans block far past the last one made recovery fill the gap without bound (7 GB
//     written before the fuzzer was stopped);
//  3. (with 2) a header's scan rate is not checked against the rig limits.
// Found by fuzz_csv's round trip:
//  4. the reader takes a column name starting with '#' after the first, which the writer
//     refused (only the first column's would read back as a metadata line).
#include <catch2/catch.hpp>
#include <cstdint>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/record/journal.h"
#include "acquisition/record/recovery.h"
#include "acquisition/session/recording_csv.h"
#include "fixtures/temp_dir.h"

namespace {

using namespace doorbench;
namespace fs = std::filesystem;

// One counts channel "a"; `calibration_id` and `unit` as given.
JournalHeader header_of(double scan_rate_hz, const std::string& calibration_id = {},
                        const std::string& unit = {}) {
  JournalHeader header;
  header.metadata.rig_name = "bench";
  ChannelInfo a;
  a.name = "a";
  a.calibration_id = calibration_id;
  a.unit = unit;
  a.sample_rate_hz = scan_rate_hz;
  header.channels = {a};
  header.scan_rate_hz = scan_rate_hz;
  header.session_name = "s.h5";
  header.flush_interval_s = 0.05;
  header.backend = "test";
  return header;
}

// A journal of `header` with blocks of 10 scans starting at each of `firsts`.
fs::path journal_of(const fs::path& dir, const JournalHeader& header,
                    const std::vector<std::uint64_t>& firsts) {
  const fs::path path = dir / "s.h5.journal";
  JournalWriter journal(path, header, 10);
  journal.append_start(1);
  std::vector<std::int32_t> counts(10, 7);
  for (std::uint64_t first : firsts) journal.append_scans(first, 10, counts.data(), 10);
  journal.close();
  return path;
}

// The JournalError recovering `journal` gives ("" when it recovers, or fails otherwise).
std::string recovery_error(const fs::path& journal) {
  try {
    recover_session(journal);
  } catch (const JournalError& error) {
    return error.what();
  }
  return "";
}

}  // namespace

TEST_CASE("Fuzz findings: a header naming a missing calibration record is damage",
          "[journal][recovery][fuzz]") {
  const testing::TempDir dir("fuzz_finding_calibration");
  const fs::path journal =
      journal_of(dir.path, header_of(1000.0, "nominal-SIM-LC445-0001", "N"), {0, 10});
  const std::string message = recovery_error(journal);
  INFO(message);
  CHECK(message.rfind(
            journal.string() + ": the journal's header does not describe a valid session: ", 0) ==
        0);
  CHECK(message.find("calibration record nominal-SIM-LC445-0001") != std::string::npos);
  CHECK(fs::exists(journal));  // kept: nothing was recovered
  CHECK(!fs::exists(dir / "s.h5"));
  CHECK(!fs::exists(dir / "s.h5.partial"));
}

TEST_CASE("Fuzz findings: a block more than an hour past the last is damage, not a gap",
          "[journal][recovery][fuzz]") {
  const testing::TempDir dir("fuzz_finding_gap");
  // 1 kHz: an hour is 3.6 million scans; the second block starts 3600001 scans late.
  const fs::path journal = journal_of(dir.path, header_of(1000.0), {0, 10 + 3600001});
  const std::string message = recovery_error(journal);
  INFO(message);
  CHECK(message.rfind(journal.string() + ": block at byte ", 0) == 0);
  CHECK(message.find(" starts at scan 3600011, 3600001 scans after the last one the journal "
                     "has (more than an hour): the journal is damaged") != std::string::npos);
  CHECK(!fs::exists(dir / "s.h5"));
  // A gap of an hour exactly is still a gap.
  const testing::TempDir ok("fuzz_finding_gap_ok");
  const fs::path hour = journal_of(ok.path, header_of(1.0), {0, 10 + 3600});
  const ConvertResult result = recover_session(hour);
  CHECK(result.gap_scans == 3600);
}

TEST_CASE("Fuzz findings: a header's scan rate outside the rig limits is refused",
          "[journal][fuzz]") {
  const testing::TempDir dir("fuzz_finding_rate");
  const fs::path journal = journal_of(dir.path, header_of(1e9), {0});
  try {
    JournalReader reader(journal);
    FAIL("read");
  } catch (const JournalError& error) {
    const std::string message = error.what();
    INFO(message);
    CHECK(message.find("the journal's header is not valid: scan_rate_hz 1e+09 is not 0 (no DAQ) "
                       "or from 1 to 200000 Hz") != std::string::npos);
  }
}

TEST_CASE("Fuzz findings: a later column named '#...' reads, writes and reads back",
          "[csv][fuzz]") {
  const std::string text = "time_s,force_N,rate_rad_s,#note_V\n0,1,2,3\n0.5,,,4\n";
  const Recording recording = parse_recording_csv(text, "hash.csv", EmptyCells::kMissing);
  REQUIRE(recording.extra_names == std::vector<std::string>{"#note_V"});
  std::ostringstream written;
  write_recording_csv(written, recording);
  CHECK(written.str() == text);
  // The first column's name may not start with '#': that header would be a metadata line.
  std::ostringstream out;
  const std::vector<double> a{1.0};
  CHECK_THROWS_WITH(write_csv(out, {}, {"#a_V"}, {&a}),
                    "write_csv: first column name '#a_V' starts with '#' (the header would read "
                    "as metadata)");
}
