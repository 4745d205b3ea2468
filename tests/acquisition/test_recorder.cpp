// The recorder's two threads (acquisition/record/recorder.h): every scan and event reaches the
// session through the ring and the journal; the reading side allocates nothing; a full
// ring is a fault with a gap, never silent; stop requests and backend failures end with a
// complete session. Sessions are real HDF5 files, read back with SessionReader and h5py.
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>

#include "acquisition/record/journal.h"
#include "acquisition/record/recorder.h"
#include "acquisition/record/recovery.h"
#include "acquisition/rig/rig_file.h"
#include "fixtures/temp_dir.h"
#include "simulated_bench/simulated_bench.h"
#include "tests/support/allocation_counter.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using namespace doorbench;

namespace {

// The count of channel c at scan s: distinct per channel and scan, so any lost, doubled or
// misplaced sample shows.
std::int32_t expected_count(std::uint64_t scan, std::size_t channel) {
  return static_cast<std::int32_t>((scan * 7919 + channel * 104729) % 65536);
}

// A backend with known samples and events, optionally paced in real time, optionally
// failing after some scans. Its read() allocates nothing (event texts fit std::string's
// small buffer).
class CountingBackend final : public AcquisitionBackend {
 public:
  CountingBackend(std::size_t channels, double rate_hz, bool paced = false)
      : channels_(channels), rate_hz_(rate_hz), paced_(paced) {}
  std::string description() const override { return "counting backend"; }
  std::vector<ChannelInfo> channels() const override {
    std::vector<ChannelInfo> infos;
    for (std::size_t c = 0; c < channels_; ++c) {
      ChannelInfo info;
      info.name = std::string("ch").append(std::to_string(c));
      info.sensor_kind = std::string("test");
      // Strings, not operator=(const char*): GCC 12's -Wrestrict false positive once the
      // unity build inlines it.
      info.unit = std::string("V");
      info.sample_rate_hz = rate_hz_;
      info.range_min = -INFINITY;  // survives the journal's JSON
      infos.push_back(info);
    }
    return infos;
  }
  std::vector<doorbench::CalibrationRecord> calibrations() const override { return {}; }
  double scan_rate_hz() const override { return rate_hz_; }
  void start() override {
    started_ = std::chrono::steady_clock::now();
    ++starts;
  }
  std::size_t read(ScanBlock& block) override {
    if (fail_after_scans > 0 && next_ >= fail_after_scans) {
      throw std::runtime_error("counting backend: the device went away");
    }
    const std::size_t n = block.capacity();
    for (std::size_t s = 0; s < n; ++s) {
      const std::uint64_t scan = next_ + s;
      for (std::size_t c = 0; c < channels_; ++c) block.counts[c][s] = expected_count(scan, c);
      if (scan % 250 == 0) block.events.push_back({scan / rate_hz_, "mark", "ch1", "every 250"});
    }
    next_ += n;
    block.scan_count = n;
    if (paced_) {
      std::this_thread::sleep_until(started_ +
                                    std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::duration<double>(next_ / rate_hz_)));
    }
    return n;
  }
  void stop() override { ++stops; }

  std::uint64_t fail_after_scans = 0;
  int starts = 0, stops = 0;

 private:
  std::size_t channels_;
  double rate_hz_;
  bool paced_;
  std::uint64_t next_ = 0;
  std::chrono::steady_clock::time_point started_;
};

// Checks every sample of a session written from a CountingBackend; gaps (kGapFillCount)
// are counted, not compared.
std::uint64_t check_counts(const SessionReader& session, std::size_t channels,
                           std::uint64_t expected_scans) {
  std::uint64_t gap_scans = 0;
  for (std::size_t c = 0; c < channels; ++c) {
    const ChannelSlice slice = session.read("ch" + std::to_string(c));
    REQUIRE(slice.raw.size() == expected_scans);
    std::uint64_t wrong = 0;
    for (std::uint64_t s = 0; s < expected_scans; ++s) {
      if (slice.raw[s] == kGapFillCount) {
        if (c == 0) ++gap_scans;
      } else if (slice.raw[s] != expected_count(s, c)) {
        ++wrong;
      }
    }
    INFO("channel " << c);
    CHECK(wrong == 0);
  }
  return gap_scans;
}

