// sensors::RigRecording: the options a rig cannot record with, word for word; the Enter key
// of a manual trigger read on a thread that the recording stops and joins, leaving what
// follows on its input unread; a simulated rig recorded through it.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include "acquisition/session/session_file.h"
#include "fixtures/temp_dir.h"
#include "sensors/rig_recording.h"
#include "simulated_bench/simulated_bench.h"

using doorbench::RigDefinition;
using doorbench::sensors::ManualKeys;
using doorbench::sensors::RigRecordingOptions;

namespace {

// Waits until `flag` is set: true, or false after a minute (a busy machine is slow, never
// that slow).
bool becomes_set(const std::atomic<bool>* flag) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(1);
  while (!flag->load()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

struct Pipe {
  int fds[2] = {-1, -1};
  Pipe() { REQUIRE(::pipe(fds) == 0); }
  ~Pipe() {
    ::close(fds[0]);
    ::close(fds[1]);
  }
  void write(const std::string& text) const {
    REQUIRE(::write(fds[1], text.data(), text.size()) == static_cast<ssize_t>(text.size()));
  }
};

}  // namespace

TEST_CASE("RigRecordingOptions: a card or polled sensors need a duration or triggers",
          "[recorder][trigger]") {
  RigDefinition rig;
  RigRecordingOptions options;
  rig.daq_backend = "comedi";
  CHECK(options.problem(rig) ==
        "a comedi rig records for a set time: give --duration-s (or a [recording] table with "
        "its triggers)");
  rig.daq_backend = "none";
  CHECK(options.problem(rig) ==
        "a rig of polled sensors records for a set time: give --duration-s (or a [recording] "
        "table with its triggers)");
  rig.recording.line = 3;  // a [recording] table: its triggers end the recording
  CHECK(options.problem(rig).empty());
  rig.recording.line = 0;
  options.duration_s = 2.5;
  CHECK(options.problem(rig).empty());
  rig.daq_backend = "simulated";  // the bench's hand cycles bound it
  options.duration_s = 0.0;
  CHECK(options.problem(rig).empty());
  options.flush_interval_s = 0.0;
  CHECK(options.problem(rig) == "the flush interval must be > 0 s");
  options.flush_interval_s = 0.05;
  options.duration_s = -1.0;
  CHECK(options.problem(rig) == "the duration must be a number of seconds >= 0");
  options.duration_s = 0.0;
  options.max_wait_s = -1.0;
  CHECK(options.problem(rig) == "the armed wait must be a number of seconds >= 0");
  CHECK_THROWS_WITH(
      doorbench::sensors::RigRecording(rig, options, doorbench::simulated_bench::simulated_scans),
      "the armed wait must be a number of seconds >= 0");
}

TEST_CASE("ManualKeys: the first Enter starts, the next stops, nothing is read after it ends",
          "[recorder][trigger]") {
  const Pipe keys_in;
  {
    const ManualKeys keys(false, keys_in.fds[0]);
    CHECK_FALSE(keys.start()->load());
    keys_in.write("\n");
    REQUIRE(becomes_set(keys.start()));
    CHECK_FALSE(keys.stop()->load());
    keys_in.write("any text, then Enter\n");
    REQUIRE(becomes_set(keys.stop()));
  }
  // Ended and joined: what comes next on the input stays there for its next reader.
  keys_in.write("answer\n");
  char read_back[7] = {};
  REQUIRE(::read(keys_in.fds[0], read_back, sizeof read_back) == 7);
  CHECK(std::string(read_back, 7) == "answer\n");
  // A recording that starts at once: the first Enter stops it.
  const ManualKeys stop_only(true, keys_in.fds[0]);
  CHECK(stop_only.start()->load());
  keys_in.write("\n");
  REQUIRE(becomes_set(stop_only.stop()));
}

TEST_CASE("ManualKeys: ended without a key, and at the end of its input", "[recorder][trigger]") {
  Pipe keys_in;
  { const ManualKeys keys(false, keys_in.fds[0]); }  // the destructor wakes and joins it
  ::close(keys_in.fds[1]);
  keys_in.fds[1] = -1;
  const int read_end = keys_in.fds[0];
  const ManualKeys at_end(false, read_end);  // no more input: the reader ends by itself
  CHECK_FALSE(at_end.start()->load());
}

TEST_CASE("RigRecording: the simulated rig recorded through the library", "[recorder]") {
  const doorbench::testing::TempDir dir("rig_recording");
  const RigDefinition rig =
      doorbench::parse_rig(doorbench::simulated_dishwasher_rig_text(), "built-in rig", dir.path);
  RigRecordingOptions options;
  options.duration_s = 0.5;
  doorbench::sensors::RigRecording recording(rig, options,
                                             doorbench::simulated_bench::simulated_scans);
  CHECK(recording.display_duration_s() == 0.5);
  CHECK(recording.setup_report().empty());
  doorbench::SessionMetadata metadata;
  metadata.rig_name = rig.name;
  const doorbench::RecordSummary summary = recording.record(metadata, dir / "s.h5");
  CHECK(summary.scans > 0);
  CHECK(recording.end_warning().empty());
  const doorbench::SessionReader session(dir / "s.h5");
  CHECK(session.channels().size() == rig.channels.size());
  CHECK(session.problems().empty());
}
