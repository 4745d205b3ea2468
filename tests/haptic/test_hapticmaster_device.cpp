// HapticMasterDevice against the protocol emulator as a real process on loopback
// (tests/hapticmaster_emulator/hapticmaster_emulator.py on /usr/bin/python3): the command
// sequence at start and stop, error replies, samples following the commanded force, live
// inertia, a lost, stalled or corrupt link, and the tick's calls never allocating.
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.h"
#include "fixtures/temp_dir.h"
#include "haptic/hapticmaster_device.h"
#include "haptic/hapticmaster_protocol.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/hapticmaster_emulator_process.h"

using namespace doorbench::haptic;
using doorbench::testing::TempDir;

namespace {

using Emulator = doorbench::testing::HapticMasterEmulator;

// Options for tests that command by hand, not every tick: the I/O thread's watchdog on the
// tick (which has its own test) is off.
HapticMasterOptions by_hand() {
  HapticMasterOptions options;
  options.command_watchdog_s = 0.0;
  return options;
}

// What start() sends before the loop's first round trip.
const std::vector<std::string> kStartSequence = {"get state",
                                                 "get emergencybuttonpushed",
                                                 "get emergencyrelay",
                                                 "get position_calibrated",
                                                 "remove all",
                                                 "get workspace_r",
                                                 "get workspace_phi",
                                                 "get workspace_z",
                                                 "set inertia 5",
                                                 "get inertia",
                                                 "create biasforce doorbench_bias",
                                                 "set doorbench_bias force [0,0,0]",
                                                 "set doorbench_bias enable",
                                                 "set state force",
                                                 "get measpos",
                                                 "get modelvel",
                                                 "get measforce"};
const std::size_t kStartCommands = kStartSequence.size();

std::vector<std::string> lines_of(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Polls read() (as a tick would, every 1 ms) until `done` or `timeout_s`.
template <class Done>
DeviceSample poll_until(HapticMasterDevice& device, Done done, double timeout_s = 5.0) {
  const double end = doorbench::monotonic_now_s() + timeout_s;
  DeviceSample s = device.read();
  while (!done(s) && doorbench::monotonic_now_s() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    s = device.read();
  }
  return s;
}

// A loopback port with nobody listening (bound, then closed).
int closed_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t length = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &length);
  ::close(fd);
  return ntohs(a.sin_port);
}

// One command on its own connection, as another client would send it; the reply's text.
std::string send_raw(int port, const std::string& command) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
  const std::string bytes = hm::frame(command);
  REQUIRE(::write(fd, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size()));
  hm::ReplySplitter splitter;
  std::optional<std::string> reply;
  char buffer[1024];
  while (!(reply = splitter.next())) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n <= 0) break;
    splitter.feed(std::string_view(buffer, static_cast<std::size_t>(n)));
  }
  ::close(fd);
  return reply.value_or("<no reply>");
}

}  // namespace

TEST_CASE("hapticmaster device: name, address and option checks", "[hapticmaster]") {
  HapticMasterDevice device("10.0.0.5");
  CHECK(device.name() == "hapticmaster://10.0.0.5:7654");
  CHECK(HapticMasterDevice("localhost:99").name() == "hapticmaster://localhost:99");
  CHECK_THROWS_WITH(HapticMasterDevice("h:0"),
                    "hapticmaster://h:0: HapticMaster address 'h:0': port '0' is not 1..65535");
  HapticMasterOptions options;
  options.reply_timeout_s = 0;
  CHECK_THROWS_WITH(HapticMasterDevice("h", options),
                    "hapticmaster://h:7654: option reply_timeout_s must be > 0");
  options = {};
  options.bias_object = "a b";
  CHECK_THROWS_WITH(HapticMasterDevice("h", options), Catch::Contains("option bias_object"));
  const DeviceLimits limits = device.limits();
  CHECK(limits.kinematics == Kinematics::kCartesian3);
  CHECK(limits.max_force == 250.0);
  CHECK(limits.min_inertia > 0);
  // The workspace box's corners lie inside the cylindrical sector it is derived from
  // (radius 0.28..0.64 m about an axis 0.45 m behind the origin, +-0.5 rad, z +-0.2 m).
  for (const double x : {limits.workspace_min.x(), limits.workspace_max.x()}) {
    for (const double y : {limits.workspace_min.y(), limits.workspace_max.y()}) {
      const double r = std::hypot(x + 0.45, y);
      CHECK(r >= 0.28);
      CHECK(r <= 0.64);
      CHECK(std::abs(std::atan2(y, x + 0.45)) <= 0.5);
    }
  }
  CHECK(limits.workspace_min.z() >= -0.2);
  CHECK(limits.workspace_max.z() <= 0.2);
  device.stop();  // never started: harmless
  device.stop();
}

