// The recorder over several sources on one session clock (docs/synchronization.md): a
// scan backend (the comedi device emulator, tests/comedi_emulator) with polled sources
// (tests/support/fake_polled_source.h), polled sources alone, the journal's timed frames, and the
// timing test: one known signal of absolute CLOCK_MONOTONIC time on a DAQ channel and on a
// polled channel, their time offset measured.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <numbers>
#include <sstream>
#include <thread>

#include "acquisition/record/journal.h"
#include "acquisition/record/recorder.h"
#include "acquisition/record/recovery.h"
#include "acquisition/rig/rig_file.h"
#include "fixtures/temp_dir.h"
#include "sensors/comedi_backend.h"
#include "tests/support/comedi_emulator.h"
#include "tests/support/fake_polled_source.h"
#include "tests/support/session_origin.h"
#include "tests/support/sine_phase.h"

using Catch::Matchers::Contains;
using namespace doorbench;
using doorbench::testing::comedi_emulator;
using doorbench::testing::FakePolledOptions;
using doorbench::testing::FakePolledSource;
using doorbench::testing::session_origin_ns;
using doorbench::testing::sine_phase;
using doorbench::testing::TempDir;

namespace {

// A comedi rig of `channels` channels at `rate_hz` on the emulated board `device`.
RigDefinition comedi_rig(const std::string& device, int channels, double rate_hz) {
  static const char* sensors[] = {"load_cell", "inclinometer", "gyroscope"};
  static const char* units[] = {"N", "rad", "rad/s"};
  std::ostringstream rig;
  rig << "[bench]\nname = \"sources-test\"\n\n[clock]\nsample_rate_hz = " << rate_hz
      << "\nconvert_interval_s = 10e-6\n\n[daq]\nbackend = \"comedi\"\ndevice = \"" << device
      << "\"\nresolution_bits = 16\n";
  for (int c = 0; c < channels; ++c) {
    rig << "\n[[channels]]\nname = \"ch" << c << "\"\nsensor = \"" << sensors[c % 3]
        << "\"\nserial = \"S" << c << "\"\nbackend = \"comedi\"\naddress = \"0/" << c
        << "\"\nrange_V = [-10.0, 10.0]\ncalibration = \"nominal\"\nunit = \"" << units[c % 3]
        << "\"\n";
  }
  return parse_rig(rig.str(), "sources-test.toml", ".");
}

// How much later on the session axis signal 2 places the same signal instant than
// signal 1 does (both R·sin(ωt + φ)), in (−π/ω, π/ω].
double lag_s(double phase_1, double phase_2, double omega) {
  double d = phase_1 - phase_2;
  while (d > std::numbers::pi) d -= 2 * std::numbers::pi;
  while (d <= -std::numbers::pi) d += 2 * std::numbers::pi;
  return d / omega;
}

}  // namespace

