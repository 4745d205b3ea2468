// `doorbench record` on rigs with Modbus sensors, against a real pymodbus server process
// on loopback (tests/modbus): a Modbus-only rig started by a level trigger, and the timing
// of a Modbus channel against an (emulated) comedi card recording the same signal.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "acquisition/session/session_file.h"
#include "core/units.h"
#include "fixtures/modbus_test_server.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/sine_phase.h"

using Catch::Matchers::Contains;
using namespace doorbench;
using doorbench::testing::sine_phase;
using doorbench::testing::TempDir;

namespace {

using Run = doorbench::testing::DoorbenchRun;

// With the comedi emulator in place of libcomedi; `keys`: a shell command whose output is
// doorbench's stdin (the Enter key).
Run run_doorbench(const std::string& args, const TempDir& dir,
                  const std::string& keys = "cat /dev/null") {
  return doorbench::testing::run_doorbench_shell(
      args, dir, doorbench::testing::comedi_emulator_environment(), keys);
}

// The server's transmitter channels: force (float32 ABCD at 0) and angle (int16 0.01° at 8).
std::string modbus_part(int port, double poll_rate_hz) {
  std::ostringstream text;
  text << "\n[[modbus.devices]]\nname = \"tx\"\ntransport = \"tcp\"\nhost = \"127.0.0.1\"\nport = "
       << port
       << "\n\n[[channels]]\nname = \"mb_force\"\nsensor = \"load_cell\"\nserial = \"MB-LC\"\n"
          "backend = \"modbus\"\nunit = \"N\"\n[channels.modbus]\ndevice = \"tx\"\nunit_id = 1\n"
          "register = \"input\"\naddress = 0\ntype = \"float32\"\nbyte_order = \"big\"\n"
          "word_order = \"big\"\nrange = [-700.0, 700.0]\npoll_rate_hz = "
       << poll_rate_hz
       << "\n\n[[channels]]\nname = \"mb_angle\"\nsensor = \"inclinometer\"\nserial = \"MB-INC\"\n"
          "backend = \"modbus\"\nunit = \"rad\"\n[channels.modbus]\ndevice = \"tx\"\nunit_id = 1\n"
          "register = \"input\"\naddress = 8\ntype = \"int16\"\nbyte_order = \"big\"\n"
          "scale = 1.7453292519943296e-4\nrange = [-0.2, 0.2]\npoll_rate_hz = "
       << poll_rate_hz << "\n";
  return text.str();
}

std::int64_t origin_ns(const SessionReader& session) {
  return std::stoll(session.read_group_attribute("clock", "origin_monotonic_ns"));
}

double absolute_s(std::int64_t origin, double session_time_s) {
  return static_cast<double>(origin) * 1e-9 + session_time_s;
}

}  // namespace

TEST_CASE(
    "record: a Modbus-only rig started by a level trigger on the load-cell transmitter, "
    "against a pymodbus server",
    "[cli][modbus][trigger]") {
  TempDir dir("record_modbus");
  const doorbench::testing::TcpTransmitterServer server;
  // force = 50 + 40 sin(π t): it rises through 80 N once every 2 s.
  const std::string rig =
      "[bench]\nname = \"modbus-trigger\"\n\n[daq]\nbackend = \"none\"\n" +
      modbus_part(server.port, 100) +
      "\n[[triggers]]\nname = \"push\"\nkind = \"level\"\nchannel = \"mb_force\"\nlevel = 80.0\n"
      "hysteresis = 5.0\nunit = \"N\"\n\n[recording]\nstart = \"push\"\nduration_s = 0.5\n"
      "pre_trigger_s = 0.2\n";
  dir.write("rig.toml", rig);
  const std::string session_path = (dir / "s.h5").string();
  const Run run = run_doorbench("record --rig '" + (dir / "rig.toml").string() +
                                    "' --max-wait-s 5 --out '" + session_path + "'",
                                dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Contains("mb_force"));  // the live values
  CHECK_THAT(run.err, Contains("trigger: trigger stopped: triggered at"));

  const SessionReader session(session_path);
  double trigger_s = -1;
  for (const SessionEvent& e : session.events()) {
    if (e.kind == "trigger") trigger_s = e.time_s;
  }
  const std::int64_t origin = origin_ns(session);
  const ChannelSlice force = session.read("mb_force");
  REQUIRE(force.raw.size() > 40);  // about 70 polls at 100 Hz
  // 0.2 s of pre-trigger, or all there was when the force crossed sooner after the start.
  CHECK(trigger_s <= 0.22);
  if (trigger_s < 0.18) CHECK(force.time_s.front() < 0.02);
  CHECK(session.sample_count("mb_force_latency") == force.raw.size());
  for (std::size_t i = 0; i < force.raw.size(); ++i) {
    // The server's formula at each sample's time on the session clock (the midpoint):
    // within the force's change over a few ms of latency.
    CHECK(force.raw[i] ==
          Approx(doorbench::testing::server_force_N(absolute_s(origin, force.time_s[i])))
              .margin(1.0));
    CHECK(force.time_s[i] > -0.02);
    CHECK(force.time_s[i] < 0.72);
    if (force.time_s[i] < trigger_s - 0.015) CHECK(force.raw[i] < 80.0);
  }
  const ChannelSlice angle = session.read("mb_angle");
  const std::vector<double> angle_rad = session.physical("mb_angle", angle);
  REQUIRE(!angle_rad.empty());
  CHECK(angle_rad[0] * doorbench::kDegPerRad ==
        Approx(doorbench::testing::server_angle_deg(absolute_s(origin, angle.time_s[0])))
            .margin(0.05));
}

