// The recorder with a trigger stage between its sources and the journal (RecordOptions::
// trigger, docs/triggering.md): what is kept, and where it lands on the session clock.
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>
#include <thread>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"
#include "fixtures/temp_dir.h"
#include "sensors/comedi_backend.h"
#include "tests/support/fake_polled_source.h"
#include "tests/support/session_origin.h"

using Catch::Matchers::Contains;
using namespace doorbench;
using doorbench::testing::FakePolledOptions;
using doorbench::testing::FakePolledSource;
using doorbench::testing::session_origin_ns;
using doorbench::testing::TempDir;

namespace {

// One channel at 1 kHz on the emulated board `device`.
RigDefinition one_channel_rig(const std::string& device) {
  std::ostringstream rig;
  rig << "[bench]\nname = \"trigger-test\"\n\n[clock]\nsample_rate_hz = 1000\n\n[daq]\n"
         "backend = \"comedi\"\ndevice = \""
      << device
      << "\"\nresolution_bits = 16\n\n[[channels]]\nname = \"volts\"\nsensor = \"load_cell\"\n"
         "serial = \"S0\"\nbackend = \"comedi\"\naddress = \"0/0\"\nrange_V = [-10.0, 10.0]\n"
         "calibration = \"nominal\"\nunit = \"N\"\n";
  return parse_rig(rig.str(), "trigger-test.toml", ".");
}

double sine_at(double amplitude, double frequency_hz, std::int64_t monotonic_ns) {
  return amplitude *
         std::sin(2 * std::numbers::pi * frequency_hz * (static_cast<double>(monotonic_ns) * 1e-9));
}

}  // namespace

TEST_CASE(
    "Recorder with a trigger: a level on a polled channel starts it, the pre-trigger and the "
    "duration are kept, scans and polled samples stay on one clock",
    "[recorder][trigger]") {
  TempDir dir("recorder_trigger");
  // The card and the polled source see the same 1 Hz sine of absolute CLOCK_MONOTONIC time.
  // Transfers of 64 bytes (32 scans): the emulator's default 4 kB would hand this one
  // channel over in 2 s chunks, more than the recorder's ring holds.
  const auto device =
      dir.write("comedi0", "transfer_bytes = 64\nsignal.0 = monotonic_sine 1.0 1.0 0.0\n");
  sensors::ComediOptions comedi;
  comedi.duration_s = 3.0;
  sensors::ComediBackend backend(one_channel_rig(device.string()),
                                 sensors::load_comedi_library(DOORBENCH_COMEDI_EMULATOR), comedi);
  FakePolledOptions fake;
  fake.names = {"polled"};
  fake.period_s = 0.002;
  fake.latency_s = 0.0004;
  fake.frequency_hz = 1.0;
  FakePolledSource polled(fake);

  RecordSources sources;
  sources.scans = &backend;
  sources.polled = {&polled};
  RecordOptions options;
  options.duration_s = 3.0;  // the whole acquisition, armed time included
  options.block_scans = 20;
  options.when_ring_full = RingFullPolicy::kDropAndRecordFault;
  TriggerOptions trigger;
  trigger.start = TriggerOptions::Start::kLevel;
  trigger.start_level.channel = "polled";
  trigger.start_level.level = 0.5;
  trigger.start_level.hysteresis = 0.1;
  trigger.pre_trigger_s = 0.2;
  trigger.duration_s = 0.5;
  options.trigger = trigger;
  const auto path = dir / "triggered.h5";
  const RecordSummary summary = record_session(sources, SessionMetadata{}, path, options);
  INFO(summary.brief_report());
  REQUIRE(summary.triggered);
  CHECK(summary.dropped_scans == 0);

  const SessionReader session(path);
  const std::vector<SessionEvent> events = session.events();
  const SessionEvent* fired = nullptr;
  const SessionEvent* started = nullptr;  // the acquisition's start, now a mark
  for (const SessionEvent& e : events) {
    if (e.kind == "trigger") fired = &e;
    if (e.kind == "mark" && e.detail.find("acquisition started") == 0) started = &e;
  }
  REQUIRE(fired != nullptr);
  REQUIRE(started != nullptr);
  CHECK_THAT(fired->detail, Contains("polled"));
  // 0.2 s before the trigger, or all there was when the sine crossed the level sooner
  // after the start (then the first kept scan is the acquisition's first, at time 0).
  const bool whole_pre_trigger = started->time_s < -0.001;
  if (whole_pre_trigger) {
    CHECK(fired->time_s == Approx(0.2).margin(0.003));
  } else {
    CHECK(started->time_s == Approx(0.0).margin(1e-9));
    CHECK(fired->time_s <= 0.2);
  }
  // And 0.5 s after it, at 1 kHz (a scan of slack for where the polled crossing falls).
  CHECK(static_cast<double>(session.sample_count("volts")) ==
        Approx(1000 * fired->time_s + 500).margin(2));

  // Session time 0 is the first kept scan: the origin recorded with the session maps
  // both channels' times back to the absolute clock their signal was made of.
  const std::int64_t origin = session_origin_ns(session);
  const ChannelSlice scans = session.read("volts");
  const std::vector<double> volts_N = session.physical("volts", scans);
  const ChannelInfo& volts = session.channel("volts");
  double worst_scan_V = 0.0;
  for (std::size_t i = 0; i < scans.raw.size(); ++i) {
    const double signal_V = volts.raw_offset + volts.raw_scale * scans.raw[i];
    const auto t_ns = origin + static_cast<std::int64_t>(std::llround(scans.time_s[i] * 1e9));
    worst_scan_V = std::max(worst_scan_V, std::abs(signal_V - sine_at(1.0, 1.0, t_ns)));
  }
  INFO("worst scan deviation " << worst_scan_V << " V");
  CHECK(worst_scan_V < 0.01);  // 1 ms of a 1 Hz sine of 1 V: 6 mV
  const ChannelSlice values = session.read("polled");
  REQUIRE(values.raw.size() > 200);
  double worst_polled = 0.0;
  for (std::size_t i = 0; i < values.raw.size(); ++i) {
    const auto t_ns = origin + static_cast<std::int64_t>(std::llround(values.time_s[i] * 1e9));
    worst_polled = std::max(worst_polled, std::abs(values.raw[i] - sine_at(1.0, 1.0, t_ns)));
    // Nothing before the kept window, nothing after its end.
    CHECK(values.time_s[i] >= -0.002);
    CHECK(values.time_s[i] <= 0.703);
  }
  CHECK(worst_polled < 1e-6);
  // The level fired at the crossing: below it just before, at or above it from then on.
  for (std::size_t i = 0; i < values.raw.size(); ++i) {
    if (values.time_s[i] < fired->time_s - 0.001) CHECK(values.raw[i] < 0.5 + 1e-9);
    if (std::abs(values.time_s[i] - fired->time_s) < 1e-9) CHECK(values.raw[i] >= 0.5);
  }
  CHECK_THAT(summary.trigger_report, Contains("triggered"));
}