TEST_CASE("hapticmaster device: connecting to nothing names the address", "[hapticmaster]") {
  const std::string address = "127.0.0.1:" + std::to_string(closed_port());
  HapticMasterDevice device(address);
  CHECK_THROWS_WITH(device.start(5.0),
                    Catch::StartsWith("hapticmaster://" + address + ": cannot connect: "));
  CHECK_THROWS_WITH(HapticMasterDevice("no-such-host.invalid").start(5.0),
                    Catch::StartsWith("hapticmaster://no-such-host.invalid:7654: cannot resolve"));
  CHECK_THROWS_WITH(device.start(0.5), Catch::Contains("inertia 0.5 kg is outside 2..100 kg"));
}

TEST_CASE("hapticmaster device: the exact command sequence at start, in the loop and at stop",
          "[hapticmaster]") {
  TempDir dir("hm_sequence");
  const auto log = dir / "commands.log";
  Emulator emulator({"--log", log.string()});
  {
    HapticMasterDevice device(emulator.address(), by_hand());
    device.start(5.0);
    const DeviceSample s =
        poll_until(device, [](const DeviceSample& s) { return s.sequence >= 5; });
    CHECK(s.sequence >= 5);
    CHECK(s.link_ok);
    device.stop();
    CHECK(device.last_error() == "");
    CHECK_FALSE(device.read().sequence < s.sequence);
  }
  const std::vector<std::string> lines = lines_of(log);
  REQUIRE(lines.size() >= kStartCommands + 4 * 4 + 3);
  CHECK(std::vector<std::string>(lines.begin(), lines.begin() + kStartCommands) == kStartSequence);
  // Every round trip: the force, then the three readings.
  const std::size_t loop_end = lines.size() - 3;
  CHECK((loop_end - kStartCommands) % 4 == 0);
  for (std::size_t i = kStartCommands; i < loop_end; i += 4) {
    INFO(i);
    CHECK(lines[i] == "set doorbench_bias force [0,0,0]");
    CHECK(lines[i + 1] == "get measpos");
    CHECK(lines[i + 2] == "get modelvel");
    CHECK(lines[i + 3] == "get measforce");
  }
  const std::vector<std::string> stop = {"set doorbench_bias force [0,0,0]", "set state stop",
                                         "remove doorbench_bias"};
  CHECK(std::vector<std::string>(lines.end() - 3, lines.end()) == stop);
}

TEST_CASE("hapticmaster device: start-up passes when the device replies with fewer digits",
          "[hapticmaster]") {
  // "set inertia 10.91954" read back as "10.9195" (%g), "10.919540" (%.6f) or in full is the
  // inertia that was set; every other number replied (workspace, readings) in that format too.
  for (const char* format : {"%g", "%.6f", ""}) {
    INFO("replies formatted as '" << format << "'");
    std::vector<std::string> options;
    if (*format != '\0') options = {"--number-format", format};
    Emulator emulator(options);
    HapticMasterDevice device(emulator.address(), by_hand());
    REQUIRE_NOTHROW(device.start(10.91954));
    CHECK(device.startup_report().workspace_source == "device");
    CHECK(device.startup_report().inertia_read_back_kg == Approx(10.91954).epsilon(1e-5));
    const DeviceSample s =
        poll_until(device, [](const DeviceSample& s) { return s.sequence >= 3; });
    CHECK(s.link_ok);
    device.stop();
    CHECK(device.last_error() == "");
  }
  // An inertia that differs in the digits the reply carries is still refused.
  Emulator wrong({"--answer", "get inertia=10.9194"});
  HapticMasterDevice device(wrong.address(), by_hand());
  CHECK_THROWS_WITH(device.start(10.91954),
                    wrong.name() +
                        ": 'set inertia 10.91954' was accepted but the device "
                        "reports 10.9194 kg");
}