std::size_t count_kind(const std::vector<SessionEvent>& events, const std::string& kind) {
  std::size_t n = 0;
  for (const SessionEvent& e : events) n += e.kind == kind ? 1 : 0;
  return n;
}

// h5py opens the session and reports the first channel's length.
long h5py_length(const std::filesystem::path& session, const std::string& channel) {
  const std::string command =
      "/usr/bin/python3 -c \"import h5py,sys; f=h5py.File(sys.argv[1],'r'); "
      "print(len(f['channels/" +
      channel + "/raw']))\" '" + session.string() + "' 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  char line[256] = {};
  const bool got = std::fgets(line, sizeof line, pipe) != nullptr;
  ::pclose(pipe);
  INFO("h5py said: " << line);
  REQUIRE(got);
  return std::strtol(line, nullptr, 10);
}

}  // namespace

TEST_CASE("Recorder: every scan and event reaches the session, and the journal is removed",
          "[recorder]") {
  testing::TempDir dir("recorder");
  CountingBackend backend(4, 5000.0);
  RecordOptions options;
  options.duration_s = 2.0;
  const std::filesystem::path path = dir / "s.h5";
  std::size_t progress_calls = 0;
  options.progress = [&](const doorbench::RecordStatus&) { ++progress_calls; };
  const RecordSummary summary = record_session(backend, SessionMetadata{}, path, options);
  CHECK(summary.scans == 10000);
  CHECK(summary.duration_s == 2.0);
  CHECK(summary.events == 40);  // one mark every 250 scans
  CHECK(summary.dropped_scans == 0);
  CHECK(summary.journal_syncs >= 2);  // at least the header's and the end's
  CHECK(progress_calls > 0);
  CHECK(backend.starts == 1);
  CHECK(backend.stops == 1);
  CHECK_THAT(summary.brief_report(), StartsWith("10000 scans (2.000 s), 40 events; journal "));

  CHECK(!std::filesystem::exists(journal_path_for(path)));
  CHECK(!std::filesystem::exists(dir / "s.h5.partial"));
  const SessionReader session(path);
  CHECK(check_counts(session, 4, 10000) == 0);
  const std::vector<SessionEvent> events = session.events();
  REQUIRE(events.size() == 40);
  CHECK(events[3].time_s == 750 / 5000.0);
  CHECK(events[3].channel == "ch1");
  CHECK(events[3].detail == "every 250");
  CHECK(session.channel("ch0").range_min == -INFINITY);
  CHECK(h5py_length(path, "ch3") == 10000);
}

TEST_CASE("Recorder: refuses an existing session or journal before recording", "[recorder]") {
  testing::TempDir dir("recorder");
  CountingBackend backend(2, 1000.0);
  RecordOptions options;
  options.duration_s = 0.1;
  const std::filesystem::path existing = dir.write("old.h5", "x");
  CHECK_THROWS_WITH(record_session(backend, SessionMetadata{}, existing, options),
                    existing.string() + ": already exists (sessions are never overwritten)");
  const std::filesystem::path path = dir / "new.h5";
  dir.write("new.h5.journal", "DBJRNL");
  CHECK_THROWS_WITH(record_session(backend, SessionMetadata{}, path, options),
                    Contains(journal_path_for(path).string() +
                             ": an unfinished recording's journal is in the way; recover it "
                             "first (doorbench recover "));
  CHECK(backend.starts == 0);

  options.flush_interval_s = 0;
  CHECK_THROWS_WITH(record_session(backend, SessionMetadata{}, dir / "x.h5", options),
                    "record flush_interval_s must be > 0 and <= 10");
}