TEST_CASE("Recorder sources: a DAQ and a polled source on one clock, latency and faults kept",
          "[recorder][sources]") {
  TempDir dir("sources");
  const auto device = dir.write("comedi0", "signal.0 = counter\n");
  sensors::ComediOptions comedi;
  comedi.duration_s = 1.0;
  sensors::ComediBackend backend(comedi_rig(device.string(), 3, 1000), comedi_emulator(), comedi);
  FakePolledOptions fake;
  fake.names = {"p_force", "p_angle"};
  fake.period_s = 0.004;
  fake.latency_s = 0.0005;
  fake.frequency_hz = 2.0;
  fake.fault_every = 50;  // every 0.2 s
  FakePolledSource polled(fake);

  RecordSources sources;
  sources.scans = &backend;
  sources.polled = {&polled};
  RecordOptions options;
  options.duration_s = 1.0;
  options.block_scans = 20;
  std::vector<RecordStatus> statuses;
  options.progress = [&](const RecordStatus& status) { statuses.push_back(status); };
  const auto path = dir / "mixed.h5";
  const RecordSummary summary = record_session(sources, SessionMetadata{}, path, options);
  INFO(summary.brief_report());
  CHECK(summary.scans == 1000);
  CHECK(summary.polled_samples > 300);  // 2 channels × ~250 polls
  CHECK(summary.faults >= 3);
  CHECK_THAT(summary.brief_report(), Contains(" polled samples"));

  const SessionReader session(path);
  REQUIRE(session.channels().size() == 3 + 4);
  CHECK(session.channels()[3].name == "p_force");
  CHECK(session.channels()[4].name == "p_force_latency");
  CHECK(session.channels()[4].sensor_kind == "poll_latency");
  CHECK(session.channels()[4].unit == "s");
  CHECK(session.channels()[6].name == "p_angle_latency");
  CHECK(session.sample_count("ch0") == 1000);
  // The origin: UTC and monotonic, recorded together.
  const std::int64_t origin = session_origin_ns(session);
  CHECK(session.read_group_attribute("clock", "origin_utc") == session.metadata().start_time_utc);
  CHECK(session.metadata().start_time_utc.size() == 30);
  for (const std::string name : {"p_force", "p_angle"}) {
    INFO(name);
    const ChannelSlice values = session.read(name);
    const ChannelSlice latency = session.read(std::string(name).append("_latency"));
    REQUIRE(values.raw.size() > 150);
    REQUIRE(latency.raw.size() == values.raw.size());
    CHECK(latency.time_s == values.time_s);
    CHECK(values.time_s.front() >= 0.0);
    CHECK(values.time_s.back() < 1.2);
    double worst = 0.0;
    for (std::size_t i = 0; i < values.raw.size(); ++i) {
      if (i > 0) REQUIRE(values.time_s[i] > values.time_s[i - 1]);
      CHECK(latency.raw[i] >= 0.0005);
      CHECK(latency.raw[i] < 0.05);
      // The value is the sine at its absolute midpoint: session time + origin gives it back.
      const auto midpoint_ns =
          origin + static_cast<std::int64_t>(std::llround(values.time_s[i] * 1e9));
      worst = std::max(worst, std::abs(values.raw[i] - testing::fake_sine(fake, midpoint_ns)));
    }
    CHECK(worst < 1e-6);
  }
  // Faults of the polled source, placed on the session clock.
  std::size_t faults = 0;
  for (const SessionEvent& e : session.events()) {
    if (e.kind != "fault") continue;
    ++faults;
    CHECK(e.channel == "p_force");
    CHECK_THAT(e.detail, Contains("injected timeout after poll"));
    CHECK(e.time_s > 0.0);
    CHECK(e.time_s < 1.2);
  }
  CHECK(faults == summary.faults);

  // The live status: every channel, values and rates.
  REQUIRE(!statuses.empty());
  const RecordStatus& last = statuses.back();
  REQUIRE(last.channels.size() == 5);  // 3 scan channels, 2 polled (no latency channels)
  CHECK(last.scans == 1000);
  CHECK(last.achieved_scan_rate_hz == Approx(1000).epsilon(0.15));
  CHECK(last.channels[0].samples == 1000);
  CHECK(last.channels[3].polled);
  CHECK(last.channels[3].name == "p_force");
  CHECK(last.channels[3].achieved_rate_hz == Approx(250).epsilon(0.2));
  CHECK(std::abs(last.channels[3].latest) <= 1.0);
  CHECK(last.faults == summary.faults);
}

TEST_CASE("Recorder sources: polled sources alone, time 0 at their start", "[recorder][sources]") {
  TempDir dir("sources");
  FakePolledOptions fake;
  fake.names = {"count"};
  fake.counter = true;
  fake.period_s = 0.002;
  FakePolledSource polled(fake);
  RecordSources sources;
  sources.polled = {&polled};
  RecordOptions options;
  options.duration_s = 0.5;
  const RecordSummary summary = record_session(sources, SessionMetadata{}, dir / "p.h5", options);
  CHECK(summary.scans == 0);
  CHECK(summary.duration_s == Approx(0.5).margin(0.05));
  const SessionReader session(dir / "p.h5");
  const ChannelSlice slice = session.read("count");
  REQUIRE(slice.raw.size() > 150);
  CHECK(slice.raw.size() == summary.polled_samples);
  // The first sample is taken as the recording starts; on a busy machine the polling thread
  // may wake some milliseconds late (10.8 ms seen under ctest -j2 beside two builds), while a
  // wrong origin (the epoch, the machine's boot) is off by far more.
  CHECK(slice.time_s.front() >= 0.0);
  CHECK(slice.time_s.front() < 0.1);
  for (std::size_t i = 0; i < slice.raw.size(); ++i) REQUIRE(slice.raw[i] == double(i));
  CHECK(!session.read_group_attribute("clock", "origin_utc").empty());
}