TEST_CASE("hapticmaster device: an error reply at start is a DeviceError with its text",
          "[hapticmaster]") {
  Emulator emulator({"--fail", "set inertia 5=Inertia cannot be set in state 'home'"});
  HapticMasterDevice device(emulator.address());
  CHECK_THROWS_AS(device.start(5.0), DeviceError);
  CHECK_THROWS_WITH(device.start(5.0), emulator.name() +
                                           ": 'set inertia 5' failed: Inertia cannot be set in "
                                           "state 'home'");
  // The emulator's own validation: a second device creating the same bias object fails.
  Emulator plain;
  HapticMasterDevice first(plain.address());
  first.start(3.0);
  first.stop();
  HapticMasterDevice again(plain.address());
  CHECK_NOTHROW(again.start(3.0));
  again.stop();
  // A session that ended without stop() left its bias object; the next start removes it.
  CHECK(send_raw(plain.port, "create biasforce doorbench_bias") ==
        "\"Effect biasforce with name doorbench_bias created\"");
  HapticMasterDevice after_crash(plain.address());
  CHECK_NOTHROW(after_crash.start(3.0));
  after_crash.stop();
}

TEST_CASE("hapticmaster device: samples flow and the position follows the commanded force",
          "[hapticmaster]") {
  Emulator emulator({"--ext-force", "[0,0,1.5]"});
  HapticMasterDevice device(emulator.address(), by_hand());
  device.start(4.0);
  DeviceSample s = poll_until(device, [](const DeviceSample& s) { return s.sequence >= 3; });
  REQUIRE(s.sequence >= 3);
  CHECK(s.measured_force.isApprox(Vec3(0, 0, 1.5)));

  // +x force on 4 kg: x grows, velocity +x; the user's +z force moves z too.
  device.command_force(Vec3(8.0, 0, 0));
  const double t0 = doorbench::monotonic_now_s();
  const std::uint64_t seq0 = s.sequence;
  s = poll_until(device, [](const DeviceSample& s) { return s.position.x() > 0.02; });
  const double elapsed = doorbench::monotonic_now_s() - t0;
  CHECK(s.position.x() > 0.02);
  CHECK(s.velocity.x() > 0.0);
  CHECK(s.position.z() > 0.0);
  CHECK(std::abs(s.position.y()) < 1e-9);
  CHECK(s.sequence > seq0);
  CHECK(s.link_ok);
  // x = a t^2 / 2 with a = 2 m/s^2 reaches 0.02 m after 0.14 s (plus the link's latency).
  CHECK(elapsed > 0.1);
  CHECK(elapsed < 1.5);
  const double rate_hz = static_cast<double>(s.sequence - seq0) / elapsed;
  INFO("round trips per second: " << rate_hz);
  CHECK(rate_hz > 50.0);

  // Reversed force: x velocity turns negative.
  device.command_force(Vec3(-20.0, 0, 0));
  s = poll_until(device, [](const DeviceSample& s) { return s.velocity.x() < -0.05; });
  CHECK(s.velocity.x() < -0.05);
  // Sequence only grows; time stamps are monotonic.
  DeviceSample a = device.read();
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  DeviceSample b = device.read();
  CHECK(b.sequence > a.sequence);
  CHECK(b.time_s > a.time_s);
  device.stop();
  CHECK(device.last_error() == "");
}

TEST_CASE("hapticmaster device: command_inertia reaches the device", "[hapticmaster]") {
  TempDir dir("hm_inertia");
  const auto log = dir / "commands.log";
  Emulator emulator({"--log", log.string()});
  HapticMasterDevice device(emulator.address(), by_hand());
  device.start(5.0);
  poll_until(device, [](const DeviceSample& s) { return s.sequence >= 2; });
  device.command_inertia(12.5);
  device.command_inertia(12.5);  // unchanged: sent once
  const std::uint64_t seq = device.read().sequence;
  poll_until(device, [&](const DeviceSample& s) { return s.sequence >= seq + 5; });
  device.command_inertia(1000.0);  // clamped to the limit
  const std::uint64_t seq2 = device.read().sequence;
  poll_until(device, [&](const DeviceSample& s) { return s.sequence >= seq2 + 5; });
  device.stop();
  const std::vector<std::string> lines = lines_of(log);
  int sent_12_5 = 0;
  int sent_100 = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i] == "set inertia 12.5") {
      ++sent_12_5;
      // In the same round trip as the force and the readings.
      REQUIRE(i >= 1);
      CHECK(lines[i - 1] == "set doorbench_bias force [0,0,0]");
      CHECK(lines[i + 1] == "get measpos");
    }
    if (lines[i] == "set inertia 100") ++sent_100;
  }
  CHECK(sent_12_5 == 1);
  CHECK(sent_100 == 1);
}

