// The comedi backend against the device emulator (tests/comedi_emulator), which
// implements comedilib's functions with their documented behaviour on no hardware: the
// command test and its adjustments, real-time blocking reads, EOF at the stop count,
// EPIPE after an overrun, soft calibration, external start, and the sessions recorded.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <thread>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"
#include "fixtures/temp_dir.h"
#include "sensors/comedi_backend.h"
#include "sensors/comedi_devices.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/comedi_emulator.h"
#include "tests/support/run_doorbench.h"

using Catch::Matchers::Contains;
using doorbench::ChannelInfo;
using doorbench::RecordOptions;
using doorbench::ScanBlock;
using doorbench::SessionEvent;
using doorbench::SessionMetadata;
using doorbench::SessionReader;
using doorbench::sensors::ComediBackend;
using doorbench::sensors::ComediError;
using doorbench::sensors::ComediOptions;
using doorbench::testing::comedi_emulator;
using doorbench::testing::TempDir;

namespace {

struct RigSpec {
  std::string device;
  int channels = 3;
  double rate_hz = 1000;
  double convert_s = 10e-6;
  int bits = 16;
  std::string channel_range = "[-10.0, 10.0]";
  std::string first_channel_range;  // overrides channel 0's
  std::string aref;                 // every channel's, when set
  std::string start_trigger;        // "software" or "external"
};

std::string rig_text(const RigSpec& spec) {
  static const char* sensors[] = {"load_cell", "inclinometer", "gyroscope"};
  static const char* units[] = {"N", "rad", "rad/s"};
  std::ostringstream rig;
  rig << "[bench]\nname = \"comedi-test\"\n\n[clock]\nsample_rate_hz = " << spec.rate_hz
      << "\nconvert_interval_s = " << spec.convert_s << "\n\n[daq]\nbackend = \"comedi\"\n"
      << "device = \"" << spec.device << "\"\nresolution_bits = " << spec.bits << "\n";
  if (!spec.start_trigger.empty()) rig << "start_trigger = \"go\"\n";
  for (int c = 0; c < spec.channels; ++c) {
    rig << "\n[[channels]]\nname = \"ch" << c << "\"\nsensor = \"" << sensors[c % 3]
        << "\"\nserial = \"S" << c << "\"\nbackend = \"comedi\"\naddress = \"0/" << c
        << "\"\nrange_V = "
        << (c == 0 && !spec.first_channel_range.empty() ? spec.first_channel_range
                                                        : spec.channel_range)
        << "\ncalibration = \"nominal\"\nunit = \"" << units[c % 3] << "\"\n";
    if (!spec.aref.empty()) rig << "aref = \"" << spec.aref << "\"\n";
  }
  if (spec.start_trigger == "external") {
    rig << "\n[[triggers]]\nname = \"go\"\nkind = \"external\"\nsource = \"PFI0\"\n";
  } else if (spec.start_trigger == "software") {
    rig << "\n[[triggers]]\nname = \"go\"\nkind = \"software\"\n";
  }
  return rig.str();
}

doorbench::RigDefinition make_rig(const RigSpec& spec) {
  return doorbench::parse_rig(rig_text(spec), "test-rig.toml", ".");
}

// Reads every scan until the backend ends; returns counts[channel] and the events.
struct Drained {
  std::vector<std::vector<std::int32_t>> counts;
  std::vector<SessionEvent> events;
};
Drained drain(ComediBackend& backend, std::size_t block_scans = 64) {
  Drained drained;
  const std::size_t channels = backend.channels().size();
  drained.counts.resize(channels);
  ScanBlock block(channels, block_scans);
  for (;;) {
    block.events.clear();
    const std::size_t got = backend.read(block);
    drained.events.insert(drained.events.end(), block.events.begin(), block.events.end());
    if (got == 0) break;
    for (std::size_t c = 0; c < channels; ++c) {
      drained.counts[c].insert(drained.counts[c].end(), block.counts[c].begin(),
                               block.counts[c].begin() + static_cast<long>(got));
    }
  }
  return drained;
}

bool has_event(const std::vector<SessionEvent>& events, const std::string& kind,
               const std::string& text) {
  for (const SessionEvent& e : events) {
    if (e.kind == kind && e.detail.find(text) != std::string::npos) return true;
  }
  return false;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text.append(line).append("\n");
  return text;
}

}  // namespace