TEST_CASE("record: a manual trigger started and stopped with the Enter key",
          "[cli][modbus][trigger]") {
  TempDir dir("record_manual");
  const doorbench::testing::TcpTransmitterServer server;
  const std::string rig = "[bench]\nname = \"modbus-manual\"\n\n[daq]\nbackend = \"none\"\n" +
                          modbus_part(server.port, 100) +
                          "\n[[triggers]]\nname = \"enter\"\nkind = \"manual\"\n\n[recording]\n"
                          "start = \"enter\"\nstop = \"enter\"\npre_trigger_s = 0.1\n";
  dir.write("rig.toml", rig);
  const std::string session_path = (dir / "s.h5").string();
  const Run run = run_doorbench("record --rig '" + (dir / "rig.toml").string() +
                                    "' --max-wait-s 20 --out '" + session_path + "'",
                                dir, "sleep 1; echo; sleep 0.6; echo");
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Contains("armed: press Enter to start recording, Enter again to stop"));
  const SessionReader session(session_path);
  std::size_t triggers = 0, stops = 0;
  for (const SessionEvent& e : session.events()) {
    if (e.kind == "trigger") {
      ++triggers;
      CHECK_THAT(e.detail, Contains("manual"));
      CHECK(e.time_s == Approx(0.1).margin(0.02));
    }
    stops += e.kind == "stop";
  }
  CHECK(triggers == 1);
  CHECK(stops == 1);
  const ChannelSlice force = session.read("mb_force");
  REQUIRE(force.raw.size() > 20);
  // 0.1 s before the first Enter, about 0.6 s to the second.
  CHECK(force.time_s.back() > 0.4);
  CHECK(force.time_s.back() < 1.5);
}

TEST_CASE(
    "record: a Modbus channel and a comedi channel of the same signal land within one DAQ "
    "sample period of each other",
    "[cli][modbus][comedi][timing]") {
  TempDir dir("record_mixed");
  const doorbench::testing::TcpTransmitterServer server;
  // The emulated card's channel 0: 40 sin(π t) + 5 V... scaled to volts: 4 sin(π t) + 5 V of
  // absolute CLOCK_MONOTONIC time, the same phase as the server's force.
  const auto device =
      dir.write("comedi0", "transfer_bytes = 256\nsignal.0 = monotonic_sine 4.0 0.5 5.0\n");
  const std::string rig =
      "[bench]\nname = \"mixed\"\n\n[clock]\nsample_rate_hz = 1000\n\n[daq]\nbackend = "
      "\"comedi\"\ndevice = \"" +
      device.string() +
      "\"\nresolution_bits = 16\n\n[[channels]]\nname = \"daq_volts\"\nsensor = \"load_cell\"\n"
      "serial = \"LC-DAQ\"\nbackend = \"comedi\"\naddress = \"0/0\"\nrange_V = [-10.0, 10.0]\n"
      "calibration = \"nominal\"\nunit = \"N\"\n" +
      modbus_part(server.port, 200);
  dir.write("rig.toml", rig);
  const std::string session_path = (dir / "s.h5").string();
  const Run run = run_doorbench("record --rig '" + (dir / "rig.toml").string() +
                                    "' --duration-s 2.0 --out '" + session_path + "'",
                                dir);
  INFO(run.err);
  REQUIRE(run.status == 0);

  const SessionReader session(session_path);
  const std::int64_t origin = origin_ns(session);
  const double omega = std::numbers::pi;  // 0.5 Hz
  // Each channel's phase against the one its signal has at its recorded times; their
  // difference is how far apart the two sources place the same instant.
  const ChannelInfo& daq = session.channel("daq_volts");
  const ChannelSlice volts = session.read("daq_volts");
  std::vector<double> t, y;
  for (std::size_t i = 0; i < volts.raw.size(); ++i) {
    t.push_back(absolute_s(origin, volts.time_s[i]));
    y.push_back(daq.raw_offset + daq.raw_scale * volts.raw[i]);
  }
  // Relative to a reference instant so that the sines stay well conditioned.
  const double t0 = t.front();
  for (double& value : t) value -= t0;
  const double expected_phase = std::fmod(omega * t0, 2 * std::numbers::pi);
  const double daq_lag_s =
      std::remainder(expected_phase - sine_phase(t, y, omega), 2 * std::numbers::pi) / omega;
  const ChannelSlice force = session.read("mb_force");
  REQUIRE(force.raw.size() > 200);
  t.clear();
  y.clear();
  for (std::size_t i = 0; i < force.raw.size(); ++i) {
    t.push_back(absolute_s(origin, force.time_s[i]) - t0);
    y.push_back(force.raw[i]);
  }
  const double modbus_lag_s =
      std::remainder(expected_phase - sine_phase(t, y, omega), 2 * std::numbers::pi) / omega;
  const double offset_s = modbus_lag_s - daq_lag_s;
  WARN("timing: Modbus vs comedi channel offset " << offset_s * 1e6 << " us (DAQ lag "
                                                  << daq_lag_s * 1e6 << " us, Modbus lag "
                                                  << modbus_lag_s * 1e6 << " us)");
  CHECK(std::abs(offset_s) < 1e-3);  // one sample period at 1 kHz
}