TEST_CASE("Recorder: the reading side allocates nothing after the start",
          "[recorder][allocation]") {
  CountingBackend backend(8, 50000.0);
  const std::size_t block = 500;  // 10 ms at 50 kS/s
  RecorderRings rings(8, block, 4, 16);
  SECTION("with the writer keeping up") {
    RealtimeReader reader(backend, rings, 8, block, 1'000'000, RingFullPolicy::kDropAndRecordFault);
    reader.start();
    const long long before = testing::allocations();
    std::size_t events = 0;
    for (int i = 0; i < 1000; ++i) {
      REQUIRE(reader.step());
      // Drain in place, as the writer thread does (without writing anywhere).
      while (rings.scans.consumer_slot() != nullptr) rings.scans.release();
      while (rings.events.consumer_slot() != nullptr) {
        rings.events.release();
        ++events;
      }
    }
    CHECK(testing::allocations() == before);
    CHECK(reader.scans() == 500'000);
    CHECK(events == 2000);
    CHECK(rings.dropped_scans.load() == 0);
  }
  SECTION("with the rings full: overflow faults and dropped events allocate nothing either") {
    RealtimeReader reader(backend, rings, 8, block, 1'000'000, RingFullPolicy::kDropAndRecordFault);
    reader.start();
    const long long before = testing::allocations();
    for (int i = 0; i < 200; ++i) REQUIRE(reader.step());
    CHECK(testing::allocations() == before);
    CHECK(rings.dropped_scans.load() == 196 * 500);
    CHECK(rings.overflows.load() == 1);
    CHECK(rings.dropped_events.load() > 0);
    const EventSlot* first = rings.events.consumer_slot();
    REQUIRE(first != nullptr);
    CHECK(std::string(first->kind) == "mark");
  }
}

TEST_CASE("Recorder: the simulated bench's read path allocates nothing after its first block",
          "[recorder][allocation]") {
  const RigDefinition rig =
      parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
  const DoorModel model = simulated_bench::simulated_door_model(rig);
  simulated_bench::SimulatedBench bench(rig, model, 20.0);
  RecorderRings rings(3, 10, 8, 64);
  RealtimeReader reader(bench, rings, 3, 10, 20'000, RingFullPolicy::kDropAndRecordFault);
  reader.start();
  // The first block's trigger event has a text longer than std::string's small buffer.
  REQUIRE(reader.step());
  const long long before = testing::allocations();
  std::size_t events = 0;
  while (reader.step()) {
    while (rings.scans.consumer_slot() != nullptr) rings.scans.release();
    while (rings.events.consumer_slot() != nullptr) {
      rings.events.release();
      ++events;
    }
  }
  CHECK(testing::allocations() == before);
  CHECK(reader.scans() == 20'000);
  CHECK(events >= 5);  // strokes started and ended on the way
}

TEST_CASE("Recorder: a writer that falls behind is a fault and a gap, never silent",
          "[recorder][overflow]") {
  testing::TempDir dir("recorder");
  CountingBackend backend(3, 10000.0, /*paced=*/true);
  RecordOptions options;
  options.duration_s = 1.0;
  options.block_scans = 100;
  options.ring_s = 0.04;  // 4 blocks
  options.when_ring_full = RingFullPolicy::kDropAndRecordFault;
  // A writer stalled by its disk: 60 ms per drain while blocks arrive every 10 ms.
  int stalls = 0;
  options.progress = [&](const doorbench::RecordStatus&) {
    if (stalls++ < 3) std::this_thread::sleep_for(std::chrono::milliseconds(60));
  };
  const std::filesystem::path path = dir / "s.h5";
  const RecordSummary summary = record_session(backend, SessionMetadata{}, path, options);
  INFO(summary.brief_report());
  REQUIRE(summary.dropped_scans > 0);
  CHECK_THAT(summary.brief_report(), Contains(" scans lost to ring overflows"));
  CHECK(summary.scans == 10000);  // the last scan's index + 1: the clock runs on

  const SessionReader session(path);
  CHECK(check_counts(session, 3, 10000) == summary.dropped_scans);
  const std::vector<SessionEvent> events = session.events();
  CHECK(count_kind(events, "fault") >= 1);
  CHECK(count_kind(events, "gap") >= 1);
  bool overflow_fault = false;
  for (const SessionEvent& e : events) {
    if (e.kind == "fault") {
      CHECK_THAT(e.detail, StartsWith("ring buffer overflow: the writer fell behind; scans from "));
      overflow_fault = true;
    }
    if (e.kind == "gap") CHECK_THAT(e.detail, Contains("lost (ring buffer overflow)"));
  }
  CHECK(overflow_fault);
}

TEST_CASE("Recorder: an unpaced source waits for a slow writer and loses nothing",
          "[recorder][overflow]") {
  testing::TempDir dir("recorder");
  CountingBackend backend(3, 10000.0);
  RecordOptions options;
  options.duration_s = 1.0;
  options.block_scans = 100;
  options.ring_s = 0.04;
  options.when_ring_full = RingFullPolicy::kWait;
  int stalls = 0;
  options.progress = [&](const doorbench::RecordStatus&) {
    if (stalls++ < 3) std::this_thread::sleep_for(std::chrono::milliseconds(30));
  };
  const RecordSummary summary = record_session(backend, SessionMetadata{}, dir / "s.h5", options);
  CHECK(summary.dropped_scans == 0);
  const SessionReader session(dir / "s.h5");
  CHECK(check_counts(session, 3, 10000) == 0);
  CHECK(count_kind(session.events(), "fault") == 0);
}

TEST_CASE("Recorder: a stop request ends the recording with a complete session", "[recorder]") {
  testing::TempDir dir("recorder");
  CountingBackend backend(2, 2000.0, /*paced=*/true);
  std::atomic<bool> stop{false};
  RecordOptions options;
  options.duration_s = 30.0;
  options.stop_requested = &stop;
  options.progress = [&](const doorbench::RecordStatus& status) {
    if (status.recorded_s >= 0.3) stop.store(true);
  };
  const auto begun = std::chrono::steady_clock::now();
  const RecordSummary summary = record_session(backend, SessionMetadata{}, dir / "s.h5", options);
  CHECK(std::chrono::steady_clock::now() - begun < std::chrono::seconds(3));
  CHECK(summary.stopped_by_request);
  CHECK(summary.duration_s >= 0.3);
  CHECK(summary.duration_s < 1.0);
  const SessionReader session(dir / "s.h5");
  check_counts(session, 2, summary.scans);
  const std::vector<SessionEvent> events = session.events();
  REQUIRE(!events.empty());
  CHECK(events.back().kind == "stop");
  CHECK_THAT(events.back().detail, StartsWith("recording stopped by hand after 0."));
}

TEST_CASE("Recorder: a backend that fails mid-way leaves a complete session with a fault",
          "[recorder]") {
  testing::TempDir dir("recorder");
  CountingBackend backend(2, 1000.0);
  backend.fail_after_scans = 300;
  RecordOptions options;
  options.duration_s = 5.0;
  options.block_scans = 100;
  CHECK_THROWS_WITH(record_session(backend, SessionMetadata{}, dir / "s.h5", options),
                    "counting backend: the device went away");
  CHECK(backend.stops == 1);
  const SessionReader session(dir / "s.h5");
  check_counts(session, 2, 300);
  const std::vector<SessionEvent> events = session.events();
  REQUIRE(!events.empty());
  CHECK(events.back().kind == "fault");
  CHECK(events.back().detail == "the recording stopped: counting backend: the device went away");
  CHECK(!std::filesystem::exists(dir / "s.h5.journal"));
}