TEST_CASE("hapticmaster device: a dropped connection clears link_ok at once", "[hapticmaster]") {
  // 17 start commands + 4 per round trip: dropped in the 25th round trip.
  Emulator emulator({"--drop-after", std::to_string(kStartCommands + 4 * 24)});
  HapticMasterOptions options = by_hand();
  options.reply_timeout_s = 0.5;
  HapticMasterDevice device(emulator.address(), options);
  device.start(5.0);
  std::uint64_t last_seq = 0;
  double last_change_s = doorbench::monotonic_now_s();
  DeviceSample s = device.read();
  const double end = doorbench::monotonic_now_s() + 5.0;
  while (s.link_ok && doorbench::monotonic_now_s() < end) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    s = device.read();
    if (s.sequence != last_seq) {
      last_seq = s.sequence;
      last_change_s = doorbench::monotonic_now_s();
    }
  }
  const double detect_s = doorbench::monotonic_now_s() - last_change_s;
  INFO("link_ok false " << detect_s << " s after the last sample");
  REQUIRE_FALSE(s.link_ok);
  CHECK(s.sequence == 25);
  // A closed connection is seen at once, far inside the reply timeout.
  CHECK(detect_s < 0.1);
  CHECK_THAT(device.last_error(),
             Catch::StartsWith(emulator.name() + ": connection closed by the device"));
  device.stop();
  device.stop();
  CHECK_FALSE(device.read().link_ok);
}

TEST_CASE("hapticmaster device: a silent device clears link_ok after the reply timeout",
          "[hapticmaster]") {
  // Answers 10 round trips (the first reading and 9 more), then nothing.
  Emulator emulator({"--stall-after", std::to_string(kStartCommands + 4 * 9)});
  HapticMasterOptions options = by_hand();
  options.reply_timeout_s = 0.2;
  HapticMasterDevice device(emulator.address(), options);
  device.start(5.0);
  DeviceSample s = poll_until(device, [](const DeviceSample& s) { return s.sequence >= 10; });
  const double t0 = doorbench::monotonic_now_s();
  s = poll_until(device, [](const DeviceSample& s) { return !s.link_ok; });
  const double detect_s = doorbench::monotonic_now_s() - t0;
  INFO("link_ok false " << detect_s << " s after the last sample");
  REQUIRE_FALSE(s.link_ok);
  CHECK(s.sequence == 10);
  CHECK(detect_s > 0.15);
  CHECK(detect_s < 0.2 + 0.2);
  CHECK_THAT(device.last_error(), Catch::Contains("no reply within 0.2 s"));
  const double stop_t0 = doorbench::monotonic_now_s();
  device.stop();  // the device was stopped on a fresh connection already: no waiting
  CHECK(doorbench::monotonic_now_s() - stop_t0 < 0.1);
}

TEST_CASE("hapticmaster device: garbage and error replies in the loop clear link_ok",
          "[hapticmaster]") {
  {
    Emulator emulator({"--garbage-after", std::to_string(kStartCommands + 4)});
    HapticMasterDevice device(emulator.address(), by_hand());
    device.start(5.0);
    const DeviceSample s = poll_until(device, [](const DeviceSample& s) { return !s.link_ok; });
    CHECK_FALSE(s.link_ok);
    CHECK_THAT(device.last_error(), Catch::Contains("not the HapticMaster protocol"));
    device.stop();
  }
  {
    Emulator emulator({"--fail", "set doorbench_bias force [1,0,0]=Force too large"});
    HapticMasterDevice device(emulator.address(), by_hand());
    device.start(5.0);
    device.command_force(Vec3(1, 0, 0));
    const DeviceSample s = poll_until(device, [](const DeviceSample& s) { return !s.link_ok; });
    CHECK_FALSE(s.link_ok);
    CHECK(s.sequence >= 1);
    CHECK(device.last_error() ==
          emulator.name() +
              ": 'set doorbench_bias force [1,0,0]' failed: Force too large; the device was "
              "stopped (zero force, state stop)");
    device.stop();
  }
  {
    // An error reply to the first reading fails start(), which leaves the device stopped.
    TempDir dir("hm_first_reading");
    const auto log = dir / "commands.log";
    Emulator emulator({"--fail", "get modelvel=Not in state force", "--log", log.string()});
    HapticMasterDevice device(emulator.address(), by_hand());
    CHECK_THROWS_WITH(device.start(5.0),
                      emulator.name() + ": 'get modelvel' failed: Not in state force");
    const std::vector<std::string> lines = lines_of(log);
    REQUIRE(lines.size() >= 3);
    CHECK(std::vector<std::string>(lines.end() - 3, lines.end()) ==
          std::vector<std::string>{"set doorbench_bias force [0,0,0]", "set state stop",
                                   "remove doorbench_bias"});
  }
}