TEST_CASE("Recorder sources: what cannot be recorded is refused, naming it",
          "[recorder][sources]") {
  TempDir dir("sources");
  RecordOptions options;
  CHECK_THROWS_WITH(record_session(RecordSources{}, SessionMetadata{}, dir / "a.h5", options),
                    Contains("nothing to record"));
  FakePolledOptions fake;
  fake.names = {"x", "x_latency"};
  FakePolledSource clash(fake);
  RecordSources sources;
  sources.polled = {&clash};
  CHECK_THROWS_WITH(record_session(sources, SessionMetadata{}, dir / "a.h5", options),
                    Contains("channel name x_latency is used twice"));
  options.polled_batch = 0;
  CHECK(options.validate() == "record polled_batch must be >= 1 and <= 1048576");
  CHECK(!std::filesystem::exists(dir / "a.h5.journal"));

  // A source that cannot start: the recording does not begin, the others are stopped, and
  // no journal is left behind.
  struct Unreachable : FakePolledSource {
    using FakePolledSource::FakePolledSource;
    std::string description() const override { return "modbus tcp 192.0.2.1:502"; }
    void start() override {
      throw std::runtime_error("modbus tcp 192.0.2.1:502: cannot connect: timed out");
    }
  };
  FakePolledOptions first_options;
  first_options.names = {"first"};
  FakePolledSource first(first_options);
  FakePolledOptions second_options;
  second_options.names = {"second"};
  Unreachable second(second_options);
  RecordSources two;
  two.polled = {&first, &second};
  CHECK_THROWS_WITH(record_session(two, SessionMetadata{}, dir / "b.h5", RecordOptions{}),
                    Contains("192.0.2.1:502: cannot connect"));
  CHECK(first.statistics().polls < 100);  // stopped at once, not left polling
  const auto polls = first.statistics().polls;
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  CHECK(first.statistics().polls == polls);
  CHECK(!std::filesystem::exists(dir / "b.h5.journal"));
  CHECK(!std::filesystem::exists(dir / "b.h5"));
}

TEST_CASE("Timing: one signal of CLOCK_MONOTONIC on a DAQ channel and a polled channel agrees",
          "[recorder][sources][timing]") {
  TempDir dir("timing");
  const double frequency_hz = 5.0, rate_hz = 1000.0;
  const auto device = dir.write("comedi0", "signal.0 = monotonic_sine 2.0 5.0 0.0\n");
  sensors::ComediOptions comedi;
  comedi.duration_s = 2.0;
  sensors::ComediBackend backend(comedi_rig(device.string(), 1, rate_hz), comedi_emulator(),
                                 comedi);
  FakePolledOptions fake;
  fake.names = {"polled"};
  fake.period_s = 0.003;
  fake.latency_s = 0.0008;
  fake.amplitude = 2.0;
  fake.frequency_hz = frequency_hz;
  FakePolledSource polled(fake);
  RecordSources sources;
  sources.scans = &backend;
  sources.polled = {&polled};
  RecordOptions options;
  options.duration_s = 2.0;
  options.block_scans = 20;
  record_session(sources, SessionMetadata{}, dir / "t.h5", options);

  const SessionReader session(dir / "t.h5");
  const ChannelInfo& daq = session.channel("ch0");
  const ChannelSlice daq_slice = session.read("ch0");
  std::vector<double> volts;
  for (double raw : daq_slice.raw) volts.push_back(daq.raw_offset + daq.raw_scale * raw);
  const ChannelSlice poll_slice = session.read("polled");
  REQUIRE(daq_slice.raw.size() == 2000);
  REQUIRE(poll_slice.raw.size() > 400);
  const double omega = 2 * std::numbers::pi * frequency_hz;
  const double daq_phase = sine_phase(daq_slice.time_s, volts, omega);
  const double poll_phase = sine_phase(poll_slice.time_s, poll_slice.raw, omega);
  const double offset_s = lag_s(daq_phase, poll_phase, omega);
  std::cout << "timing: polled channel vs DAQ channel offset " << offset_s * 1e6
            << " us (one DAQ sample period: " << 1e6 / rate_hz << " us)\n";
  CHECK(std::abs(offset_s) < 1.0 / rate_hz);

  // The estimator sees a known shift: the polled times moved 2 ms later by 2 ms.
  std::vector<double> shifted = poll_slice.time_s;
  for (double& t : shifted) t += 0.002;
  CHECK(lag_s(daq_phase, sine_phase(shifted, poll_slice.raw, omega), omega) - offset_s ==
        Approx(0.002).margin(1e-6));
}