TEST_CASE("comedi command test: timers rounded to the board's clock, the achieved rate kept",
          "[comedi]") {
  TempDir dir("comedi");
  // A 1 MHz timebase: 1e9 / 3000 Hz = 333333 ns becomes 333000 ns (3003.003 Hz).
  const auto device = dir.write("comedi0", "base_clock_ns = 1000\nmin_convert_ns = 2000\n");
  RigSpec spec;
  spec.device = device.string();
  spec.rate_hz = 3000;
  spec.convert_s = 10.4e-6;  // 10400 ns → 10000 ns
  ComediBackend backend(make_rig(spec), comedi_emulator());
  const auto& setup = backend.setup();
  CHECK(setup.requested_scan_rate_hz == 3000);
  CHECK(backend.scan_rate_hz() == Approx(1e9 / 333000.0).epsilon(1e-12));
  CHECK(setup.achieved_convert_interval_s == Approx(10e-6).epsilon(1e-12));
  const std::string adjustments = joined(setup.adjustments);
  CHECK_THAT(adjustments, Contains("scan_begin_arg 333333 -> 333000 ns (test 1 returned 4)"));
  CHECK_THAT(adjustments, Contains("convert_arg 10400 -> 10000 ns (test 1 returned 4)"));
  REQUIRE(setup.tests.size() == 2);  // adjusted, then valid
  CHECK_THAT(setup.tests[1], Contains("returned 0 (valid)"));
  // The session gets the achieved rate and the achieved converter skew.
  for (std::size_t c = 0; c < 3; ++c) {
    CHECK(backend.channels()[c].sample_rate_hz == backend.scan_rate_hz());
    CHECK(backend.channels()[c].first_sample_time_s == Approx(c * 10e-6));
  }
  CHECK_THAT(backend.description(), Contains("requested 3000 Hz"));
}

TEST_CASE("comedi command test: a scan faster than the converter is raised to its minimum",
          "[comedi]") {
  TempDir dir("comedi");
  // 4 µs per conversion (250 kS/s): 3 channels need at least 12 µs per scan.
  const auto device = dir.write("comedi0", "min_convert_ns = 4000\n");
  RigSpec spec;
  spec.device = device.string();
  spec.rate_hz = 200000;  // 5000 ns per scan
  spec.convert_s = 1e-6;  // 1000 ns per conversion
  ComediBackend backend(make_rig(spec), comedi_emulator());
  const std::string adjustments = joined(backend.setup().adjustments);
  CHECK_THAT(adjustments, Contains("convert_arg 1000 -> 4000 ns (test 1 returned 3)"));
  CHECK_THAT(adjustments, Contains("scan_begin_arg 5000 -> 12000 ns (test 1 returned 3)"));
  CHECK(backend.scan_rate_hz() == Approx(1e9 / 12000.0));
  CHECK(backend.channels()[0].sample_rate_hz == Approx(1e9 / 12000.0));
}

TEST_CASE("comedi command test: sources the board lacks are errors naming them", "[comedi]") {
  TempDir dir("comedi");
  const auto device = dir.write("comedi0", "board = pci-6221\n");
  RigSpec spec;
  spec.device = device.string();
  spec.convert_s = 0;  // TRIG_NOW: simultaneous sampling, which a multiplexed M-series lacks
  REQUIRE_THROWS_WITH(ComediBackend(make_rig(spec), comedi_emulator()),
                      Contains(device.string() + " subdevice 0 (ni_pcimio pci-6221) refuses the "
                                                 "command: a trigger source is not supported") &&
                          Contains("convert_src TRIG_NOW -> none"));
  // A simultaneous-sampling board takes it.
  const auto simultaneous = dir.write("comedi1", "simultaneous = 1\n");
  spec.device = simultaneous.string();
  ComediBackend backend(make_rig(spec), comedi_emulator());
  CHECK(backend.setup().achieved_convert_interval_s == 0);
  CHECK(backend.channels()[2].first_sample_time_s == 0);
}