TEST_CASE("hapticmaster device: the tick's calls never allocate", "[hapticmaster][allocation]") {
  // No I/O thread may run while counting (the counter is process-wide): the calls are
  // measured on a device before start and after a full start/stop with the emulator.
  Emulator emulator;
  HapticMasterDevice device(emulator.address(), by_hand());
  const auto exercise = [&] {
    const long long before = doorbench::testing::allocations();
    double sum = 0;
    for (int i = 0; i < 20000; ++i) {
      device.command_force(Vec3(i * 1e-3, 0, -1));
      if (i % 100 == 0) device.command_inertia(5.0 + i * 1e-4);
      if (i % 1000 == 0) device.brake();  // a trip's call from the tick
      const DeviceSample s = device.read();
      sum += s.position.x() + static_cast<double>(s.sequence);
    }
    CHECK(sum >= 0);
    return doorbench::testing::allocations() - before;
  };
  CHECK(exercise() == 0);
  device.start(5.0);
  poll_until(device, [](const DeviceSample& s) { return s.sequence >= 3; });
  device.stop();
  CHECK(exercise() == 0);
}

TEST_CASE("hapticmaster device: commands as separate messages, forces clamped to the limit",
          "[hapticmaster]") {
  TempDir dir("hm_separate");
  const auto log = dir / "commands.log";
  Emulator emulator({"--log", log.string()});
  HapticMasterOptions options = by_hand();
  options.join_commands = false;
  HapticMasterDevice device(emulator.address(), options);
  device.start(5.0);
  DeviceSample s = poll_until(device, [](const DeviceSample& s) { return s.sequence >= 2; });
  device.command_force(Vec3(300.0, 400.0, 0.0));  // |F| = 500 N -> 250 N, same direction
  s = poll_until(device, [&](const DeviceSample& x) { return x.sequence >= s.sequence + 3; });
  device.command_force(Vec3(std::nan(""), 1.0, 0.0));  // not finite -> zero
  s = poll_until(device, [&](const DeviceSample& x) { return x.sequence >= s.sequence + 3; });
  CHECK(s.link_ok);
  CHECK(s.position.x() > 0.0);
  device.stop();
  const std::vector<std::string> lines = lines_of(log);
  const auto count = [&](const std::string& line) {
    return std::count(lines.begin(), lines.end(), line);
  };
  CHECK(count("set doorbench_bias force [150,200,0]") >= 1);
  CHECK(count("set doorbench_bias force [300,400,0]") == 0);
  CHECK(count("get measpos") >= 8);
  CHECK(lines.back() == "remove doorbench_bias");
}

TEST_CASE("hapticmaster device: wrong answers to 'get state' or to a round trip",
          "[hapticmaster]") {
  {
    Emulator emulator({"--answer", "get state=[1,2,3]"});
    HapticMasterDevice device(emulator.address());
    CHECK_THROWS_WITH(device.start(5.0),
                      emulator.name() +
                          ": 'get state' answered '[1,2,3]', not a state name: is this a "
                          "HapticMaster?");
  }
  {
    // Unquoted state names are taken too (the HapticAPI examples show "stop;").
    Emulator emulator({"--answer", "get state=off"});
    HapticMasterDevice device(emulator.address(), by_hand());
    CHECK_NOTHROW(device.start(5.0));
    device.stop();
  }
  {
    // One reply too many in the loop's reply message: the link is declared lost.
    Emulator emulator({"--answer", "set doorbench_bias force [2,0,0]=ok;[4,5,6]"});
    HapticMasterDevice device(emulator.address(), by_hand());
    device.start(5.0);
    device.command_force(Vec3(2, 0, 0));
    const DeviceSample s = poll_until(device, [](const DeviceSample& s) { return !s.link_ok; });
    CHECK_FALSE(s.link_ok);
    CHECK(device.last_error() ==
          emulator.name() +
              ": 4 command(s) 'set doorbench_bias force [2,0,0];get measpos;get modelvel;get "
              "measforce' answered with 5 replies; the device was stopped (zero force, state "
              "stop)");
    device.stop();
  }
  {
    // A reading that is not a vector fails start().
    Emulator emulator({"--answer", "get measpos=\"none\""});
    HapticMasterDevice device(emulator.address());
    CHECK_THROWS_WITH(device.start(5.0),
                      emulator.name() + ": 'get measpos' answered '\"none\"', not [x,y,z]");
  }
}