// ---------------------------------------------------------------------------------------
// The journal's version 2: timed frames; version 1 still read

namespace {

JournalHeader mixed_header() {
  JournalHeader header;
  header.metadata.rig_name = "bench";
  ChannelInfo a;
  a.name = "a";
  a.sample_rate_hz = 100.0;
  header.channels.push_back(a);
  ChannelInfo p;
  p.name = "p";
  p.raw_type = RawType::kValues;
  p.raw_unit = "N";
  p.unit = "N";
  p.sample_rate_hz = 0.0;
  header.channels.push_back(p);
  ChannelInfo latency = p;
  latency.name = "p_latency";
  latency.sensor_kind = "poll_latency";
  latency.raw_unit = "s";
  latency.unit = "s";
  latency.range_min = 0;
  header.channels.push_back(latency);
  header.scan_rate_hz = 100.0;
  header.session_name = "s.h5";
  return header;
}

void append_raw_frame(const std::filesystem::path& path, std::uint32_t type,
                      const std::vector<std::uint8_t>& payload) {
  std::vector<std::uint8_t> frame(16 + payload.size());
  const std::uint32_t magic = 0x52464244, length = static_cast<std::uint32_t>(payload.size());
  std::memcpy(frame.data(), &magic, 4);
  std::memcpy(frame.data() + 4, &type, 4);
  std::memcpy(frame.data() + 8, &length, 4);
  std::memcpy(frame.data() + 16, payload.data(), payload.size());
  std::uint32_t crc = crc32({frame.data() + 4, 8});
  crc = crc32({frame.data() + 16, payload.size()}, crc);
  std::memcpy(frame.data() + 12, &crc, 4);
  std::ofstream out(path, std::ios::binary | std::ios::app);
  out.write(reinterpret_cast<const char*>(frame.data()),
            static_cast<std::streamsize>(frame.size()));
}

}  // namespace