TEST_CASE("comedi ranges, aref and maxdata come from the rig and are checked", "[comedi]") {
  TempDir dir("comedi");
  const auto device =
      dir.write("comedi0", "ranges = -10 10, -5 5, -1 1, -0.2 0.2\narefs = ground diff\n");
  RigSpec spec;
  spec.device = device.string();
  spec.first_channel_range = "[-5.0, 5.0]";
  spec.channel_range = "[-1.0, 1.0]";
  {
    ComediBackend backend(make_rig(spec), comedi_emulator());
    CHECK(backend.setup().channels[0].range == 1);
    CHECK(backend.setup().channels[1].range == 2);
    CHECK(backend.channels()[0].raw_offset == Approx(-5.0));
    CHECK(backend.channels()[0].raw_scale == Approx(10.0 / 65535));
    CHECK(backend.channels()[1].range_max == Approx(1.0));
  }
  spec.first_channel_range = "[-2.0, 2.0]";
  REQUIRE_THROWS_WITH(ComediBackend(make_rig(spec), comedi_emulator()),
                      device.string() +
                          " subdevice 0: channel ch0 (0/0): the board has no range "
                          "[-2, 2] V; its voltage ranges are [-10, 10] V, [-5, 5] "
                          "V, [-1, 1] V, [-0.2, 0.2] V");
  spec.first_channel_range = "";
  spec.aref = "common";
  REQUIRE_THROWS_WITH(ComediBackend(make_rig(spec), comedi_emulator()),
                      device.string() +
                          " subdevice 0: channel ch0 (0/0): aref common is not "
                          "supported by the subdevice");
  spec.aref = "diff";
  {
    ComediBackend backend(make_rig(spec), comedi_emulator());
    CHECK(backend.setup().channels[2].aref == AREF_DIFF);
  }
  spec.aref = "";
  spec.bits = 12;
  REQUIRE_THROWS_WITH(ComediBackend(make_rig(spec), comedi_emulator()),
                      Contains("channel ch0 (0/0): maxdata is 65535 but the rig says "
                               "resolution_bits = 12 (maxdata 4095)"));
}