TEST_CASE(
    "Recorder with a trigger: a start condition that never fires keeps a session that says so",
    "[recorder][trigger]") {
  TempDir dir("recorder_trigger");
  FakePolledOptions fake;
  fake.names = {"polled"};
  fake.frequency_hz = 2.0;
  FakePolledSource polled(fake);
  RecordSources sources;
  sources.polled = {&polled};
  RecordOptions options;
  options.duration_s = 0.4;
  TriggerOptions trigger;
  trigger.start = TriggerOptions::Start::kLevel;
  trigger.start_level.channel = "polled";
  trigger.start_level.level = 5.0;  // the sine reaches 1
  options.trigger = trigger;
  const RecordSummary summary = record_session(sources, SessionMetadata{}, dir / "n.h5", options);
  CHECK_FALSE(summary.triggered);
  const SessionReader session(dir / "n.h5");
  CHECK(session.sample_count("polled") == 0);
  bool said = false;
  for (const SessionEvent& e : session.events()) {
    said |= e.kind == "mark" && e.detail.find("never fired") != std::string::npos;
  }
  CHECK(said);
}

TEST_CASE("Recorder with a trigger: started and stopped by hand, polled sources alone",
          "[recorder][trigger]") {
  TempDir dir("recorder_trigger");
  FakePolledOptions fake;
  fake.names = {"count"};
  fake.counter = true;
  fake.period_s = 0.002;
  FakePolledSource polled(fake);
  RecordSources sources;
  sources.polled = {&polled};
  std::atomic<bool> start{false}, stop{false};
  RecordOptions options;
  options.duration_s = 5.0;
  TriggerOptions trigger;
  trigger.start = TriggerOptions::Start::kManual;
  trigger.stop = TriggerOptions::Stop::kManual;
  trigger.manual_start = &start;
  trigger.manual_stop = &stop;
  trigger.pre_trigger_s = 0.1;
  options.trigger = trigger;
  std::thread hand([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    start = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    stop = true;
  });
  const auto began = std::chrono::steady_clock::now();
  const RecordSummary summary = record_session(sources, SessionMetadata{}, dir / "m.h5", options);
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  hand.join();
  INFO(summary.brief_report());
  CHECK(summary.triggered);
  CHECK(took_s < 3.0);  // ended by the stop key, not the 5 s bound
  const SessionReader session(dir / "m.h5");
  const ChannelSlice slice = session.read("count");
  REQUIRE(slice.raw.size() > 50);
  CHECK(slice.time_s.front() >= -0.003);
  CHECK(slice.time_s.front() < 0.01);
  // About 0.1 s before the start key and 0.3 s after it (the machine may be slow to react).
  CHECK(slice.time_s.back() > 0.3);
  CHECK(slice.time_s.back() < 1.0);
  // No poll lost inside the kept window: the counter runs on by one.
  for (std::size_t i = 1; i < slice.raw.size(); ++i) {
    REQUIRE(slice.raw[i] == slice.raw[i - 1] + 1);
  }
  std::size_t triggers = 0, stops = 0;
  for (const SessionEvent& e : session.events()) {
    if (e.kind == "trigger") {
      ++triggers;
      CHECK(e.time_s == Approx(0.1).margin(0.01));
      CHECK_THAT(e.detail, Contains("manual"));
    }
    stops += e.kind == "stop";
  }
  CHECK(triggers == 1);
  CHECK(stops == 1);
}