TEST_CASE("Journal v2: timed frames round trip and convert, and the origin's UTC is kept",
          "[journal][sources]") {
  TempDir dir("journal");
  const auto journal_path = dir / "s.h5.journal";
  {
    JournalWriter journal(journal_path, mixed_header(), 4, 3);
    journal.append_start(5'000'000'000, 1'795'000'000'123'456'789);
    const std::int32_t counts[4] = {1, 2, 3, 4};
    journal.append_scans(0, 4, counts, 4);
    const std::int64_t times[3] = {1'000'000, 12'000'000, 25'000'000};
    const std::int64_t latencies[3] = {400'000, 500'000, 600'000};
    const double raw[3] = {1.5, -2.5, 3.25};
    journal.append_timed(1, 3, times, latencies, raw);
    CHECK_THROWS_WITH(journal.append_timed(0, 1, times, latencies, raw),
                      Contains("channel index 0 is not an explicit-time channel"));
    CHECK_THROWS_WITH(journal.append_timed(1, 4, times, latencies, raw),
                      Contains("a block of 4 timed samples is larger"));
    journal.append_event(0.02, "fault", "p", "timeout");
    journal.append_end(4);
    journal.close();
  }
  {
    JournalReader reader(journal_path);
    CHECK(reader.format_version() == 2);
    CHECK(scan_channel_count(reader.header()) == 1);
    JournalFrame frame;
    REQUIRE(reader.next(frame));
    CHECK(frame.type == FrameType::kStart);
    CHECK(frame.realtime_ns == 1'795'000'000'123'456'789);
    REQUIRE(reader.next(frame));
    CHECK(frame.type == FrameType::kScans);
    CHECK(frame.counts == std::vector<std::int32_t>{1, 2, 3, 4});
    REQUIRE(reader.next(frame));
    CHECK(frame.type == FrameType::kTimed);
    CHECK(frame.channel == 1);
    CHECK(frame.time_ns == std::vector<std::int64_t>{1'000'000, 12'000'000, 25'000'000});
    CHECK(frame.latency_ns == std::vector<std::int64_t>{400'000, 500'000, 600'000});
    CHECK(frame.raw == std::vector<double>{1.5, -2.5, 3.25});
  }
  const ConvertResult result = recover_session(journal_path);
  CHECK(result.timed_samples == 3);
  CHECK(result.start_realtime_ns == 1'795'000'000'123'456'789);
  CHECK_THAT(result.brief_report(), Contains("3 polled samples"));
  const SessionReader session(dir / "s.h5");
  CHECK(session.metadata().start_time_utc == "2026-11-18T11:06:40.123456789Z");
  CHECK(session.read_group_attribute("clock", "origin_utc") == "2026-11-18T11:06:40.123456789Z");
  CHECK(session.read_group_attribute("clock", "origin_monotonic_ns") == "5000000000");
  const ChannelSlice p = session.read("p");
  CHECK(p.time_s == std::vector<double>{0.001, 0.012, 0.025});
  CHECK(p.raw == std::vector<double>{1.5, -2.5, 3.25});
  const std::vector<double> latency = session.read("p_latency").raw;
  REQUIRE(latency.size() == 3);
  CHECK(latency[0] == Approx(0.0004));
  CHECK(latency[2] == Approx(0.0006));
  CHECK(session.sample_count("a") == 4);
}

TEST_CASE("Journal v1 (scans only, no UTC in the start frame) is still read and converted",
          "[journal][sources]") {
  TempDir dir("journal");
  const auto journal_path = dir / "old.h5.journal";
  JournalHeader header = mixed_header();
  header.channels.resize(1);                           // version 1: counts channels only
  { JournalWriter journal(journal_path, header, 4); }  // the header only
  {
    // Make it a version 1 journal: the version field follows the 8-byte magic.
    std::fstream file(journal_path, std::ios::binary | std::ios::in | std::ios::out);
    file.seekp(8);
    const std::uint32_t version = 1;
    file.write(reinterpret_cast<const char*>(&version), 4);
  }
  std::vector<std::uint8_t> start(8);
  const std::int64_t monotonic = 777;
  std::memcpy(start.data(), &monotonic, 8);
  append_raw_frame(journal_path, 1, start);
  std::vector<std::uint8_t> scans(16 + 3 * 4);
  const std::uint64_t first = 0;
  const std::uint32_t count = 3, channels = 1;
  const std::int32_t counts[3] = {7, 8, 9};
  std::memcpy(scans.data(), &first, 8);
  std::memcpy(scans.data() + 8, &count, 4);
  std::memcpy(scans.data() + 12, &channels, 4);
  std::memcpy(scans.data() + 16, counts, 12);
  append_raw_frame(journal_path, 2, scans);
  {
    JournalReader reader(journal_path);
    CHECK(reader.format_version() == 1);
    JournalFrame frame;
    REQUIRE(reader.next(frame));
    CHECK(frame.monotonic_ns == 777);
    CHECK(frame.realtime_ns == 0);
  }
  const ConvertResult result = recover_session(journal_path);
  CHECK(result.scans == 3);
  CHECK(!result.ended_cleanly);
  const SessionReader session(dir / "old.h5");
  CHECK(session.read("a").raw == std::vector<double>{7, 8, 9});
  CHECK(session.read_group_attribute("clock", "origin_monotonic_ns") == "777");
  CHECK_THROWS(session.read_group_attribute("clock", "origin_utc"));
}