TEST_CASE("comedi recording: known signals at the achieved rate, EOF at the stop count",
          "[comedi]") {
  TempDir dir("comedi");
  // 1 MHz timebase: 2000 Hz is exact; 2 kHz, 3 channels, 0.5 s.
  const auto device = dir.write("comedi0",
                                "base_clock_ns = 1000\nmin_convert_ns = 2000\n"
                                "signal.0 = sine 4.0 7.0 1.0\nsignal.1 = sine 0.5 3.0 -0.25\n"
                                "signal.2 = constant 2.5\n");
  RigSpec spec;
  spec.device = device.string();
  spec.rate_hz = 2999;  // 333444.4 ns → 333000 ns: the session must use 3003.003 Hz
  spec.convert_s = 100e-6;
  ComediOptions options;
  options.duration_s = 0.5;
  ComediBackend backend(make_rig(spec), comedi_emulator(), options);
  const double rate = backend.scan_rate_hz();
  REQUIRE(rate == Approx(1e9 / 333000.0));
  CHECK(backend.setup().stop_scans == static_cast<std::size_t>(std::llround(0.5 * rate)));

  SessionMetadata metadata;
  metadata.rig_name = "comedi-test";
  RecordOptions record;
  record.duration_s = 10.0;  // longer than the command: EOF must end it
  record.block_scans = 50;
  const auto session_path = dir / "s.h5";
  const auto started = std::chrono::steady_clock::now();
  const auto summary = doorbench::record_session(backend, metadata, session_path, record);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  CHECK(summary.scans == backend.setup().stop_scans);
  CHECK(elapsed_s > 0.45);  // hardware-timed: the emulated card runs in real time
  CHECK_THAT(backend.end_reason(), Contains("end of acquisition after 1502 scans"));

  const SessionReader session(session_path);
  const double amplitude[] = {4.0, 0.5, 0.0}, frequency[] = {7.0, 3.0, 0.0},
               offset[] = {1.0, -0.25, 2.5};
  for (int c = 0; c < 3; ++c) {
    const ChannelInfo& info = session.channels()[c];
    CHECK(info.sample_rate_hz == rate);
    const auto slice = session.read(info.name);
    REQUIRE(slice.raw.size() == summary.scans);
    double worst_V = 0;
    for (std::size_t i = 0; i < slice.raw.size(); ++i) {
      const double volts = info.raw_offset + info.raw_scale * slice.raw[i];
      const double t = slice.time_s[i];
      const double truth =
          offset[c] + amplitude[c] * std::sin(2 * std::numbers::pi * frequency[c] * t);
      worst_V = std::max(worst_V, std::abs(volts - truth));
    }
    INFO("channel " << c);
    CHECK(worst_V <= 0.6 * 20.0 / 65535);  // within the quantization
  }
  const auto events = session.events();
  REQUIRE(!events.empty());
  CHECK(events[0].kind == "trigger");
  CHECK(events[0].detail == "start: software (TRIG_INT 0)");
  CHECK(session.read_group_attribute("acquisition/comedi", "achieved_scan_rate_hz") ==
        "3003.003003");
  CHECK_THAT(session.read_group_attribute("acquisition/comedi", "adjustments"),
             Contains("scan_begin_arg 333444 -> 333000 ns"));
}

TEST_CASE("comedi soft calibration: counts convert through the board's polynomial", "[comedi]") {
  TempDir dir("comedi");
  // A cubic to_phys polynomial about mid-scale, like an M-series board's.
  const auto cal = dir.write("board.cal", "* * 32767.5 0.0021 3.04e-4 1.2e-12 -4.0e-16\n");
  const auto device = dir.write("comedi0", "calibration_file = " + cal.string() +
                                               "\nbase_clock_ns = 1000\nmin_convert_ns = 2000\n"
                                               "signal.0 = sine 8.0 5.0 0.0\n");
  RigSpec spec;
  spec.device = device.string();
  spec.channels = 1;
  spec.rate_hz = 2000;
  ComediOptions options;
  options.duration_s = 0.25;
  ComediBackend backend(make_rig(spec), comedi_emulator(), options);
  const auto& channel = backend.setup().channels[0];
  CHECK(channel.conversion == "softcal");
  REQUIRE(channel.polynomial.size() == 4);
  CHECK(channel.polynomial[3] == -4.0e-16);
  CHECK(channel.polynomial_origin == 32767.5);
  CHECK(backend.channels()[0].raw_scale == Approx(3.04e-4).epsilon(0.01));
  CHECK(channel.line_deviation_V > 1e-4);  // the cubic's curvature, reported
  CHECK(channel.line_deviation_V < 1e-2);

  backend.start();
  const Drained drained = drain(backend);
  REQUIRE(drained.counts[0].size() == 500);
  // Through the session's line the volts are within the reported deviation (+ an LSB).
  double worst_V = 0;
  for (std::size_t i = 0; i < drained.counts[0].size(); ++i) {
    const double volts =
        backend.channels()[0].raw_offset + backend.channels()[0].raw_scale * drained.counts[0][i];
    const double truth = 8.0 * std::sin(2 * std::numbers::pi * 5.0 * i / 2000.0);
    worst_V = std::max(worst_V, std::abs(volts - truth));
  }
  CHECK(worst_V <= channel.line_deviation_V + 3.04e-4);
  // The hardware range conversion alone would be off by far more: the calibration matters.
  const double nominal = -10.0 + 20.0 / 65535 * drained.counts[0][100];
  CHECK(std::abs(nominal - 8.0 * std::sin(2 * std::numbers::pi * 5.0 * 100 / 2000.0)) > 0.01);
}

TEST_CASE("comedi soft-calibrated board without its file falls back and says so", "[comedi]") {
  TempDir dir("comedi");
  const auto device =
      dir.write("comedi0", "calibration_file = " + (dir / "missing.cal").string() + "\n");
  RigSpec spec;
  spec.device = device.string();
  ComediBackend backend(make_rig(spec), comedi_emulator());
  CHECK(backend.setup().channels[0].conversion == "comedi_to_phys");
  REQUIRE(backend.setup().warnings.size() == 1);
  CHECK_THAT(backend.setup().warnings[0],
             Contains("missing.cal cannot be read (run comedi_soft_calibrate)"));
}

TEST_CASE("comedi buffer overrun: drained, then a fault event with its time", "[comedi]") {
  TempDir dir("comedi");
  // 10 kHz × 2 channels × 2 bytes = 40 kB/s into a 4 kB buffer: full in 0.1 s.
  const auto device = dir.write("comedi0",
                                "buffer_bytes = 4096\ntransfer_bytes = 256\nbase_clock_ns = 1000\n"
                                "min_convert_ns = 2000\nsignal.0 = counter\nsignal.1 = counter\n");
  RigSpec spec;
  spec.device = device.string();
  spec.channels = 2;
  spec.rate_hz = 10000;
  ComediBackend backend(make_rig(spec), comedi_emulator());
  backend.start();
  ScanBlock block(2, 64);
  REQUIRE(backend.read(block) > 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // fall behind
  const Drained drained = drain(backend);
  CHECK(backend.overran());
  // Everything the buffer held was delivered, in order, without a gap.
  const std::size_t scans = drained.counts[0].size() + block.scan_count;
  CHECK(drained.counts[0].size() >= 4096 / 4 - 64);
  for (std::size_t i = 1; i < drained.counts[0].size(); ++i) {
    REQUIRE(drained.counts[0][i] == drained.counts[0][i - 1] + 1);
  }
  CHECK(scans == backend.scans_read());
  bool found = false;
  for (const SessionEvent& e : drained.events) {
    if (e.kind == "fault" && e.detail.find("comedi buffer overrun") != std::string::npos) {
      found = true;
      CHECK(e.time_s == Approx(scans / 10000.0));
      CHECK_THAT(e.detail, Contains("after " + std::to_string(scans) + " scans"));
    }
  }
  CHECK(found);
  CHECK_THAT(backend.end_reason(), Contains("buffer overrun"));
}

TEST_CASE("comedi start on an external line (TRIG_EXT PFI0) waits for it", "[comedi]") {
  TempDir dir("comedi");
  const auto device = dir.write("comedi0",
                                "external_trigger_line = 0\nexternal_trigger_delay_s = 0.3\n"
                                "base_clock_ns = 1000\nmin_convert_ns = 2000\n");
  RigSpec spec;
  spec.device = device.string();
  spec.start_trigger = "external";
  ComediOptions options;
  options.duration_s = 0.05;
  ComediBackend backend(make_rig(spec), comedi_emulator(), options);
  CHECK(backend.setup().start == "external PFI0 (TRIG_EXT " + std::to_string(CR_EDGE) + ")");
  const auto started = std::chrono::steady_clock::now();
  backend.start();
  const Drained drained = drain(backend);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  CHECK(elapsed_s >= 0.34);  // the line fired at 0.3 s, then 50 ms of scans
  CHECK(drained.counts[0].size() == 50);
  CHECK(has_event(drained.events, "trigger", "start: external PFI0"));

  // A software start_trigger is TRIG_INT.
  spec.start_trigger = "software";
  ComediBackend software(make_rig(spec), comedi_emulator(), options);
  CHECK(software.setup().start == "software, trigger go (TRIG_INT 0)");
}

TEST_CASE("comedi out-of-range samples are flagged as events", "[comedi]") {
  TempDir dir("comedi");
  const auto device = dir.write("comedi0",
                                "base_clock_ns = 1000\nmin_convert_ns = 2000\n"
                                "signal.0 = constant 12.0\nsignal.1 = sine 12.0 10.0 0.0\n");
  RigSpec spec;
  spec.device = device.string();
  spec.channels = 2;
  spec.rate_hz = 1000;
  ComediOptions options;
  options.duration_s = 0.2;
  ComediBackend backend(make_rig(spec), comedi_emulator(), options);
  backend.start();
  const Drained drained = drain(backend);
  REQUIRE(drained.counts[0].size() == 200);
  CHECK(drained.counts[0][10] == 65535);
  int ch0 = 0, ch1_high = 0, ch1_low = 0, back = 0;
  for (const SessionEvent& e : drained.events) {
    if (e.kind != "fault") continue;
    if (e.channel == "ch0") ++ch0;
    if (e.channel == "ch1" &&
        e.detail.find("at maxdata 65535 counts (above 10 V)") != std::string::npos)
      ++ch1_high;
    if (e.channel == "ch1" && e.detail.find("at 0 counts (below -10 V)") != std::string::npos)
      ++ch1_low;
    if (e.channel == "ch1" && e.detail.find("back in range after") != std::string::npos) ++back;
  }
  CHECK(ch0 == 1);       // reached the rail once and stayed there
  CHECK(ch1_high == 2);  // a 12 V sine over a ±10 V range: 2 periods in 0.2 s
  CHECK(ch1_low == 2);
  CHECK(back >= 3);
}

TEST_CASE("comedi 32-bit samples (SDF_LSAMPL) of an 18-bit board", "[comedi]") {
  TempDir dir("comedi");
  const auto device = dir.write("comedi0",
                                "lsampl = 1\nmaxdata = 262143\nbase_clock_ns = 1000\n"
                                "min_convert_ns = 2000\nsignal.0 = constant 1.25\n");
  RigSpec spec;
  spec.device = device.string();
  spec.bits = 18;
  spec.channels = 1;
  ComediOptions options;
  options.duration_s = 0.02;
  ComediBackend backend(make_rig(spec), comedi_emulator(), options);
  CHECK(backend.setup().sample_bytes == 4);
  backend.start();
  const Drained drained = drain(backend);
  REQUIRE(drained.counts[0].size() == 20);
  const double volts =
      backend.channels()[0].raw_offset + backend.channels()[0].raw_scale * drained.counts[0][5];
  CHECK(volts == Approx(1.25).margin(20.0 / 262143));
}

TEST_CASE("comedi reads allocate nothing in steady state", "[comedi]") {
  TempDir dir("comedi");
  const auto device =
      dir.write("comedi0", "base_clock_ns = 1000\nmin_convert_ns = 1000\nbuffer_bytes = 1048576\n");
  RigSpec spec;
  spec.device = device.string();
  spec.channels = 4;
  spec.rate_hz = 20000;
  spec.convert_s = 2e-6;
  ComediBackend backend(make_rig(spec), comedi_emulator());
  backend.start();
  ScanBlock block(4, 200);
  block.events.clear();
  REQUIRE(backend.read(block) > 0);  // the first read brings the trigger event
  block.events.clear();
  const long long before = doorbench::testing::allocations();
  std::size_t scans = 0;
  while (scans < 4000) {
    const std::size_t got = backend.read(block);
    if (got == 0) break;  // never expected: the 1 MiB buffer holds 6.5 s of data
    scans += got;
  }
  REQUIRE(scans >= 4000);
  CHECK(doorbench::testing::allocations() == before);
  CHECK(block.events.empty());
  backend.stop();
}

TEST_CASE("comedi device open errors and addresses name the device and channel", "[comedi]") {
  TempDir dir("comedi");
  RigSpec spec;
  spec.device = (dir / "comedi7").string();
  REQUIRE_THROWS_WITH(
      ComediBackend(make_rig(spec), comedi_emulator()),
      Contains(spec.device + ": cannot open the comedi device: No such file or directory"));
  const auto device = dir.write("comedi0", "ai_channels = 2\n");
  spec.device = device.string();
  REQUIRE_THROWS_WITH(ComediBackend(make_rig(spec), comedi_emulator()),
                      Contains("channel ch2 (0/2): no channel 2 (the subdevice has 2)"));
  const std::string text = doorbench::sensors::comedi_devices_report(comedi_emulator(), dir.path);
  CHECK_THAT(text, Contains(device.string() + ": driver ni_pcimio, board pci-6221, 3 subdevices"));
}

TEST_CASE("comedi devices lists the emulated boards", "[comedi]") {
  TempDir dir("comedi");
  dir.write("comedi0", "board = pcie-6251\nranges = -10 10, -5 5, -2 2, -1 1, -0.5 0.5\n");
  dir.write("comedi1", "board = pci-6221\nlsampl = 0\ncalibration_file = /nonexistent.cal\n");
  dir.write("comedi0_subd2", "not a device");
  const std::string text = doorbench::sensors::comedi_devices_report(comedi_emulator(), dir.path);
  CHECK_THAT(text, Contains((dir / "comedi0").string() +
                            ": driver ni_pcimio, board pcie-6251, 3 subdevices"));
  CHECK_THAT(text, Contains("  subdevice 0: analog input, 16 channels, maxdata 65535, aref ground "
                            "common diff other, commands(read), buffer 65536 bytes"));
  CHECK_THAT(text,
             Contains("    ranges (V): 0:[-10, 10] 1:[-5, 5] 2:[-2, 2] 3:[-1, 1] 4:[-0.5, 0.5]"));
  CHECK_THAT(text, Contains("  subdevice 1: analog output, 2 channels"));
  CHECK_THAT(text, Contains("  subdevice 2: digital I/O, 24 channels, maxdata 1"));
  CHECK_THAT(text, Contains("commands(read) soft-calibrated"));
  CHECK(text.find("comedi0_subd2") == std::string::npos);
  CHECK(text.find((dir / "comedi0").string()) < text.find((dir / "comedi1").string()));

  TempDir empty("comedi_empty");
  CHECK(doorbench::sensors::comedi_devices_report(comedi_emulator(), empty.path) ==
        "no comedi devices: " + (empty.path / "comedi*").string() +
            " does not exist (comedi needs a supported card and its kernel driver; the study's "
            "USB cDAQ-9172 has no comedi driver)\n");
}

namespace {

using Run = doorbench::testing::DoorbenchRun;

// The doorbench executable with the emulator in place of libcomedi when `emulated`.
Run run_doorbench(const std::string& args, const TempDir& dir, bool emulated) {
  return doorbench::testing::run_doorbench_shell(
      args, dir, emulated ? doorbench::testing::comedi_emulator_environment() : "");
}

}  // namespace

TEST_CASE("doorbench devices and record on the emulated card", "[comedi][cli]") {
  TempDir dir("comedi_cli");
  std::filesystem::create_directories(dir / "dev");
  dir.write("dev/comedi0", "board = pcie-6251\nmin_convert_ns = 1000\nbase_clock_ns = 50\n");
  const Run devices =
      run_doorbench("devices --dev-dir '" + (dir / "dev").string() + "'", dir, true);
  CHECK(devices.status == 0);
  CHECK_THAT(devices.out, Contains("comedi0: driver ni_pcimio, board pcie-6251, 3 subdevices"));
  CHECK_THAT(devices.out, Contains("ranges (V): 0:[-10, 10]"));

  RigSpec spec;
  spec.device = (dir / "dev/comedi0").string();
  spec.rate_hz = 1000;
  dir.write("rig.toml", rig_text(spec));
  const std::string session = (dir / "s.h5").string();
  const Run record = run_doorbench(
      "record --rig '" + (dir / "rig.toml").string() + "' --duration-s 0.3 --out '" + session + "'",
      dir, true);
  INFO(record.err);
  CHECK(record.status == 0);
  CHECK_THAT(record.err, Contains("scan rate 1000 Hz (requested 1000 Hz)"));
  CHECK_THAT(record.err, Contains("300 scans"));
  // Not a terminal: sparse status lines with the live values of every channel.
  CHECK_THAT(record.err, Contains(" faults; ch0 "));
  CHECK_THAT(record.err, Contains("; ch2 "));
  CHECK_THAT(record.err, Contains(" scans at "));
  const SessionReader reader(session);
  CHECK(reader.sample_count("ch0") == 300);

  const Run no_duration = run_doorbench(
      "record --rig '" + (dir / "rig.toml").string() + "' --out '" + session + "2'", dir, true);
  CHECK(no_duration.status == 2);
  CHECK_THAT(no_duration.err, Contains("a comedi rig records for a set time: give --duration-s"));
}

TEST_CASE("rig keys for comedi: aref and daq.start_trigger", "[comedi][rig]") {
  RigSpec spec;
  spec.device = "/dev/comedi0";
  spec.aref = "gnd";
  REQUIRE_THROWS_WITH(make_rig(spec),
                      Contains("channels[0].aref: \"gnd\" is not an aref; valid: ground, common, "
                               "diff, other"));
  spec.aref = "";
  CHECK(make_rig(spec).channels[1].aref == "ground");  // the default
  std::string text = rig_text(spec);
  text.replace(text.find("resolution_bits = 16\n"), 21,
               "resolution_bits = 16\nstart_trigger = \"door\"\n");
  REQUIRE_THROWS_WITH(doorbench::parse_rig(text, "r.toml", "."),
                      "r.toml:12: daq.start_trigger: \"door\" is not the name of a [[triggers]] "
                      "table (there are none)");
  spec.start_trigger = "external";
  CHECK(make_rig(spec).daq_start_trigger == "go");
  // Simulated channels have no aref.
  std::string simulated = std::string(doorbench::simulated_dishwasher_rig_text());
  simulated.replace(simulated.find("calibration = \"nominal\""), 23,
                    "aref = \"diff\"\ncalibration = \"nominal\"");
  REQUIRE_THROWS_WITH(doorbench::parse_rig(simulated, "sim.toml", "."),
                      Contains("channels[0].aref: only comedi channels have an aref"));
}

TEST_CASE("comedi: a duration beyond the board's stop count acquires with TRIG_NONE", "[comedi]") {
  TempDir dir("comedi");
  const auto device = dir.write("comedi0", "min_convert_ns = 1000\n");
  RigSpec spec;
  spec.device = device.string();
  spec.channels = 1;
  spec.rate_hz = 50000;
  ComediOptions options;
  options.duration_s = 400;  // 20 million scans; the board counts at most 2^24 − 1
  ComediBackend backend(make_rig(spec), comedi_emulator(), options);
  CHECK(backend.setup().stop_scans == 0);
  REQUIRE(backend.setup().warnings.size() == 1);
  CHECK(backend.setup().warnings[0] ==
        "the board's stop count holds at most 16777215 scans, fewer than the 20000000 asked "
        "for: acquiring with stop TRIG_NONE instead");
  CHECK_THAT(joined(backend.setup().tests), Contains("round 3, test 1: comedi_command_test "
                                                     "returned 0 (valid)"));
  options.duration_s = 300;  // 15 million: fits
  ComediBackend fits(make_rig(spec), comedi_emulator(), options);
  CHECK(fits.setup().stop_scans == 15000000);
}
